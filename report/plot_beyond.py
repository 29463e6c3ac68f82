"""The figures and report sections of the questions beyond the paper (profile `beyond`):

  fig_active      SIRL on actively chosen triplets (sirl@vote, sirl@infogain) against the
                  paper's uniform triplets: FPE vs N, TPA at each N (frozen, as SIRL in Fig. 5);
                  the report estimates N*, the fewest active queries whose FPE matches uniform
                  selection's at the largest N, with a bootstrap CI over seeds, and the compute.
  fig_robustness  every method's FPE and TPA against the noise of its teacher, one column per
                  noise axis (Boltzmann β, mistake rate, attended features); the report gives each
                  method's degradation from the perfect teacher to the noisiest, with a CI.

Imported by plot_figures.py; reads the DataFrames of /tables/fpe, tpa, robust_fpe, robust_tpa
and timings. Draws nothing (and says so) when a file has none of these cells.
"""
import math
import os

import matplotlib.pyplot as plt
import numpy as np

import figures
from safe_output import save_figure
from run_tables import PAPER, methods, of_protocol

# The query-selection variants of SIRL (uniform = the paper's) and the methods of the noisy-teacher
# figures, as colour and label from the file's /methods (figures.load_styles fills it first).


def selection_styles():
    """{variant: (colour, label)} of SIRL's selection rules in the file, uniform first."""
    m = figures.METHODS
    m = m[(m.role == "sirl") & ~m.vae].sort_values("selection_order")
    return {v: (r.selection_colour, r.selection_label) for v, r in m.iterrows()}


def method_styles():
    """{variant: (colour, label)} of the plain methods, in the figures' order."""
    return {v: figures.STYLE[v] for v in figures.methods_of("sirl") + figures.methods_of("baseline")}


AXES = {"beta": ("Boltzmann β", True), "mistake": ("mistake rate", False),
        "attend": ("share of features attended", True)}  # True: noisier as the value falls
BOOTSTRAP = 2000


def active_rules():
    """{variant: its query selection rule} of SIRL's active variants in the file (the
    `selection` column of every table), in the engine's order."""
    return {v: s for v, s in selection_rules().items() if s != "uniform"}


def selection_rules():
    m = figures.METHODS
    m = m[(m.role == "sirl") & ~m.vae].sort_values("selection_order")
    return dict(zip(m.index, m.selection))


def mean_ci(v):
    """figures.mean_ci as plain floats (the JSON of what was drawn)."""
    m, ci = figures.mean_ci(v)
    return float(m), float(ci)


def save(fig, out, name):
    for ext in ("png", "pdf"):
        save_figure(fig, os.path.join(out, f"{name}.{ext}"), dpi=150, bbox_inches="tight")
    plt.close(fig)


# ---------------------------------------------------------------- active selection

def active_envs(fpe):
    if fpe.empty:
        return []
    has = fpe[fpe.variant.isin(list(active_rules()))]
    return [e for e in dict.fromkeys(has.env)]


def fpe_curves(d, variant):
    """{seed: {N: fpe}} of one variant."""
    out = {}
    for _, r in d[d.variant == variant].iterrows():
        out.setdefault(int(r.seed), {})[int(r.N)] = float(r.fpe)
    return out


def n_star(curve_ns, active_means, target):
    """The smallest N (interpolated linearly between grid points) at which the active mean FPE
    is at or below `target`; inf when it never is on the grid."""
    for i, (n, m) in enumerate(zip(curve_ns, active_means)):
        if m <= target:
            if i == 0:
                return float(n)
            n0, m0 = curve_ns[i - 1], active_means[i - 1]
            return float(n0 + (n - n0) * (m0 - target) / (m0 - m)) if m0 != m else float(n)
    return math.inf


def n_star_estimate(d, variant, seed=0):
    """N* of `variant` against uniform SIRL's FPE at the largest N, and a 95 % percentile CI from
    resampling seeds (the same seeds for both curves: the design is paired by seed)."""
    uni, act = fpe_curves(d, "sirl"), fpe_curves(d, variant)
    Ns = sorted(set.intersection(*[set(c) for c in list(uni.values()) + list(act.values())]))
    seeds = sorted(set(uni) & set(act))
    if len(Ns) < 2 or not seeds:
        return None
    top = Ns[-1]
    U = np.array([[uni[s][n] for n in Ns] for s in seeds])
    A = np.array([[act[s][n] for n in Ns] for s in seeds])

    def est(idx):
        return n_star(Ns, A[idx].mean(axis=0), U[idx, -1].mean())

    point = est(np.arange(len(seeds)))
    rng = np.random.default_rng(seed)
    boots = np.array([est(rng.integers(0, len(seeds), len(seeds))) for _ in range(BOOTSTRAP)])
    finite = boots[np.isfinite(boots)]
    lo = float(np.percentile(boots, 2.5)) if len(seeds) > 1 else math.nan
    hi = float(np.percentile(boots, 97.5)) if len(seeds) > 1 else math.nan
    return {"variant": variant, "N_top": top, "N_star": point, "ci": (lo, hi),
            "share_reached": float(len(finite) / len(boots)), "seeds": len(seeds), "Ns": Ns,
            "uniform_at_top": float(U[:, -1].mean()), "active_at_top": float(A[:, -1].mean())}


def plot_active(fpe, tpa, out, notes, drawn):
    fpe, tpa = methods(fpe), methods(of_protocol(tpa, PAPER))  # the paper's TPA heads
    envs = active_envs(fpe)
    if not envs:
        return []
    fig, axes = plt.subplots(2, len(envs), figsize=(min(5.2 * len(envs), 14), 7.0),
                             squeeze=False, constrained_layout=True)
    n_styles = {}
    for c, env in enumerate(envs):
        ax = axes[0][c]
        d = fpe[fpe.env == env]
        for v, (colour, label) in selection_styles().items():
            dv = d[d.variant == v]
            if dv.empty:
                continue
            Ns = sorted(dv.N.unique())
            st = [mean_ci(dv[dv.N == n].fpe) for n in Ns]
            ms, cis = np.array([s[0] for s in st]), np.array([s[1] for s in st])
            drawn.setdefault("fig_active", {}).setdefault(env, {})[v] = {
                str(int(n)): m for n, m in zip(Ns, ms)}
            ax.plot(Ns, ms, "o-", color=colour, label=label, ms=4)
            ok = np.isfinite(cis)
            ax.fill_between(np.array(Ns)[ok], (ms - cis)[ok], (ms + cis)[ok], color=colour,
                            alpha=0.15)
        ax.set_title(env)
        ax.set_xlabel("similarity queries N")
        ax.set_ylabel(f"FPE (test MSE)\n({figures.better_note('fpe')})", fontsize=9)
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
        ax = axes[1][c]
        t = tpa[(tpa.env == env) & tpa.frozen] if not tpa.empty else tpa
        Ms = sorted(int(m) for m in t.M.dropna().unique()) if not t.empty else []
        SELECTION = selection_styles()
        if t.empty or not t.variant.isin([v for v in SELECTION if v != "sirl"]).any():
            ax.set_axis_off()
            continue
        Ns = sorted(int(n) for n in t[t.variant.isin(list(SELECTION))].N.dropna().unique())
        styles = ["--", "-", ":", "-."]
        for i, n in enumerate(Ns):
            for v, (colour, label) in SELECTION.items():
                dv = t[(t.variant == v) & (t.N == n)]
                if dv.empty:
                    continue
                st = [mean_ci(dv[dv.M == m].tpa) for m in Ms]
                ms, cis = np.array([x[0] for x in st]), np.array([x[1] for x in st])
                drawn.setdefault("fig_active_tpa", {}).setdefault(env, {}).setdefault(
                    str(int(n)), {})[v] = {str(int(m)): x for m, x in zip(Ms, ms)}
                shift = 0.015 * max(Ms) * (list(SELECTION).index(v) - 1)  # side by side
                ax.errorbar(np.array(Ms) + shift, ms,
                            yerr=np.where(np.isfinite(cis), cis, 0), color=colour,
                            ls=styles[i % len(styles)], marker="o", ms=4, capsize=2)
            n_styles[f"N = {int(n)}"] = styles[i % len(styles)]
        ax.set_xlabel("preference queries per test reward M")
        if len(Ms) == 1:
            ax.set_xlim(0.8 * Ms[0], 1.2 * Ms[0])
        ax.set_ylim(0.4, 1.0)
        figures.chance_line(ax)
        ax.set_ylabel(f"TPA (SIRL frozen)\n({figures.better_note('tpa')})", fontsize=9)
        ax.grid(alpha=0.3)
    # One legend below the panels: the selection rules' colours (the FPE row), the line style of
    # each N (the TPA row), chance.
    for lab, ls in n_styles.items():
        axes[-1][0].plot([], [], color="black", ls=ls, marker="o", ms=4, label=f"TPA at {lab}")
    figures.legend_below(fig, axes.flat)
    fig.suptitle("Active vs uniform similarity queries (mean ± 95 % CI over seeds)", fontsize=11)
    save(fig, out, "fig_active")
    return envs


def active_lines(fpe, tim, envs):
    if not envs:
        return []
    L = ["", "## Beyond the paper: active similarity queries", "",
         "SIRL trained on triplets chosen round by round from an ensemble's disagreement "
         "(*vote*: vote entropy; *infogain*: the crowd-kernel information gain, the mutual "
         "information between the answer and the ensemble member) against the paper's uniform "
         "triplets; every φ starts from the same initialisation and sees the same teacher. "
         "**N\\*** = the fewest active queries whose mean FPE is at or below uniform selection's "
         "at the largest N (linear between grid points); its 95 % CI resamples seeds "
         f"({BOOTSTRAP} draws, paired by seed); *reached* = share of draws in which N\\* is on "
         "the grid at all.", "",
         "![Active vs uniform](fig_active.png)", "",
         "| env | selection | FPE at top N (uniform → active) | N\\* | 95 % CI | reached | seeds |",
         "|---|---|---|---:|---|---:|---:|"]
    for env in envs:
        d = fpe[fpe.env == env]
        for v, rule in active_rules().items():
            e = n_star_estimate(d, v)
            if not e:
                continue
            ns = "> " + str(e["N_top"]) if not math.isfinite(e["N_star"]) else f"{e['N_star']:.0f}"
            lo, hi = e["ci"]
            ci = "—" if not math.isfinite(lo) and not math.isfinite(hi) and len(d.seed.unique()) < 2 \
                else f"[{lo:.0f}, {'> ' + str(e['N_top']) if not math.isfinite(hi) else f'{hi:.0f}'}]"
            L.append(f"| {env} | {rule} | {e['uniform_at_top']:.4f} → "
                     f"{e['active_at_top']:.4f} (N = {e['N_top']}) | {ns} | {ci} | "
                     f"{100 * e['share_reached']:.0f} % | {e['seeds']} |")
    if len(tim):
        L += ["", "What choosing costs (task-seconds on this machine, summed over seeds): the "
              "ensemble's training and pool scoring (`active` tasks) against training SIRL's φ "
              "on the chosen triplets at every N (`rep`).", "",
              "| env | selection | choosing: s | GFLOP | SIRL φ of that selection: s |",
              "|---|---|---:|---:|---:|"]
        for env in envs:
            for v, rule in selection_rules().items():
                rule = None if rule == "uniform" else rule
                act = tim[(tim.kind == "active") & (tim.env == env) & (tim.selection == rule)
                          & (tim.teacher == "")] if rule else tim.iloc[0:0]
                # the main teacher's φ of this selection only (not the robustness cells' φ)
                reps = tim[(tim.kind == "rep") & (tim.env == env) & (tim.variant == v)
                           & (tim.teacher == "")]
                L.append(f"| {env} | {rule or 'uniform'} | {act.seconds.sum():.1f} | "
                         f"{act.flops.sum() / 1e9:.0f} | {reps.seconds.sum():.1f} |")
    return L


# ---------------------------------------------------------------- noisy teachers

def reference_rows(main, d_robust, metric):
    """The main teacher's cells of the sizes the robustness cells have (the axes' reference)."""
    if main.empty or d_robust.empty:
        return main.iloc[0:0]
    keys = ["env", "variant", "seed"] + (["M", "frozen"] if metric == "tpa" else [])
    sizes = d_robust[keys + ["N"]].drop_duplicates()
    m = main.merge(sizes, on=keys + ["N"])
    return m


def axis_points(d, axis):
    """The axis's levels, perfect first then noisier, with their mean answer errors."""
    lv = sorted(d[d.axis == axis].level.unique(), reverse=AXES[axis][1])
    return lv


def robustness_frames(fpe, tpa, rfpe, rtpa):
    """Long frames of (env, variant, seed, axis, level, value, error) per metric, the perfect
    teacher's rows added to every axis at level 'perfect'."""
    out = {}
    # The main teacher's cells as the axes' reference: methods only, and the paper's TPA protocol
    # (the robustness cells' heads are the paper's).
    fpe, tpa = methods(fpe), methods(of_protocol(tpa, PAPER))
    rfpe, rtpa = methods(rfpe), methods(of_protocol(rtpa, PAPER))
    for metric, main, rob in (("fpe", fpe, rfpe), ("tpa", tpa, rtpa)):
        if rob.empty:
            continue
        r = rob.copy()
        if metric == "tpa":  # the paper's best mode per method, as in [robustness]
            r = r[r.best_mode]
        ref = reference_rows(main, r, metric)
        if metric == "tpa" and not ref.empty:
            ref = ref[ref.best_mode]
        frames = [r.assign(perfect=0)]
        for axis in r.axis.unique():
            if not ref.empty:
                frames.append(ref.assign(axis=axis, level=np.nan, perfect=1, similarity_error=0.0,
                                         preference_error=0.0))
        import pandas as pd
        out[metric] = pd.concat(frames, ignore_index=True)
    return out


def plot_robustness(fpe, tpa, rfpe, rtpa, out, notes, drawn):
    F = robustness_frames(fpe, tpa, rfpe, rtpa)
    if not F:
        return []
    envs = list(dict.fromkeys(list(rfpe.env) + list(rtpa.env)))
    axes_present = [a for a in AXES if any((f.axis == a).any() for f in F.values())]
    for env in envs:
        metrics = [m for m in ("fpe", "tpa") if m in F and (F[m].env == env).any()]
        fig, axs = plt.subplots(len(metrics), len(axes_present),
                                figsize=(min(4.4 * len(axes_present), 14), 3.4 * len(metrics)),
                                squeeze=False, constrained_layout=True)
        for r, metric in enumerate(metrics):
            d = F[metric][F[metric].env == env]
            for c, axis in enumerate(axes_present):
                ax = axs[r][c]
                da = d[d.axis == axis]
                levels = axis_points(da[da.perfect == 0], axis)
                ticks = ["perfect"] + [f"{lv:g}" for lv in levels]
                errs = [0.0] + [float(da[(da.perfect == 0) & (da.level == lv)][
                    "similarity_error" if metric == "fpe" else "preference_error"].mean())
                    for lv in levels]
                for v, (colour, label) in method_styles().items():
                    dv = da[da.variant == v]
                    if dv.empty:
                        continue
                    st = [mean_ci(dv[dv.perfect == 1][metric])] + \
                         [mean_ci(dv[(dv.perfect == 0) & (dv.level == lv)][metric]) for lv in levels]
                    ms = np.array([s[0] for s in st])
                    cis = np.array([s[1] for s in st])
                    xs = np.arange(len(ticks))
                    drawn.setdefault("fig_robustness", {}).setdefault(env, {}).setdefault(
                        metric, {}).setdefault(axis, {})[v] = {t: m for t, m in zip(ticks, ms)}
                    marker, ls = figures.line_style(v)
                    ax.plot(xs, ms, marker=marker, ls=ls, color=colour, label=label, ms=4)
                    ok = np.isfinite(cis)
                    ax.fill_between(xs[ok], (ms - cis)[ok], (ms + cis)[ok], color=colour, alpha=0.12)
                ax.set_xticks(range(len(ticks)))
                ax.set_xticklabels([f"{t}\n{100 * e:.0f} %" for t, e in zip(ticks, errs)],
                                   fontsize=8)
                ax.set_xlabel(f"{AXES[axis][0]} (below: share of answers wrong)", fontsize=8)
                if metric == "tpa":
                    figures.chance_line(ax)
                if c == 0:
                    ax.set_ylabel(("FPE (test MSE)" if metric == "fpe" else "TPA (held-out)")
                                  + f"\n({figures.better_note(metric)})", fontsize=9)
                ax.grid(alpha=0.3)
        figures.legend_below(fig, axs.flat)  # one legend below: it hides no curve
        fig.suptitle(f"{env}: robustness to noisy teachers (FPE at N = {int(F['fpe'].N.max()) if 'fpe' in F else '—'}"
                     f"; TPA at M = {int(F['tpa'].M.max()) if 'tpa' in F else '—'}; mean ± 95 % CI)",
                     fontsize=11)
        save(fig, out, f"fig_robustness_{env}")
    return envs


def robustness_lines(fpe, tpa, rfpe, rtpa, envs):
    if not envs:
        return []
    F = robustness_frames(fpe, tpa, rfpe, rtpa)
    L = ["", "## Beyond the paper: robustness to noisy teachers", "",
         "Each noisy teacher answers the very queries the perfect one was asked (its noise has "
         "random streams of its own); TPA's held-out pairs are labelled by the true reward, so "
         "accuracy is measured against the truth. Below each level: the measured share of its "
         "answers that differ from the perfect oracle's (similarity answers for FPE, preference "
         "labels for TPA). *Degradation* = the metric at the noisiest level of an axis minus at "
         "the perfect teacher, mean over seeds with a paired 95 % CI (FPE: + is worse; TPA: − is "
         "worse). FPE of VAE and Random does not depend on the teacher (their φ learns from no "
         "answers), so they have no FPE rows.", ""]
    for env in envs:
        L += [f"![Robustness: {env}](fig_robustness_{env}.png)", ""]
    L += ["| env | metric | axis (noisiest level) | method | perfect | noisiest | degradation [95 % CI] | seeds |",
          "|---|---|---|---|---:|---:|---|---:|"]
    for env in envs:
        for metric in ("fpe", "tpa"):
            if metric not in F:
                continue
            d = F[metric][F[metric].env == env]
            for axis in AXES:
                da = d[d.axis == axis]
                if da.empty:
                    continue
                levels = axis_points(da[da.perfect == 0], axis)
                worst = levels[-1]
                METHOD_STYLE = method_styles()
                for v in METHOD_STYLE:
                    dv = da[da.variant == v]
                    p = dv[dv.perfect == 1].set_index("seed")[metric]
                    w = dv[(dv.perfect == 0) & (dv.level == worst)].set_index("seed")[metric]
                    s = sorted(set(p.index) & set(w.index))
                    if not s:
                        continue
                    diff = (w.loc[s] - p.loc[s]).values
                    m, ci = mean_ci(diff)
                    cit = f"{m:+.4f} [{m - ci:+.4f}, {m + ci:+.4f}]" if np.isfinite(ci) else f"{m:+.4f}"
                    L.append(f"| {env} | {metric.upper()} | {AXES[axis][0]} = {worst:g} | "
                             f"{METHOD_STYLE[v][1]} | {p.loc[s].mean():.4f} | {w.loc[s].mean():.4f} | "
                             f"{cit} | {len(s)} |")
    return L
