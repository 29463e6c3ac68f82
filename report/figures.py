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
# filled by load_styles before anything is drawn, so no method is named here.
# STYLE {variant: (colour, label)} and ORDER (the method lines of Figs. 4, 5 and the curves, in
# the engine's order, external methods last); REFERENCE_STYLE {variant: (colour, label, dashes)}
# for the references (ceiling and floor), drawn as reference lines, never as methods; METHODS
# the file's /methods table itself (res.methods: role, queries, best_frozen, accepts_vae, …).
STYLE = {}
ORDER = []
REFERENCE_STYLE = {}
METHODS = None


def load_styles(res):
    """Fills STYLE, ORDER, REFERENCE_STYLE and METHODS from the file's /methods; raises
    sirl_bench.ResultsError for a file without it (an engine before 0.19.0)."""
    global METHODS
    m = res.methods
    if m.empty:
        raise sirl_bench.ResultsError(
            f"{res.path}: no /methods (written by an engine before 0.19.0): `sirl merge NEW.h5 "
            "THIS.h5` rewrites it with the current engine")
    METHODS = m
    STYLE.clear(), ORDER.clear(), REFERENCE_STYLE.clear()
    for v, r in m.sort_values(["catalog_order", "figure_order"]).iterrows():
        STYLE[v] = (r.colour, r.label)
        if r.role == "reference":
            dashes = tuple(float(x) for x in str(r.dashes).split()) or (4.0, 2.0)
            REFERENCE_STYLE[v] = (r.colour, r.label, (0, dashes))
    ORDER.extend(m[m.figure_order >= 0].sort_values("figure_order").index)


def methods_of(role):
    """The plain methods (no +vae, no query selection) of one role, in the figures' order."""
    m = METHODS[(METHODS.role == role) & ~METHODS.vae & (METHODS.selection == "uniform")]
    return list(m.sort_values("figure_order").index)


def reference_style(v):
    return REFERENCE_STYLE.get(v, ("#999999", f"{v} (reference)", "-."))


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


def mse_floor(ax, drew_reference):
    """An MSE axis from 0 (CI bands of few seeds may dip below it), a little below 0 when a
    reference is drawn: truth φ*'s FPE is about 0 and would hide in the x-axis."""
    ax.set_ylim(bottom=0)
    if drew_reference:
        ax.set_ylim(bottom=-0.02 * ax.get_ylim()[1])


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
        ax.errorbar([i], [m], yerr=[ci if np.isfinite(ci) else 0], fmt="o", color=colour,
                    capsize=3, ms=6, label=label)
    lines = reference_rows(refs, env)
    for v, dv in lines:
        m = reference_line(ax, v, dv.fpe)
        DRAWN.setdefault("fig4_references", {}).setdefault(env, {})[v] = {"0": float(m)}
    ax.set_xticks(range(len(variants)))
    ax.set_xticklabels([STYLE[v][1] for v in variants], rotation=35, ha="right", fontsize=8)
    ax.set_xlim(-0.6, len(variants) - 0.4)
    ax.set_title(f"{env_title(env)}" + (f", N = {Ns[0]}" if Ns else ""))
    mse_floor(ax, bool(lines))
    ax.set_ylabel("FPE (test MSE, normalised features)")
    ax.grid(alpha=0.3, axis="y")


def plot_fig4(fpe, envs, out, notes):
    """Fig. 4: each method's FPE against N; the references (truth φ*, raw input: no queries) as
    horizontal lines, recorded under figures.json's fig4_references."""
    refs = references(fpe)
    fpe = methods(fpe)
    envs = [e for e in envs if not fpe.empty and (fpe.env == e).any()]
    if not envs:
        notes.append("Fig. 4: no FPE cells in this file")
        return
    note_references(notes, "Fig. 4", refs)
    fig, axes = plt.subplots(1, len(envs), figsize=(5.2 * len(envs), 3.8), squeeze=False,
                             constrained_layout=True)
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
            if dv.N.isna().all():  # VAE and Random use no queries: one value per seed
                m, ci = mean_ci(dv.fpe)
                DRAWN.setdefault("fig4", {}).setdefault(env, {})[v] = {"0": float(m)}
                ax.axhline(m, color=colour, ls="--", lw=1.5, label=label)
                if np.isfinite(ci) and Ns:
                    ax.axhspan(m - ci, m + ci, color=colour, alpha=0.12)
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
            ax.plot(xs, ms, "o-", color=colour, label=label, ms=4)
            ok = np.isfinite(cis)
            ax.fill_between(np.array(xs)[ok], (ms - cis)[ok], (ms + cis)[ok], color=colour, alpha=0.15)
        lines = reference_rows(refs, env)
        for v, dv in lines:
            m = reference_line(ax, v, dv.fpe)
            DRAWN.setdefault("fig4_references", {}).setdefault(env, {})[v] = {"0": float(m)}
        ax.set_title(env_title(env))
        mse_floor(ax, bool(lines))
        ax.set_xlabel("representation queries N")
        ax.set_ylabel("FPE (test MSE, normalised features)")
        ax.grid(alpha=0.3)
    axes[0][-1].legend(fontsize=8, loc="upper right")
    fig.suptitle("Fig. 4: feature prediction error (mean ± 95 % CI over seeds"
                 + ("; lines: references" if not refs.empty else "") + ")", fontsize=11)
    save(fig, out, "fig4_fpe")


def note_references(notes, fig, refs):
    """A note when a figure has no reference to draw (a file of an older engine). Which references
    a protocol scores is the engine's (the paper's protocol has no raw-input cells): a figure
    draws those its rows hold, listed in figures.json."""
    if refs.empty:
        notes.append(f"{fig}: the references ({', '.join(s[1] for s in REFERENCE_STYLE.values())})"
                     " not run (no reference rows in this file)")


def plot_fig5(tpa, envs, out, notes, protocol=PAPER):
    """Fig. 5 under one TPA protocol: each method's TPA against M, one panel per (environment, N),
    in its best mode for that protocol; the references (truth φ*, raw input: no queries) as
    reference lines in every panel of their environment. The paper's protocol draws fig5_tpa
    (figures.json: fig5, fig5_references), another fig5_tpa_<protocol> (fig5_<protocol>, ...).
    Returns whether it drew."""
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
    fig, axes = plt.subplots(len(envs), len(Ns), figsize=(4.2 * len(Ns), 3.4 * len(envs)),
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
                stats_ = [mean_ci(dv[dv.M == m].tpa) for m in Ms]
                ms = np.array([s[0] for s in stats_])
                cis = np.array([s[1] for s in stats_])
                DRAWN.setdefault(key, {}).setdefault(env, {}).setdefault(str(n), {})[v] = {
                    str(m): float(x) for m, x in zip(Ms, ms) if np.isfinite(x)}
                if np.isnan(ms).any():
                    notes.append(f"{title} {env_title(env)} N={n}: {label} missing at M = "
                                 f"{[m for m, x in zip(Ms, ms) if np.isnan(x)]} (gaps)")
                if len(Ms) >= 3:
                    ax.plot(Ms, ms, "o-", color=colour, label=label, ms=4)
                    ok = np.isfinite(cis)
                    ax.fill_between(np.array(Ms)[ok], (ms - cis)[ok], (ms + cis)[ok],
                                    color=colour, alpha=0.15)
                else:  # two M points far apart: a line between them would invent a curve;
                    # the methods' markers are spread a little along M so that none hides another
                    k = ORDER.index(v) if v in ORDER else 0
                    dodge = (k - (len(ORDER) - 1) / 2) * 0.012 * (max(Ms) - min(Ms) or 1)
                    ax.errorbar(np.array(Ms) + dodge, ms, yerr=np.nan_to_num(cis), fmt="o",
                                color=colour, label=label, ms=4, capsize=3)
            for v, dv in reference_rows(refs, env):  # N-free: the same line in every panel
                rMs = sorted(int(m) for m in dv.M.dropna().unique())
                ms = np.array([mean_ci(dv[dv.M == m].tpa)[0] for m in rMs])
                colour, label, ls = reference_style(v)
                DRAWN.setdefault(key + "_references", {}).setdefault(env, {}).setdefault(
                    str(n), {})[v] = {str(m): float(x) for m, x in zip(rMs, ms) if np.isfinite(x)}
                if len(rMs) >= 3:
                    ax.plot(rMs, ms, color=colour, ls=ls, lw=1.6, label=label, zorder=1)
                else:  # as the methods: markers, no line across the gap between two M values
                    ax.plot(rMs, ms, color=colour, ls="none", marker="_", ms=14, mew=2,
                            label=label, zorder=1)
            ax.set_title(f"{env_title(env)}, N = {n}")
            ax.set_ylim(0.35, 1.0)
            ax.set_xlabel("preference queries per test reward M")
            if c == 0:
                ax.set_ylabel("TPA (held-out accuracy)")
            ax.grid(alpha=0.3)
    axes[0][-1].legend(fontsize=8, loc="lower right")
    if protocol == PAPER:
        frozen = "SIRL" + (" and external methods" if (t.method == "external").any() else "")
        fig.suptitle(f"Fig. 5: test preference accuracy ({frozen} frozen, others unfrozen; "
                     "mean ± 95 % CI)",
                     fontsize=11)
    else:
        fig.suptitle(f"{title}: test preference accuracy, {PROTOCOL_TEXT.get(protocol, protocol)}"
                     " (mean ± 95 % CI)", fontsize=10)
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
    fig, axes = plt.subplots(1, len(envs), figsize=(7 * len(envs), 3.8), squeeze=False,
                             constrained_layout=True)
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
        ax.set_ylabel("TPA (mean over the cells)")
        ax.set_title(f"{env_title(env)}, N = {Nab}, M = {Mab}")
        ax.grid(alpha=0.3, axis="y")
        handles = [matplotlib.patches.Patch(facecolor="white", edgecolor="black", hatch=h, label=c[2])
                   for h, c in zip(hatches, configs)]
        ax.legend(handles=handles, fontsize=8, loc="upper right")
    fig.suptitle("Fig. 7: ablation — frozen/unfrozen φ × VAE pre-training (n/a: VAE "
                 "pre-training does not apply)", fontsize=11)
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
        for i in idx:
            pts = X[i, :18].reshape(9, 2) * scale
            ax.plot(pts[:, 0], pts[:, 1], "-o", color=colour, ms=3, lw=2, alpha=0.8)
            ax.annotate(f"{X[i, 18] * 90:+.0f}°", pts[-1], fontsize=7, color=colour)
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
    fig.suptitle(f"Fig. 3: {env_title(env)} under a SIRL φ ({key}); {marks}, "
                 "end angle in degrees", fontsize=10)
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


def plot_learning_curves(res, t, envs, out, notes):
    """Per environment: the VAE, each method's φ at its largest N, and the TPA heads of the main
    grid's largest (N, M): median over seeds with the min–max band."""
    tr = t["training"]
    if tr.empty:
        notes.append("learning curves: no training in this file")
        return False
    envs = [e for e in envs if (tr.env == e).any()]
    panels = [("vae", "VAE (loss per epoch)"), ("rep", "φ training (largest N)"),
              ("tpa", "TPA heads (largest N, M; mean over heads)")]
    fig, axes = plt.subplots(len(envs), 3, figsize=(15, 3.3 * len(envs)), squeeze=False,
                             constrained_layout=True)
    for r, env in enumerate(envs):
        for c, (kind, title) in enumerate(panels):
            ax = axes[r][c]
            d = tr[(tr.env == env) & (tr.kind == kind)]
            if kind == "tpa":
                d = d[(d.N == d.N.max()) & (d.M == d.M.max())] if not d.empty else d
            for v in ["vae"] if kind == "vae" else ORDER:
                dv = d[d.variant == v]
                if kind == "rep" and not dv.empty:
                    dv = dv[dv.N == dv.N.max()]
                if dv.empty:
                    continue
                cs = list(head_mean_curves(res, dv).values())
                if not cs:
                    continue
                n = max(len(x) for x in cs)  # curves of stopped heads end early: NaN-padded
                A = np.full((len(cs), n), np.nan)
                for i, x in enumerate(cs):
                    A[i, :len(x)] = x
                ep = np.arange(1, n + 1)
                colour, label = STYLE.get(v, ("#2ca02c", "VAE"))
                if kind == "tpa":
                    label += " (frozen)" if dv.frozen.all() else ""
                ax.plot(ep, np.nanmedian(A, 0), "o-" if n < 10 else "-", ms=3, color=colour,
                        label=f"{label} ({len(cs)})")
                ax.fill_between(ep, np.nanmin(A, 0), np.nanmax(A, 0), color=colour, alpha=0.15)
            ax.set_title(f"{env_title(env)}: {title}", fontsize=9)
            ax.set_xlabel("epoch")
            ax.set_ylabel("training loss")
            ax.grid(alpha=0.3)
            if ax.lines:
                ax.set_yscale("log" if kind == "vae" else "linear")
                ax.legend(fontsize=7)
            else:
                ax.text(0.5, 0.5, "not run", ha="center", va="center", transform=ax.transAxes)
                ax.set_xticks([])
                ax.set_yticks([])
    fig.suptitle("Learning curves: median over seeds (band: min–max); (n) = trainings", fontsize=11)
    save(fig, out, "fig_learning_curves")
    return True
