"""Hyper-parameter axes ([hyper.<env>] keys given as lists): one figure per environment with
axes, each method's FPE (at the largest N) and TPA (its best mode, the largest N and M) at every
point of the axes, mean ± 95 % CI over seeds, and the report's lines for them.

A cell the point does not change (a Random φ under a "sirl.epochs" axis) is the base point's
cell, stored once with hyper_point "": it is drawn at every point."""
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from run_tables import PAPER, methods, of_protocol, references

CELL = ["variant", "N", "M", "frozen", "seed", "teacher", "protocol"]


def at_point(d, point, base):
    """The rows of table d (one environment) at `point`: its own, and the base point's for cells
    it shares."""
    if point == base:
        return d[d.hyper_point == ""]
    own = d[d.hyper_point == point]
    cols = [c for c in CELL if c in d.columns]
    shared = d[d.hyper_point == ""]
    keys = set(map(tuple, own[cols].astype(str).values))
    return pd.concat([own, shared[[tuple(r) not in keys for r in shared[cols].astype(str).values]]])


def metric_rows(fpe, tpa, env):
    """(label, table, value column) of the two metrics drawn for an environment."""
    out = []
    # Methods only (the references, truth φ* and raw input, are no point of an axis), and the
    # paper's TPA protocol (the linear protocol's cells are not the figures' best mode).
    fpe, tpa = methods(fpe), methods(of_protocol(tpa, PAPER))
    f = fpe[fpe.env == env] if not fpe.empty else fpe
    if not f.empty:
        nmax = f.N.max()
        out.append((f"FPE at N = {int(nmax)} (N-free methods: theirs); lower is better",
                    f[(f.N == nmax) | f.N.isna()], "fpe"))
    t = tpa[(tpa.env == env) & tpa.in_main & tpa.best_mode] if not tpa.empty else tpa
    if not t.empty:
        nmax, mmax = t.N.max(), t.M.max()
        out.append((f"TPA at N = {int(nmax)}, M = {int(mmax)}, best mode; higher is better",
                    t[((t.N == nmax) | t.N.isna()) & (t.M == mmax)], "tpa"))
    return out


def plot_fig5_points(tpa, env, tags, style, order, mean_ci, save, out, drawn):
    """Fig. 5 at every point of an environment's axes (fig_hyper_fig5_<env>.png): TPA against M
    at the largest N, each method in its best mode and the truth reference, one panel per point
    on a shared y axis. Returns the report's lines ([] without TPA cells)."""
    p = of_protocol(tpa, PAPER)
    p = p[p.env == env] if not p.empty else p
    if p.empty:
        return []
    m = methods(p)
    m = m[m.in_main & m.best_mode]
    nmax = m.N.max() if not m.empty else None
    cells = pd.concat([m[(m.N == nmax) | m.N.isna()], references(p)])
    fig, axes = plt.subplots(1, len(tags), figsize=(min(4.2 * len(tags), 14), 3.6),
                             squeeze=False, sharey=True, constrained_layout=True)
    # The references (truth φ*) in the figures' reference style (black, dashed), never as a
    # method; chance as in Fig. 5.
    from figures import REFERENCE_STYLE, chance_line, legend_below, line_style
    for ax, tag in zip(axes[0], tags):
        d = at_point(cells, tag, tags[0])
        refs = [v for v in REFERENCE_STYLE if (d.variant == v).any()]
        for v in [v for v in order if (d.variant == v).any()] + refs:
            dv = d[d.variant == v]
            Ms = sorted(int(x) for x in dv.M.dropna().unique())
            st = [mean_ci(dv[dv.M == M].tpa) for M in Ms]
            ref = v in REFERENCE_STYLE
            if ref:
                colour, name, ls = REFERENCE_STYLE[v]
                marker = "_"
            else:
                (colour, name), (marker, ls) = style[v], line_style(v)
            ax.errorbar(Ms, [x[0] for x in st], yerr=[x[1] if np.isfinite(x[1]) else 0 for x in st],
                        color=colour, marker=marker, ms=10 if ref else 6, capsize=3, label=name,
                        ls=ls if len(Ms) >= 3 else "none", zorder=1 if ref else 2)
            drawn.setdefault("hyper_fig5", {}).setdefault(env, {}).setdefault(tag, {})[v] = {
                str(M): float(x[0]) for M, x in zip(Ms, st)}
        chance_line(ax)
        ax.set_title(tag + (" (base point)" if tag == tags[0] else ""), fontsize=9)
        ax.set_xlabel("M (reward-head queries)")
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel(f"TPA at N = {int(nmax) if nmax is not None else '—'}\n"
                          "(higher is better)", fontsize=9)
    legend_below(fig, axes[0])
    fig.suptitle(f"{env}: Fig. 5 at every point of its axes (paper protocol; mean ± 95 % CI "
                 "over seeds; black: references; grey line: chance)", fontsize=10)
    name = f"fig_hyper_fig5_{env}"
    save(fig, out, name)
    return [f"![{env}: Fig. 5 at every point]({name}.png)", ""]


def plot_hyper(fpe, tpa, points, style, order, mean_ci, save, out, notes, drawn):
    """Draws fig_hyper_<env>.png and fig_hyper_fig5_<env>.png for every environment with axes;
    returns the report's lines."""
    from figures import legend_below, line_style  # the figures' shared styles
    lines = []
    for env, tags in points.items():
        rows = metric_rows(fpe, tpa, env)
        if not rows:
            notes.append(f"hyper-parameter axes of {env}: no FPE or TPA cells to draw")
            continue
        fig, axes = plt.subplots(1, len(rows), figsize=(min(5.5 * len(rows), 14), 3.8),
                                 squeeze=False, constrained_layout=True)
        xs = np.arange(len(tags))
        for ax, (label, d, col) in zip(axes[0], rows):
            for v in order:
                if not (d.variant == v).any():
                    continue
                colour, name = style[v]
                ms, cis = [], []
                for tag in tags:
                    m, ci = mean_ci(at_point(d[d.variant == v], tag, tags[0])[col])
                    ms.append(m)
                    cis.append(ci if np.isfinite(ci) else 0)
                    drawn.setdefault("hyper", {}).setdefault(env, {}).setdefault(col, {}) \
                        .setdefault(v, {})[tag] = float(m)
                marker, ls = line_style(v)
                ax.errorbar(xs, ms, yerr=cis, color=colour, marker=marker, ls=ls, capsize=3,
                            label=name)
            ax.set_xticks(xs)
            ax.set_xticklabels(tags, rotation=20, ha="right", fontsize=8)
            ax.set_title(label, fontsize=10)
            ax.grid(alpha=0.3)
        legend_below(fig, axes[0])  # below the panels: it hides no point
        fig.suptitle(f"{env}: every point of its hyper-parameter axes (mean ± 95 % CI over "
                     "seeds; the first point is the figures' and claims')", fontsize=10)
        name = f"fig_hyper_{env}"
        save(fig, out, name)
        lines += [f"![{env}: hyper-parameter axes]({name}.png)", ""]
        lines += plot_fig5_points(tpa, env, tags, style, order, mean_ci, save, out, drawn)
    if lines:
        lines = ["", "## Hyper-parameter axes", "",
                 "The profile lists values for some hyper-parameters; every figure and claim above "
                 "uses each axis's first value, these show every point. A method the axis does "
                 "not change keeps one value.", ""] + lines
    return lines
