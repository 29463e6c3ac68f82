"""The paper's figures (Fig. 3, 4, 5, 7 and the learning curves) from a results file's tables:
one colour and label per method, what each figure drew recorded in DRAWN (figures.json)."""
import math
import os

import matplotlib

matplotlib.use("Agg")
# Labels come from the results file (a method's label, an environment's title): drawn as text,
# never parsed as TeX ("$" in a label is a dollar sign, not a formula that can fail to parse).
matplotlib.rcParams["text.parse_math"] = False
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

from run_tables import (ENV, PAPER, PROTOCOL_TEXT, env_title, main_tpa, methods,  # noqa: E402
                        of_protocol, reference_tpa, references)
import sirl_bench  # noqa: E402  (on the path once run_tables is imported)
from safe_output import save_figure  # noqa: E402

# One colour and one label per variant, shared by every figure, as the engine declares each
# method (engine/method_catalog.cpp) and the results file stores it (/methods/<variant>):
# filled by load_styles before anything is drawn, so no method is named here but in the
# figures' own palette just below (what the figures set apart that the file's colours do not).
# STYLE {variant: (colour, label)} and ORDER (the method lines of Figs. 4, 5 and the curves, in
# the engine's order, external methods last); LINE {variant: (marker, line style)}, so that
# methods whose curves coincide (the preference baselines' losses) stay distinguishable;
# REFERENCE_STYLE {variant: (colour, label, dashes)} for the references (ceiling and floor),
# drawn as black reference lines, never as methods; METHODS the file's /methods table itself
# (res.methods: role, queries, best_frozen, accepts_vae, …).
STYLE = {}
ORDER = []
LINE = {}
REFERENCE_STYLE = {}
METHODS = None

# The figures' palette over the file's declared colours, by method name (the file's `method`
# column): Random in orange, apart from the references' black and every built-in method; the
# external methods (the user's own) in colours no built-in method or reference uses, in the
# order the file lists them (figure_order); the references black, told apart by their dashes,
# their legend label saying what each is (truth: the best a φ can do; raw: what a learned φ must
# beat), whichever metric is plotted (lower is better for FPE, higher for TPA).
METHOD_COLOUR = {"random": "#ff7f0e"}
EXTERNAL_COLOURS = ("#e377c2", "#bcbd22", "#8c564b", "#7b4173", "#393b79", "#637939",
                    "#bd9e39", "#ad494a")
REFERENCE_COLOUR = "#000000"
REFERENCE_LABEL = {"truth": "truth φ* (reference: best possible)",
                   "raw": "raw input (reference: floor to beat)"}
# Marker and line style by method name ("+vae" variants: the method's marker, dashed).
METHOD_LINE = {"sirl": ("o", "-"), "vae": ("s", "-"), "multipref10": ("^", "-"),
               "multipref50": ("v", "--"), "singlepref": ("D", ":"), "random": ("X", "-."),
               "external": ("P", "-")}
# The chance level of a preference accuracy: a thin grey line, labelled, in every TPA panel.
CHANCE_STYLE = {"color": "#8c8c8c", "lw": 0.9, "ls": "-"}
# Colours of the figures drawn without a results file's /methods (Fig. 6 from a study analysis).
STUDY_COLOURS = {"sirl": "#d62728", "random": METHOD_COLOUR["random"]}


def load_styles(res):
    """Fills STYLE, ORDER, LINE, REFERENCE_STYLE and METHODS from the file's /methods and the
    palette above; raises sirl_bench.ResultsError for a file without it (an engine before
    0.19.0)."""
    global METHODS
    m = res.methods
    if m.empty:
        raise sirl_bench.ResultsError(
            f"{res.path}: no /methods (written by an engine before 0.19.0): `sirl merge NEW.h5 "
            "THIS.h5` rewrites it with the current engine")
    METHODS = m
    STYLE.clear(), ORDER.clear(), LINE.clear(), REFERENCE_STYLE.clear()
    externals = list(m[m.role == "external"].sort_values(["figure_order", "catalog_order"]).index)
    for v, r in m.sort_values(["catalog_order", "figure_order"]).iterrows():
        name = str(r["method"]) if "method" in r and isinstance(r["method"], str) else v.split("+")[0]
        colour = r.colour
        if r.role == "external":
            colour = EXTERNAL_COLOURS[externals.index(v) % len(EXTERNAL_COLOURS)]
        elif r.role == "reference":
            colour = REFERENCE_COLOUR
        elif name in METHOD_COLOUR and not bool(r.vae):
            colour = METHOD_COLOUR[name]
        STYLE[v] = (colour, r.label)
        marker, ls = METHOD_LINE.get("external" if r.role == "external" else name, ("o", "-"))
        LINE[v] = (marker, "--" if bool(r.vae) else ls)
        if r.role == "reference":
            dashes = tuple(float(x) for x in str(r.dashes).split()) or (4.0, 2.0)
            REFERENCE_STYLE[v] = (colour, REFERENCE_LABEL.get(name, f"{r.label} (reference)"),
                                  (0, dashes))
    ORDER.extend(m[m.figure_order >= 0].sort_values("figure_order").index)


def line_style(v):
    """(marker, line style) of a method variant (LINE; a circle on a solid line if unknown)."""
    return LINE.get(v, ("o", "-"))


def methods_of(role):
    """The plain methods (no +vae, no query selection) of one role, in the figures' order."""
    m = METHODS[(METHODS.role == role) & ~METHODS.vae & (METHODS.selection == "uniform")]
    return list(m.sort_values("figure_order").index)


def reference_style(v):
    return REFERENCE_STYLE.get(v, (REFERENCE_COLOUR, f"{v} (reference)", "-."))


CHANCE_LABEL = "chance (0.5)"


def chance_line(ax, text=True, zorder=0.5):
    """The chance level of a preference accuracy (0.5): a thin grey line across the panel,
    labelled "chance" just below it at the middle of the panel (where no curve of a TPA panel
    sits below chance for long); in the legend as CHANCE_LABEL. Bar charts draw it over their
    bars (zorder 3) and without the text."""
    ax.axhline(0.5, zorder=zorder, label=CHANCE_LABEL, **CHANCE_STYLE)
    if text:
        ax.text(0.5, 0.5, "chance", transform=ax.get_yaxis_transform(), ha="center", va="top",
                fontsize=7, color=CHANCE_STYLE["color"])


def legend_below(fig, axes, rows=None, fontsize=8):
    """One legend for the whole figure, below its panels (so it hides no curve): each label once,
    the methods in ORDER's order in the first columns, then the references and chance in columns
    of their own. The saved figure grows to hold it (bbox_inches="tight")."""
    found = {}
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab and not lab.startswith("_"):
                found.setdefault(lab, h)
    if not found:
        return None
    rank = {STYLE[v][1]: i for i, v in enumerate(ORDER) if v in STYLE}
    refs = {s[1]: i for i, s in enumerate(REFERENCE_STYLE.values())}
    meths = sorted((lab for lab in found if lab not in refs and lab != CHANCE_LABEL),
                   key=lambda lab: rank.get(lab, len(rank)))
    others = sorted((lab for lab in found if lab in refs), key=refs.get)
    others += [CHANCE_LABEL] if CHANCE_LABEL in found else []
    rows = rows or (2 if len(meths) + len(others) <= 14 else 3)
    blank = matplotlib.lines.Line2D([], [], alpha=0)
    handles, labels = [], []
    for group in (meths, others):  # column-major: each group starts a column
        pad = -len(group) % rows if group is meths else 0
        handles += [found[lab] for lab in group] + [blank] * pad
        labels += group + [""] * pad
    return fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0),
                      ncol=math.ceil(len(labels) / rows), fontsize=fontsize, frameon=False,
                      handlelength=3.2, columnspacing=1.6)


def better_note(metric):
    """The direction of a metric, for a panel's axis label or a figure's subtitle."""
    return "lower is better" if metric == "fpe" else "higher is better"


def fig_name(base, protocol):
    """A figure's file and figures.json name under a TPA protocol: the paper's keeps the plain
    name (fig5_tpa, fig5), another gets its own suffix (fig5_tpa_linear, fig5_linear)."""
    return base if protocol == PAPER else f"{base}_{protocol}"


# What each figure drew, written to figures.json beside them (tests and users check it):
# fig4 {env: {method: {N: mean}}} and fig4_references {env: {truth|raw: {"0": mean}}}; per TPA
# protocol fig5 (the paper's) or fig5_<protocol> {env: {panel N: {method: {M: mean}}}} and
# fig5[_<protocol>]_references (the same, the references'); fig5_protocols {protocol: the file
# drawn, or "not run"}; fig7 {env: {N, M, bars, missing}}; fig3.
DRAWN = {}


def mean_ci(values):
    """Mean and the half-width of its 95 % t confidence interval (nan for one value)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if len(v) == 0:
        return np.nan, np.nan
    if len(v) == 1:
        return v[0], np.nan
    return v.mean(), stats.t.ppf(0.975, len(v) - 1) * v.std(ddof=1) / math.sqrt(len(v))


def save(fig, out, name):
    for ext in ("png", "pdf"):
        save_figure(fig, os.path.join(out, f"{name}.{ext}"), dpi=150, bbox_inches="tight")
    plt.close(fig)


def reference_rows(refs, env):
    """(reference, its rows of env) for every reference `refs` holds there, in
    REFERENCE_STYLE's order."""
    if refs.empty:
        return []
    d = refs[refs.env == env]
    names = [v for v in REFERENCE_STYLE if (d.variant == v).any()]
    names += sorted(set(d.variant) - set(names))
    return [(v, d[d.variant == v]) for v in names]


def reference_line(ax, v, values):
    """A reference's mean over seeds across the panel (no band: a reference line, not a
    method's estimate); returns the mean."""
    colour, label, ls = reference_style(v)
    m, _ = mean_ci(values)
    ax.axhline(m, color=colour, ls=ls, lw=1.6, label=label, zorder=1)
    return m


def reference_marks(ax, v, Ms, ms, span):
    """A reference at a few M far apart (no line across the gap between them, as the methods):
    at each M a short horizontal segment in the reference's dashes, `span` wide on the M axis."""
    colour, label, ls = reference_style(v)
    for i, (x, y) in enumerate(zip(Ms, ms)):
        if np.isfinite(y):
            ax.plot([x - span, x + span], [y, y], color=colour, ls=ls, lw=1.8, zorder=1,
                    label=label if i == 0 else "_" + label)


def mse_floor(ax, drew_reference):
    """An MSE axis from 0 (CI bands of few seeds may dip below it), a little below 0 when a
    reference is drawn: truth φ*'s FPE is about 0 and would hide in the x-axis."""
    ax.set_ylim(bottom=0)
    if drew_reference:
        ax.set_ylim(bottom=-0.02 * ax.get_ylim()[1])


FPE_LABEL = "FPE (test MSE, normalised features)"
TPA_LABEL = "TPA (held-out accuracy)"


def fpe_dots(ax, d, env, Ns, refs):
    """Fig. 4's panel for an environment run at one N: each method's mean FPE as a dot with its
    95 % CI, methods along the x-axis (an N axis with one point would read as a curve); the
    references as horizontal lines."""
    variants = [v for v in ORDER if (d.variant == v).any()]
    for i, v in enumerate(variants):
        colour, label = STYLE[v]
        m, ci = mean_ci(d[d.variant == v].fpe)
        DRAWN.setdefault("fig4", {}).setdefault(env, {})[v] = {
            str(Ns[0]) if Ns and d[d.variant == v].N.notna().all() else "0": float(m)}
        ax.errorbar([i], [m], yerr=[ci if np.isfinite(ci) else 0], fmt=line_style(v)[0],
                    color=colour, capsize=3, ms=6, label=label)
    lines = reference_rows(refs, env)
    for v, dv in lines:
        m = reference_line(ax, v, dv.fpe)
        DRAWN.setdefault("fig4_references", {}).setdefault(env, {})[v] = {"0": float(m)}
    ax.set_xticks(range(len(variants)))
    ax.set_xticklabels([STYLE[v][1] for v in variants], rotation=35, ha="right", fontsize=8)
    ax.set_xlim(-0.6, len(variants) - 0.4)
    ax.set_title(f"{env_title(env)}" + (f", N = {Ns[0]}" if Ns else ""))
    mse_floor(ax, bool(lines))
    ax.set_ylabel(f"{FPE_LABEL}\n({better_note('fpe')})", fontsize=9)
    ax.grid(alpha=0.3, axis="y")


def plot_fig4(fpe, envs, out, notes):
    """Fig. 4: each method's FPE against N; the references (truth φ*, raw input: no queries) as
    horizontal black lines, recorded under figures.json's fig4_references; one legend below the
    panels."""
    refs = references(fpe)
    fpe = methods(fpe)
    envs = [e for e in envs if not fpe.empty and (fpe.env == e).any()]
    if not envs:
        notes.append("Fig. 4: no FPE cells in this file")
        return
    note_references(notes, "Fig. 4", refs)
    fig, axes = plt.subplots(1, len(envs), figsize=(min(4.5 * len(envs), 14), 3.8),
                             squeeze=False, constrained_layout=True)
    flat_methods = []
    for ax, env in zip(axes[0], envs):
        d = fpe[fpe.env == env]
        Ns = sorted(int(n) for n in d.N.dropna().unique())
        if len(Ns) <= 1:  # one N (the simplified GridRobot): a dot per method, not a curve
            fpe_dots(ax, d, env, Ns, refs)
            continue
        for v in ORDER:
            dv = d[d.variant == v]
            if dv.empty:
                continue
            colour, label = STYLE[v]
            marker, ls = line_style(v)
            if dv.N.isna().all():  # VAE and Random use no queries: one value per seed
                m, ci = mean_ci(dv.fpe)
                DRAWN.setdefault("fig4", {}).setdefault(env, {})[v] = {"0": float(m)}
                ax.axhline(m, color=colour, ls="--", lw=1.5, label=label)
                if np.isfinite(ci) and Ns:
                    ax.axhspan(m - ci, m + ci, color=colour, alpha=0.12)
                if label not in flat_methods:
                    flat_methods.append(label)
                continue
            xs, ms, cis = [], [], []
            for n in Ns:
                m, ci = mean_ci(dv[dv.N == n].fpe)
                xs.append(n)
                ms.append(m)  # nan for a missing cell: matplotlib leaves a gap
                cis.append(ci)
            ms, cis = np.array(ms), np.array(cis)
            DRAWN.setdefault("fig4", {}).setdefault(env, {})[v] = {
                str(x): float(m) for x, m in zip(xs, ms) if np.isfinite(m)}
            if np.isnan(ms).any():
                notes.append(f"Fig. 4 {env_title(env)}: {label} missing at N = "
                             f"{[x for x, m in zip(xs, ms) if np.isnan(m)]} (drawn as gaps)")
            ax.plot(xs, ms, marker=marker, ls=ls, color=colour, label=label, ms=4)
            ok = np.isfinite(cis)
            ax.fill_between(np.array(xs)[ok], (ms - cis)[ok], (ms + cis)[ok], color=colour, alpha=0.15)
        lines = reference_rows(refs, env)
        for v, dv in lines:
            m = reference_line(ax, v, dv.fpe)
            DRAWN.setdefault("fig4_references", {}).setdefault(env, {})[v] = {"0": float(m)}
        ax.set_title(env_title(env))
        mse_floor(ax, bool(lines))
        ax.set_xlabel("representation queries N")
        ax.set_ylabel(f"{FPE_LABEL}\n({better_note('fpe')})", fontsize=9)
        ax.grid(alpha=0.3)
    legend_below(fig, axes[0])
    sub = [better_note("fpe")]
    if not refs.empty:
        sub.append("black lines: references (no queries)")
    if flat_methods:
        sub.append(f"dashed across N: {', '.join(flat_methods)} (no queries, one value)")
    fig.suptitle("Fig. 4: feature prediction error (mean ± 95 % CI over seeds)\n"
                 + wrap("; ".join(sub), 140), fontsize=10)
    save(fig, out, "fig4_fpe")


def wrap(text, width):
    """A subtitle wrapped at `width` characters (a figure's title is no wider than its panels)."""
    import textwrap
    return "\n".join(textwrap.wrap(text, width))


def note_references(notes, fig, refs):
    """A note when a figure has no reference to draw (a file of an older engine). Which references
    a protocol scores is the engine's (the paper's protocol has no raw-input cells): a figure
    draws those its rows hold, listed in figures.json."""
    if refs.empty:
        notes.append(f"{fig}: the references ({', '.join(s[1] for s in REFERENCE_STYLE.values())})"
                     " not run (no reference rows in this file)")


def plot_fig5(tpa, envs, out, notes, protocol=PAPER):
    """Fig. 5 under one TPA protocol: each method's TPA against M, one panel per (environment, N),
    in its best mode for that protocol; the references (truth φ*, raw input: no queries) as black
    reference lines in every panel of their environment, chance (0.5) as a thin grey line, one
    legend below the panels. The paper's protocol draws fig5_tpa (figures.json: fig5,
    fig5_references), another fig5_tpa_<protocol> (fig5_<protocol>, ...). Returns whether it
    drew."""
    key = fig_name("fig5", protocol)
    title = "Fig. 5" if protocol == PAPER else f"Fig. 5 ({protocol} protocol)"
    t = main_tpa(tpa, protocol)
    refs = reference_tpa(tpa, protocol)
    envs = [e for e in envs if (t.env == e).any()] if not t.empty else []
    if not envs:
        if not tpa.empty and of_protocol(tpa, protocol).empty:
            notes.append(f"{title}: not run (this file has no TPA cells of the {protocol} "
                         "protocol)")
        else:
            notes.append(f"{title}: no TPA cells of the main grid in this file")
        DRAWN.setdefault("fig5_protocols", {})[protocol] = "not run"
        return False
    note_references(notes, title, refs)
    Ns = sorted(int(n) for n in t.N.dropna().unique())
    if not Ns:
        Ns = [0]
    width = min(4.2 * len(Ns), 14)
    fig, axes = plt.subplots(len(envs), len(Ns), figsize=(width, 3.4 * len(envs)),
                             squeeze=False, sharey=True, constrained_layout=True)
    for r, env in enumerate(envs):
        for c, n in enumerate(Ns):
            ax = axes[r][c]
            d = t[(t.env == env) & ((t.N == n) | t.N.isna())]
            Ms = sorted(int(m) for m in d.M.dropna().unique())
            for v in ORDER:
                dv = d[d.variant == v]
                if dv.empty:
                    continue
                colour, label = STYLE[v]
                marker, ls = line_style(v)
                stats_ = [mean_ci(dv[dv.M == m].tpa) for m in Ms]
                ms = np.array([s[0] for s in stats_])
                cis = np.array([s[1] for s in stats_])
                DRAWN.setdefault(key, {}).setdefault(env, {}).setdefault(str(n), {})[v] = {
                    str(m): float(x) for m, x in zip(Ms, ms) if np.isfinite(x)}
                if np.isnan(ms).any():
                    notes.append(f"{title} {env_title(env)} N={n}: {label} missing at M = "
                                 f"{[m for m, x in zip(Ms, ms) if np.isnan(x)]} (gaps)")
                if len(Ms) >= 3:
                    ax.plot(Ms, ms, marker=marker, ls=ls, color=colour, label=label, ms=4)
                    ok = np.isfinite(cis)
                    ax.fill_between(np.array(Ms)[ok], (ms - cis)[ok], (ms + cis)[ok],
                                    color=colour, alpha=0.15)
                else:  # two M points far apart: a line between them would invent a curve;
                    # the methods' markers are spread a little along M so that none hides another
                    k = ORDER.index(v) if v in ORDER else 0
                    dodge = (k - (len(ORDER) - 1) / 2) * 0.012 * (max(Ms) - min(Ms) or 1)
                    ax.errorbar(np.array(Ms) + dodge, ms, yerr=np.nan_to_num(cis), fmt=marker,
                                color=colour, label=label, ms=4, capsize=3)
            for v, dv in reference_rows(refs, env):  # N-free: the same line in every panel
                rMs = sorted(int(m) for m in dv.M.dropna().unique())
                ms = np.array([mean_ci(dv[dv.M == m].tpa)[0] for m in rMs])
                colour, label, ls = reference_style(v)
                DRAWN.setdefault(key + "_references", {}).setdefault(env, {}).setdefault(
                    str(n), {})[v] = {str(m): float(x) for m, x in zip(rMs, ms) if np.isfinite(x)}
                if len(rMs) >= 3:
                    ax.plot(rMs, ms, color=colour, ls=ls, lw=1.6, label=label, zorder=1)
                else:  # as the methods: no line across the gap between two M values
                    span = 0.06 * (max(Ms + rMs) - min(Ms + rMs) or 10)
                    reference_marks(ax, v, rMs, ms, span)
            chance_line(ax)
            ax.set_title(f"{env_title(env)}, N = {n}")
            ax.set_ylim(0.35, 1.0)
            ax.set_xlabel("preference queries per test reward M")
            if c == 0:
                ax.set_ylabel(f"{TPA_LABEL}\n({better_note('tpa')})", fontsize=9)
            ax.grid(alpha=0.3)
    legend_below(fig, axes.flat)
    sub = f"{better_note('tpa')}; black lines: references (no queries); grey line: chance"
    if protocol == PAPER:
        frozen = "SIRL" + (" and external methods" if (t.method == "external").any() else "")
        fig.suptitle(f"Fig. 5: test preference accuracy ({frozen} frozen, others unfrozen; "
                     f"mean ± 95 % CI)\n{sub}", fontsize=10)
    else:
        fig.suptitle(wrap(f"{title}: test preference accuracy, "
                          f"{PROTOCOL_TEXT.get(protocol, protocol)} (mean ± 95 % CI)",
                          int(11 * width)) + "\n" + sub, fontsize=10)
    save(fig, out, fig_name("fig5_tpa", protocol))
    DRAWN.setdefault("fig5_protocols", {})[protocol] = fig_name("fig5_tpa", protocol)
    return True


def plot_fig7(tpa, envs, out, notes):
    """Fig. 7 from the cells the file marks as the ablation's (in_ablation), per environment: the
    paper's protocol only (the linear protocol fits heads on a frozen φ, so it has no ablation;
    the references are not methods)."""
    tpa = methods(of_protocol(tpa, PAPER))
    ab = tpa[tpa["in_ablation"]] if not tpa.empty and "in_ablation" in tpa else tpa.iloc[0:0]
    envs = [e for e in envs if (ab.env == e).any()]
    if not envs:
        notes.append("Fig. 7: no ablation cells in this file")
        return
    fig, axes = plt.subplots(1, len(envs), figsize=(min(6.5 * len(envs), 14), 3.8),
                             squeeze=False, constrained_layout=True)
    bases = [b for b in methods_of("sirl") + methods_of("baseline") if b in set(ab.method)]
    configs = [(1, 0, "frozen"), (0, 0, "unfrozen"), (1, 1, "frozen + VAE"), (0, 1, "unfrozen + VAE")]
    hatches = ["", "//", "..", "xx"]
    for ax, env in zip(axes[0], envs):
        d = ab[ab.env == env]
        Nab = sorted(int(n) for n in d.N.dropna().unique())
        Mab = sorted(int(m) for m in d.M.dropna().unique())
        width = 0.2
        for k, (fr, vae, name) in enumerate(configs):
            ms, cis = [], []
            for b in bases:
                cell = d[(d.method == b) & (d.frozen == fr) & (d.vae == vae)]
                # mean over the ablation's (N, M) cells per seed, then over seeds
                per_seed = cell.groupby("seed").tpa.mean()
                m, ci = mean_ci(per_seed)
                ms.append(m)
                cis.append(ci)
            x = np.arange(len(bases)) + (k - 1.5) * width
            colours = [STYLE[b][0] for b in bases]
            ax.bar(x, np.nan_to_num(ms, nan=0.0) * np.isfinite(ms), width, yerr=np.nan_to_num(cis),
                   color=colours, edgecolor="black", hatch=hatches[k], alpha=0.85, label=name)
            for xi, m, b in zip(x, ms, bases):
                if np.isnan(m):
                    applicable = vae == 0 or bool(METHODS.accepts_vae[b])
                    ax.text(xi, 0.41, "n/a" if not applicable else "missing", rotation=90,
                            ha="center", va="bottom", fontsize=7)
                    if applicable:
                        notes.append(f"Fig. 7 {env_title(env)}: no {name} cell for "
                                     f"{STYLE[b][1]}")
        DRAWN.setdefault("fig7", {})[env] = {
            "N": Nab, "M": Mab,
            "bars": int(sum(np.isfinite(p.get_height()) and p.get_height() > 0 for p in ax.patches)),
            "missing": sum(1 for t in ax.texts if t.get_text() == "missing")}
        ax.set_xticks(np.arange(len(bases)))
        ax.set_xticklabels([STYLE[b][1] for b in bases], fontsize=8)
        ax.set_ylim(0.4, 1.0)
        chance_line(ax, text=False, zorder=3)
        ax.set_ylabel(f"TPA (mean over the cells)\n({better_note('tpa')})", fontsize=9)
        ax.set_title(f"{env_title(env)}, N = {Nab}, M = {Mab}")
        ax.grid(alpha=0.3, axis="y")
    handles = [matplotlib.patches.Patch(facecolor="white", edgecolor="black", hatch=h, label=c[2])
               for h, c in zip(hatches, configs)]
    handles.append(matplotlib.lines.Line2D([], [], label=CHANCE_LABEL, **CHANCE_STYLE))
    fig.legend(handles=handles, fontsize=8, loc="upper center", bbox_to_anchor=(0.5, 0.0),
               ncol=len(handles), frameon=False)
    fig.suptitle("Fig. 7: ablation — frozen/unfrozen φ × VAE pre-training (n/a: VAE "
                 f"pre-training does not apply); {better_note('tpa')}", fontsize=10)
    save(fig, out, "fig7_ablation")


def rep_keys(res, env, variant):
    """Keys of the main teacher's representations of (env, variant) that stored an embedding,
    largest N first, then lowest seed."""
    r = res.records
    if r.empty or "variant" not in r:
        return []
    r = r[(r.kind == "rep") & (r.env == env) & (r.variant == variant) & (r.teacher == "")]
    r = r[r.arrays.str.split(",").map(lambda a: "embedding" in a)]
    return list(r.sort_values(["N", "seed"], ascending=[False, True]).key)


def angle_label(ax, x, y, angles, colour, size):
    """The end angles of the trajectories ending at cell (x, y), as one label (a shared end
    writes every angle once, its count beside a repeated one: "+60° ×2 / −60°"), put beside
    the cell on the side facing the grid's centre so that it stays inside the panel, on a white
    box over the lines."""
    counts = {}
    for a in angles:
        counts[a] = counts.get(a, 0) + 1
    text = " / ".join(a + (f" ×{n}" if n > 1 else "") for a, n in counts.items())
    mid = (size - 1) / 2
    dx = 6 if x <= mid else -6
    dy = 7 if y <= mid else -7
    ax.annotate(text.replace("-", "−"), (x, y), xytext=(dx, dy), textcoords="offset points",
                ha="left" if dx > 0 else "right", va="bottom" if dy > 0 else "top", fontsize=7,
                color=colour, zorder=5,
                bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.85))


def plot_fig3(res, out, notes):
    """The paper's Fig. 3: on the simplified GridRobot (laptop + angle), trajectories most and
    least similar to a query under a SIRL φ, from the φ's stored embedding of Ξ."""
    # The environment Fig. 3 is drawn on: the highest fig3_rank with a SIRL φ in the file.
    ranked = sorted((e for e in ENV if ENV[e]["fig3_rank"] > 0), key=lambda e: -ENV[e]["fig3_rank"])
    env, keys = None, []
    for e in ranked:
        keys = rep_keys(res, e, "sirl")
        if keys:
            env = e
            break
    if env and env != ranked[0]:
        notes.append(f"Fig. 3: no {env_title(ranked[0])} SIRL φ in this file; drawn on {env_title(env)}")
    if not keys:
        notes.append("Fig. 3: no SIRL representation of a Fig. 3 environment in this file")
        return None
    key = keys[0]
    E = res.embedding(key)
    g = res.datasets[env]
    X = g["inputs"]
    F = g["features"]  # normalised φ*; columns as the dataset names them
    fnames = list(g["attrs"].get("features.feature_names", []))
    lap = fnames.index("laptop_distance") if "laptop_distance" in fnames else 0
    ang = fnames.index("abs_angle") if "abs_angle" in fnames else 1
    # The paper's two queries: far from the laptop holding the cup on its side; close to the
    # laptop holding the cup at an angle (|angle| = 30 or 60 degrees).
    q_far = int(np.argmax(F[:, lap] + F[:, ang]))
    tilted = np.where(np.isin(np.round(np.abs(X[:, 18]) * 90), [30, 60]))[0]
    q_near = int(tilted[np.argmin(F[tilted, lap])]) if len(tilted) else int(np.argmin(F[:, lap]))
    objects = g["objects"]
    onames = list(g["attrs"]["objects.names"])
    size, scale = 5, 4

    def draw(ax, idx, title, colour):
        ax.set_xlim(-0.5, size - 0.5)
        ax.set_ylim(-0.5, size - 0.5)
        ax.set_aspect("equal")
        ax.set_xticks(range(size))
        ax.set_yticks(range(size))
        ax.grid(alpha=0.3)
        for (ox, oy), n in zip(objects, onames):
            marker, c = ("s", "black") if n.startswith("obstacle") else ("D", "tab:orange")
            ax.scatter([ox], [oy], marker=marker, s=260, c=c, zorder=3)
        ends = {}  # end cell -> the end angles of the trajectories ending there
        for i in idx:
            pts = X[i, :18].reshape(9, 2) * scale
            ax.plot(pts[:, 0], pts[:, 1], "-o", color=colour, ms=3, lw=2, alpha=0.8)
            ends.setdefault(tuple(np.round(pts[-1], 3)), []).append(f"{X[i, 18] * 90:+.0f}°")
        for (ex, ey), angles in ends.items():
            angle_label(ax, ex, ey, angles, colour, size)
        ax.set_title(title, fontsize=9)

    fig, axes = plt.subplots(2, 3, figsize=(10, 7))
    for row, q in enumerate([q_far, q_near]):
        dist = ((E - E[q]) ** 2).sum(1)
        dist[q] = np.inf
        nearest = np.argsort(dist)[:3]
        dist[q] = -np.inf
        farthest = np.argsort(dist)[-3:][::-1]
        draw(axes[row][0], [q], f"query ξ{q}", "black")
        draw(axes[row][1], nearest, "most similar under φ", "tab:green")
        draw(axes[row][2], farthest, "least similar under φ", "tab:red")
    DRAWN["fig3"] = {"env": env, "representation": key, "queries": [q_far, q_near]}
    marks = "◆ laptop" + (", ■ obstacles" if any(n.startswith("obstacle") for n in onames) else "")
    fig.suptitle(f"Fig. 3: {env_title(env)} under a SIRL φ ({key})\n{marks}; labels: end "
                 "angle in degrees (×k: k trajectories end there at that angle)", fontsize=10)
    save(fig, out, "fig3_grid_similar")
    return key


def head_mean_curves(res, rows):
    """{key: 1-D loss curve} of the given training rows; a TPA cell's heads are averaged at each
    epoch over the heads still training (a head stopped by tpa.stop has no rows after its stop),
    and the curve ends where the last head stopped."""
    recs = res.records[res.records.key.isin(set(rows.key))]
    c = res.curves_of(recs)
    if c.empty:
        return {}
    m = c.groupby(["key", "epoch"], sort=True).loss.mean()
    return {k: m.loc[k].to_numpy() for k in m.index.get_level_values(0).unique()}


def readable_log_y(ax, lo, hi):
    """A log y axis with tick labels a reader can use on a short range too (a loss falling from
    1.9 to 0.4 spans less than a decade, where the default labels one tick or none): ticks at
    1 (or 1, 2, 5, or 1, 2, 3, 5) times a power of ten, whichever first gives three or more
    spread over [lo, hi] (none of its ends further from a tick than the ticks' spacing); else
    evenly spaced round values (0.5, 1, 1.5); labelled as plain numbers. A range too short for
    three ticks is drawn linear. Returns the scale drawn."""
    from matplotlib.ticker import (FixedLocator, FuncFormatter, MaxNLocator, NullFormatter,
                                   NullLocator)
    if not (np.isfinite(lo) and np.isfinite(hi)) or lo <= 0 or hi <= lo:
        return ax.get_yscale()
    e0, e1 = int(math.floor(math.log10(lo))), int(math.ceil(math.log10(hi)))
    for subs, near in (((1,), 10), ((1, 2, 5), 2.5), ((1, 2, 3, 5), 2)):
        ticks = [s * 10.0 ** e for e in range(e0, e1 + 1) for s in subs
                 if lo <= s * 10.0 ** e <= hi]
        if len(ticks) >= 3 and ticks[0] <= near * lo and ticks[-1] >= hi / near:
            break
    else:
        ticks = [y for y in MaxNLocator(nbins=5, steps=[1, 2, 2.5, 5, 10]).tick_values(lo, hi)
                 if lo <= y <= hi and y > 0]
        if len(ticks) < 3:
            ax.set_yscale("linear")
            return "linear"
    ticks = ticks[::max(1, math.ceil(len(ticks) / 8))]
    ax.set_yscale("log")
    ax.set_ylim(lo / 1.05, hi * 1.05)
    ax.yaxis.set_major_locator(FixedLocator(ticks))
    ax.yaxis.set_major_formatter(FuncFormatter(lambda y, _: f"{y:g}"))
    ax.yaxis.set_minor_locator(NullLocator())
    ax.yaxis.set_minor_formatter(NullFormatter())
    return "log"


def counts_text(counts):
    """The trainings behind a panel's curves: "5 trainings each", or each method's count when
    they differ."""
    if len(set(counts.values())) == 1:
        n = next(iter(counts.values()))
        return f"{n} training{'s' if n != 1 else ''}" + (" each" if len(counts) > 1 else "")
    return ", ".join(f"{lab} {n}" for lab, n in counts.items())


def coinciding(curves, span):
    """Groups (lists of indices) of the curves that coincide: the same length and, at 90 % of
    their epochs or more, no further apart than 1 % of the panel's range `span` (a first
    epoch or two apart: they still hide one another); a curve alone is a group of one."""
    groups = []
    for k, c in enumerate(curves):
        for g in groups:
            o = curves[g[0]]
            if len(o) == len(c) and len(c) > 1 and \
                    np.nanpercentile(np.abs(o - c), 90) <= 0.01 * span:
                g.append(k)
                break
        else:
            groups.append([k])
    return groups


def plot_learning_curves(res, t, envs, out, notes):
    """Per environment: the VAE, each method's φ at its largest N, and the TPA heads of the main
    grid's largest (N, M): median over seeds with the min–max band. Only the panels with a
    curve are drawn (an environment whose cells trained no such thing is noted), every method in
    its STYLE colour and LINE style (curves that coincide stay visible), one legend below; what
    each panel drew is in figures.json's learning_curves {env: {kind: {variant: trainings}}}."""
    tr = t["training"]
    if tr.empty:
        notes.append("learning curves: no training in this file")
        return False
    envs = [e for e in envs if (tr.env == e).any()]
    kinds = [("vae", "VAE (loss per epoch)"), ("rep", "φ training (largest N)"),
             ("tpa", "TPA heads (largest N, M; mean over heads)")]
    # The curves first: which panels have any, so that no empty panel is drawn.
    panels = {}
    for env in envs:
        for kind, title in kinds:
            d = tr[(tr.env == env) & (tr.kind == kind)]
            if kind == "tpa":
                d = d[(d.N == d.N.max()) & (d.M == d.M.max())] if not d.empty else d
            curves = []
            for v in ["vae"] if kind == "vae" else ORDER:
                dv = d[d.variant == v]
                if kind == "rep" and not dv.empty:
                    dv = dv[dv.N == dv.N.max()]
                if dv.empty:
                    continue
                cs = list(head_mean_curves(res, dv).values())
                if cs:
                    curves.append((v, cs, bool(dv.frozen.all()) if "frozen" in dv else False))
            if curves:
                panels[(env, kind)] = curves
            else:
                notes.append(f"learning curves: {env_title(env)}: no {title.split(' (')[0]} "
                             "trainings in this file (not run; no panel drawn)")
    if not panels:
        notes.append("learning curves: no training curves in this file")
        return False
    cols = [k for k in kinds if any((e, k[0]) in panels for e in envs)]
    rows = [e for e in envs if any((e, k[0]) in panels for k in cols)]
    fig, axes = plt.subplots(len(rows), len(cols), figsize=(4.4 * len(cols), 3.1 * len(rows)),
                             squeeze=False, constrained_layout=True)
    drawn = DRAWN.setdefault("learning_curves", {})
    for r, env in enumerate(rows):
        for c, (kind, title) in enumerate(cols):
            ax = axes[r][c]
            if (env, kind) not in panels:
                ax.remove()
                continue
            counts, frozen, lo, hi = {}, [], np.inf, -np.inf
            series = []
            for v, cs, is_frozen in panels[(env, kind)]:
                n = max(len(x) for x in cs)  # curves of stopped heads end early: NaN-padded
                A = np.full((len(cs), n), np.nan)
                for i, x in enumerate(cs):
                    A[i, :len(x)] = x
                series.append((v, A))
                counts[STYLE.get(v, ("", "VAE"))[1]] = len(cs)
                if kind == "tpa" and is_frozen:
                    frozen.append(STYLE[v][1])
                drawn.setdefault(env, {}).setdefault(kind, {})[v] = len(cs)
                lo, hi = min(lo, np.nanmin(A)), max(hi, np.nanmax(A))
            groups = coinciding([np.nanmedian(A, 0) for _, A in series], hi - lo)
            for k, (v, A) in enumerate(series):
                n = A.shape[1]
                ep = np.arange(1, n + 1)
                colour, label = STYLE.get(v, ("#2ca02c", "VAE"))
                marker, ls = line_style(v)
                g = next(g for g in groups if k in g)
                # Curves that coincide: the first drawn widest, each later one narrower on top
                # of it, so that every colour and dash stays visible.
                lw = min(1.5 + 0.8 * (len(g) - 1 - g.index(k)), 4.7)
                ax.plot(ep, np.nanmedian(A, 0), ls=ls, marker=marker if n < 10 else None, ms=3,
                        lw=lw, color=colour, alpha=0.85 if lw > 1.5 else 1.0)
                ax.plot([], [], ls=ls, marker=marker, ms=3, lw=1.5, color=colour, label=label)
                ax.fill_between(ep, np.nanmin(A, 0), np.nanmax(A, 0), color=colour, alpha=0.15)
            same = [", ".join(STYLE.get(series[k][0], ("", "VAE"))[1] for k in g)
                    for g in groups if len(g) > 1]
            head = f"{env_title(env)}: {title}"
            tail = counts_text(counts) + (f"; frozen: {', '.join(frozen)}" if frozen else "")
            if same:
                tail += "\n" + wrap("nearly one curve: " + "; ".join(same), 62)
            ax.set_title(f"{head}\n{tail}", fontsize=8)
            ax.set_xlabel("epoch")
            ax.set_ylabel("training loss (lower is better)", fontsize=8)
            ax.grid(alpha=0.3)
            if kind == "vae":
                readable_log_y(ax, lo, hi)
    legend_below(fig, [a for a in axes.flat if a in fig.axes])
    fig.suptitle("Learning curves: median over seeds (band: min–max; below each panel's title: "
                 "the trainings drawn)", fontsize=10)
    save(fig, out, "fig_learning_curves")
    return True
