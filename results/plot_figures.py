#!/usr/bin/python3
"""Draws the paper's figures and a report from a sirl-bench results file (HDF5 only).

    /usr/bin/python3 results/plot_figures.py RESULTS.h5 --out FIGURE_DIR

Writes fig3_grid_similar.{png,pdf}, fig4_fpe.{png,pdf}, fig5_tpa.{png,pdf},
fig7_ablation.{png,pdf}, fig_learning_curves.{png,pdf} and report.md (+ report.html). Reads only
the file: /tables/*, /runs/... and /datasets/... . Every figure plots what the file holds (which
cells belong to Fig. 5 or Fig. 7 is a column of /tables/tpa), never a re-reading of the profile.
A partial file (an interrupted run) plots with gaps and notes, never zeros.
"""
import argparse
import html
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from scipy import stats  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
# The reader package: installed by scripts/setup.sh, or beside this folder in a checkout.
sys.path.insert(1, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import claims as claims_stats  # noqa: E402
import sirl_bench  # noqa: E402
import plot_beyond  # noqa: E402
import plot_hyper  # noqa: E402

# One colour and one label per method variant, shared by every figure.
STYLE = {
    "sirl": ("#d62728", "SIRL"),
    "sirl+vae": ("#ff9896", "SIRL+VAE"),
    "vae": ("#2ca02c", "VAE"),
    "multipref10": ("#1f77b4", "MultiPref-10"),
    "multipref50": ("#17becf", "MultiPref-50"),
    "singlepref": ("#9467bd", "SinglePref"),
    "random": ("#7f7f7f", "Random"),
}
ORDER = list(STYLE)
# Methods evaluated from outside the engine (`sirl evaluate`: method "external", the variant is
# the name the user gave), drawn after the built-in ones in these colours.
EXTERNAL_COLOURS = ["#8c564b", "#e377c2", "#bcbd22", "#000000", "#ff7f0e", "#aec7e8"]


def add_external_styles(t):
    """Gives every external method of the file a colour and its own name as label."""
    names = []
    for k in ("fpe", "tpa"):
        d = t.get(k)
        if d is not None and not d.empty and "method" in d:
            names += [v for v in d[d.method == "external"].variant.unique() if v not in names]
    for i, v in enumerate(sorted(names)):
        if v not in STYLE:
            STYLE[v] = (EXTERNAL_COLOURS[i % len(EXTERNAL_COLOURS)], v)
            ORDER.append(v)
    return sorted(names)
# Each environment's registration as the run stored it (attributes of /datasets/<env>: title,
# in_claims, fig3_rank, vae_weak_claim, view), so no environment name is spelled out here.
ENV = {}
ALPHA = claims_stats.ALPHA


def load_envs(res):
    for name, g in res.datasets.items():
        a = g["attrs"]
        ENV[name] = {"title": a.get("title", name), "in_claims": int(a.get("in_claims", 1)),
                     "fig3_rank": int(a.get("fig3_rank", 0)),
                     "vae_weak_claim": int(a.get("vae_weak_claim", 0))}


def env_title(env):
    return ENV.get(env, {}).get("title", env)


# What each figure drew, written to figures.json beside them (tests and users check it).
DRAWN = {}


TABLES = ("fpe", "tpa", "timings", "training", "vae_latents", "robust_fpe", "robust_tpa")


def load(path):
    """The file through sirl_bench (typed tables; N and M are <NA> where a cell has none). The
    cell tables hold the base point of any hyper-parameter axis only (the paper's figures and
    claims); every point's rows are in t["all_points"]."""
    res = sirl_bench.open(path)
    t = {k: res.tables[k] if k in res.tables else pd.DataFrame() for k in TABLES}
    t["all_points"] = {k: t[k] for k in ("fpe", "tpa")}
    for k in ("fpe", "tpa", "training", "robust_fpe", "robust_tpa"):
        if "hyper_point" in t[k]:
            t[k] = t[k][t[k].hyper_point == ""]
    return res, t


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
        fig.savefig(os.path.join(out, f"{name}.{ext}"), dpi=150, bbox_inches="tight")
    plt.close(fig)


def main_tpa(tpa):
    """Fig. 5's cells (the file marks them: in_main), each method in the paper's best mode (SIRL
    frozen, the others unfrozen)."""
    if tpa.empty:
        return tpa
    t = tpa[tpa["in_main"]] if "in_main" in tpa else tpa
    # best_mode: the file's (engines ≥ 0.8.0); older files have no such column
    return t[t["best_mode"]] if "best_mode" in t else t.iloc[0:0]


def fpe_dots(ax, d, env, Ns):
    """Fig. 4's panel for an environment run at one N: each method's mean FPE as a dot with its
    95 % CI, methods along the x-axis (an N axis with one point would read as a curve)."""
    variants = [v for v in ORDER if (d.variant == v).any()]
    for i, v in enumerate(variants):
        colour, label = STYLE[v]
        m, ci = mean_ci(d[d.variant == v].fpe)
        DRAWN.setdefault("fig4", {}).setdefault(env, {})[v] = {
            str(Ns[0]) if Ns and d[d.variant == v].N.notna().all() else "0": float(m)}
        ax.errorbar([i], [m], yerr=[ci if np.isfinite(ci) else 0], fmt="o", color=colour,
                    capsize=3, ms=6, label=label)
    ax.set_xticks(range(len(variants)))
    ax.set_xticklabels([STYLE[v][1] for v in variants], rotation=35, ha="right", fontsize=8)
    ax.set_xlim(-0.6, len(variants) - 0.4)
    ax.set_title(f"{env_title(env)}" + (f", N = {Ns[0]}" if Ns else ""))
    ax.set_ylim(bottom=0)
    ax.set_ylabel("FPE (test MSE, normalised features)")
    ax.grid(alpha=0.3, axis="y")


def plot_fig4(fpe, envs, out, notes):
    envs = [e for e in envs if not fpe.empty and (fpe.env == e).any()]
    if not envs:
        notes.append("Fig. 4: no FPE cells in this file")
        return
    fig, axes = plt.subplots(1, len(envs), figsize=(5.2 * len(envs), 3.8), squeeze=False,
                             constrained_layout=True)
    for ax, env in zip(axes[0], envs):
        d = fpe[fpe.env == env]
        Ns = sorted(int(n) for n in d.N.dropna().unique())
        if len(Ns) <= 1:  # one N (the simplified GridRobot): a dot per method, not a curve
            fpe_dots(ax, d, env, Ns)
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
        ax.set_title(env_title(env))
        ax.set_ylim(bottom=0)  # an MSE: CI bands of few seeds may dip below 0
        ax.set_xlabel("representation queries N")
        ax.set_ylabel("FPE (test MSE, normalised features)")
        ax.grid(alpha=0.3)
    axes[0][-1].legend(fontsize=8, loc="upper right")
    fig.suptitle("Fig. 4: feature prediction error (mean ± 95 % CI over seeds)", fontsize=11)
    save(fig, out, "fig4_fpe")


def plot_fig5(tpa, envs, out, notes):
    t = main_tpa(tpa)
    envs = [e for e in envs if (t.env == e).any()] if not t.empty else []
    if not envs:
        notes.append("Fig. 5: no TPA cells of the main grid in this file")
        return
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
                DRAWN.setdefault("fig5", {}).setdefault(env, {}).setdefault(str(n), {})[v] = {
                    str(m): float(x) for m, x in zip(Ms, ms) if np.isfinite(x)}
                if np.isnan(ms).any():
                    notes.append(f"Fig. 5 {env_title(env)} N={n}: {label} missing at M = "
                                 f"{[m for m, x in zip(Ms, ms) if np.isnan(x)]} (gaps)")
                ax.plot(Ms, ms, "o-", color=colour, label=label, ms=4)
                ok = np.isfinite(cis)
                ax.fill_between(np.array(Ms)[ok], (ms - cis)[ok], (ms + cis)[ok], color=colour,
                                alpha=0.15)
            ax.set_title(f"{env_title(env)}, N = {n}")
            ax.set_ylim(0.35, 1.0)
            ax.set_xlabel("preference queries per test reward M")
            if c == 0:
                ax.set_ylabel("TPA (held-out accuracy)")
            ax.grid(alpha=0.3)
    axes[0][-1].legend(fontsize=8, loc="lower right")
    frozen = "SIRL" + (" and external methods" if (t.method == "external").any() else "")
    fig.suptitle(f"Fig. 5: test preference accuracy ({frozen} frozen, others unfrozen; "
                 "mean ± 95 % CI)",
                 fontsize=11)
    save(fig, out, "fig5_tpa")


def plot_fig7(tpa, envs, out, notes):
    """Fig. 7 from the cells the file marks as the ablation's (in_ablation), per environment."""
    ab = tpa[tpa["in_ablation"]] if not tpa.empty and "in_ablation" in tpa else tpa.iloc[0:0]
    envs = [e for e in envs if (ab.env == e).any()]
    if not envs:
        notes.append("Fig. 7: no ablation cells in this file")
        return
    fig, axes = plt.subplots(1, len(envs), figsize=(7 * len(envs), 3.8), squeeze=False,
                             constrained_layout=True)
    bases = [b for b in ["sirl", "vae", "multipref10", "multipref50", "singlepref", "random"]
             if b in set(ab.method)]
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
                    applicable = vae == 0 or b not in ("vae", "random")
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


def convergence_lines(t):
    """One line per (environment, kind, variant): how many of its trainings converged."""
    tr = t["training"]
    if tr.empty:
        return []
    L = ["", "## Did every training converge?", "",
         "Converged: the mean loss over the last 10 % of the epochs differs from the 10 % before "
         "by less than 1 % (+1e-4 absolute); a TPA cell counts when all of its heads did. "
         "Per-task values: /tables/training.", "",
         "| env | training | variant | epochs | converged | median Δ over the last 10 % |",
         "|---|---|---|---:|---:|---:|"]
    if "teacher" in tr:  # the [robustness] cells' trainings, one line per method
        tr = tr.assign(variant=tr.variant.where(tr.teacher == "", tr.variant + " (noisy teachers)"))
    for (env, kind, v), d in tr.groupby(["env", "kind", "variant"]):
        L.append(f"| {env} | {kind} | {v} | {int(d.epochs.median())} | {int(d.converged.sum())} of "
                 f"{len(d)} | {100 * d.loss_relative_change.median():+.2f} % |")
    return L


def vae_lines(res, t):
    """The VAE's posterior (per-latent KL) and how alive each φ's last hidden layer is."""
    vl = t["vae_latents"]
    L = []
    if not vl.empty:
        L += ["", "## The VAE's posterior", "",
              "A latent dimension with KL < 0.01 nats carries no information about the trajectory "
              "(posterior collapse). Per dimension: /tables/vae_latents.", "",
              "| env | seed | ELBO form | active latents (KL > 0.01) | KL per latent (nats) | "
              "reconstruction MSE |", "|---|---:|---|---:|---|---:|"]
        for (env, seed), d in vl.groupby(["env", "seed"]):
            kl = d.sort_values("dim").kl.values
            L.append(f"| {env} | {seed} | {d.elbo.iloc[0]} | {(kl > 0.01).sum()} of {len(kl)} | "
                     f"{', '.join(f'{x:.3g}' for x in kl)} | {d.reconstruction_mse.iloc[0]:.4g} |")
    dead = []
    recs = res.records
    if not recs.empty and "variant" in recs:
        reps = recs[(recs.kind == "rep") & recs.arrays.str.split(",").map(lambda a: "dead_fraction" in a)]
        for row in reps.itertuples():
            df = res.array(row.key, "dead_fraction")
            dead.append((row.env, row.variant, float(df[-1]) if len(df) else 0.0))
    if dead:
        d = pd.DataFrame(dead, columns=["env", "variant", "dead"])
        L += ["", "## Dead units", "",
              "Share of φ's last hidden layer that is 0 on every trajectory of Ξ (a φ whose layer "
              "is all dead is a constant map: no head on it can learn, frozen or not).", "",
              "| env | variant | representations | median dead share | max |", "|---|---|---:|---:|---:|"]
        for (env, v), x in d.groupby(["env", "variant"]):
            L.append(f"| {env} | {v} | {len(x)} | {x.dead.median():.2f} | {x.dead.max():.2f} |")
    return L


def fmt(x, spec=".4f"):
    return "—" if x is None or (isinstance(x, float) and not math.isfinite(x)) else format(x, spec)


def comparison_text(c):
    name = c["name"]
    label = ("vs " + STYLE[name][1]) if name in STYLE else name
    return (f"{label}: Δ = {fmt(c['diff'], '+.4f')} [{fmt(c['lo'], '+.4f')}, {fmt(c['hi'], '+.4f')}], "
            f"d_z = {fmt(c['dz'], '+.2f')}, p = {fmt(c['p'], '.3g')}"
            f"{' (every seed differs by the same amount: exact sign test)' if c.get('test') == 'sign' else ''}"
            f", Holm p = {fmt(c.get('p_holm'), '.3g')} "
            f"(n = {c['n']})")


def claim(claims, env, name, comparisons, better, main=False, trainings=None):
    """Decides one hypothesis (claims.decide) and keeps it for the summary and the details;
    `trainings`: the /tables/training rows its numbers rest on (for the converged count)."""
    v, deciding = claims_stats.decide(comparisons, better)
    h = {"env": env, "claim": name, "better": better, "comparisons": comparisons, "verdict": v,
         "deciding": deciding, "main": main}
    if trainings is not None and not trainings.empty:
        h["converged"] = (int(trainings.converged.sum()), len(trainings))
    if comparisons:
        h["power"] = claims_stats.power(comparisons, better)
        h["seeds80"] = claims_stats.seeds_for_power(comparisons, better)
    claims.append(h)


def rested_on(tr, env, N, variants, tpa_cells):
    """The trainings behind a main claim at N: the compared methods' φ at N and the VAE, and for
    a TPA claim their TPA cells of the main grid (SIRL frozen, the others unfrozen)."""
    if tr is None or tr.empty:
        return None
    t = tr[(tr.env == env) & (tr.teacher == "")] if "teacher" in tr else tr[tr.env == env]
    use = ((t.kind == "rep") & (t.N == N) & t.variant.isin(variants)) | (t.kind == "vae")
    if tpa_cells:
        use |= ((t.kind == "tpa") & ((t.N == N) | t.N.isna()) & t.variant.isin(variants)
                & t.best_mode).fillna(False)
    return t[use]


def hypotheses(fpe, tpa, envs, training=None):
    """Every claim the report checks, per environment, decided."""
    H = []
    baselines = ["vae", "multipref10", "multipref50", "singlepref", "random"]
    compared = ["sirl"] + baselines
    for env in envs:
        d = fpe[fpe.env == env]
        if not d.empty:
            nmax = d.N.max()

            def fpe_at(v):
                x = d[(d.variant == v) & ((d.N == nmax) | d.N.isna())]
                return x.set_index("seed").fpe

            claim(H, env, f"H1 — SIRL's FPE is lower than every baseline's at N = {nmax}",
                  [claims_stats.paired(v, fpe_at("sirl"), fpe_at(v)) for v in baselines
                   if (d.variant == v).any()], "<", main=True,
                  trainings=rested_on(training, env, nmax, compared, False))
        m = main_tpa(tpa[tpa.env == env])
        if not m.empty:
            nmax = m.N.max()

            def tpa_at(v):
                x = m[(m.variant == v) & ((m.N == nmax) | m.N.isna())]
                return x.groupby("seed").tpa.mean()

            claim(H, env, f"H2 — SIRL's TPA (frozen, mean over M) is higher than every baseline's "
                          f"(unfrozen) at N = {nmax}",
                  [claims_stats.paired(v, tpa_at("sirl"), tpa_at(v)) for v in baselines
                   if (m.variant == v).any()], ">", main=True,
                  trainings=rested_on(training, env, nmax, compared, True))
            claim(H, env, "Secondary — Random beats preference pre-training (TPA)",
                  [claims_stats.paired(v, tpa_at("random"), tpa_at(v))
                   for v in ["multipref10", "multipref50", "singlepref"] if (m.variant == v).any()],
                  ">")
        ab = tpa[(tpa.env == env) & (tpa.vae == 0)]
        for meth, text in [("sirl", "SIRL is better frozen"),
                           ("multipref10", "MultiPref-10 is better unfrozen"),
                           ("multipref50", "MultiPref-50 is better unfrozen"),
                           ("singlepref", "SinglePref is better unfrozen")]:
            x = ab[ab.method == meth]
            if x.frozen.nunique() < 2:
                continue
            keys = ["N", "M"]
            cells = x.groupby(keys).frozen.nunique()
            cells = cells[cells == 2].index
            x = x.set_index(keys).loc[cells].reset_index()
            fr = x[x.frozen == 1].groupby("seed").tpa.mean()
            un = x[x.frozen == 0].groupby("seed").tpa.mean()
            claim(H, env, f"Secondary — {text} (ablation cells, mean over N, M)",
                  [claims_stats.paired("frozen − unfrozen", fr, un)], ">" if meth == "sirl" else "<")
        if ENV.get(env, {}).get("vae_weak_claim"):
            x = fpe[(fpe.env == env)]
            if not x.empty and (x.variant == "vae").any():  # a profile may run no VAE FPE
                nmax = x.N.max()
                v = x[(x.variant == "vae")].set_index("seed").fpe
                s = x[(x.variant == "sirl") & (x.N == nmax)].set_index("seed").fpe
                claim(H, env, f"Secondary — VAE is weak on {env_title(env)} (FPE above SIRL's)",
                      [claims_stats.paired("vae", v, s)], ">")
    return H


def summary_lines(H):
    """The report's first table: one row per claim × environment."""
    L = ["| claim | environment | verdict | deciding comparison: Δ [95 % CI] | Holm p | seeds | "
         "power | seeds for 80 % | trainings converged |", "|---|---|---|---|---:|---:|---:|---:|---:|"]
    for h in H:
        c = h["deciding"]
        if c is None:
            L.append(f"| {h['claim']} | {env_title(h['env'])} | not evaluated (no data) | — | — | — | — | — | — |")
            continue
        conv = h.get("converged")
        conv_text = (f"{conv[0]} of {conv[1]}" + (" ⚠" if conv[0] < conv[1] else "")) if conv else "—"
        label = ("vs " + STYLE[c["name"]][1]) if c["name"] in STYLE else c["name"]
        s80 = h.get("seeds80")
        pw = h.get("power", math.nan)
        claim_text = f"**{h['claim']}**" if h["main"] else h["claim"]
        L.append(f"| {claim_text} | {env_title(h['env'])} | **{h['verdict']}** | {label}: "
                 f"{fmt(c['diff'], '+.4f')} [{fmt(c['lo'], '+.4f')}, {fmt(c['hi'], '+.4f')}] | "
                 f"{fmt(c.get('p_holm'), '.3g')} | {c['n']} | {fmt(100 * pw, '.0f') + ' %' if pw == pw else '—'} | "
                 f"{s80 if s80 else f'> {claims_stats.MAX_SEEDS}' if pw == pw else '—'} | "
                 f"{conv_text} |")
    L += ["", f"Verdicts: *held* = every comparison goes the claimed way with Holm-adjusted p < "
          f"{ALPHA} (paired t-tests over seeds, Holm's correction within each claim); *not held* = "
          f"at least one goes the other way with adjusted p < {ALPHA}; *inconclusive* otherwise. "
          f"The deciding comparison is the one the verdict rests on (for *held* the weakest). "
          f"*Power* = the chance that a run with this many seeds decides (held or not held) if the "
          f"true effects were the observed ones (simulated noncentral t, Holm applied); *seeds for "
          f"80 %* = the fewest seeds with power ≥ 80 %. Both are planning numbers computed from this "
          f"run's effect sizes, which few seeds estimate poorly: they are not evidence. "
          f"*Trainings converged* (main claims): of the trainings the claim's numbers rest on (the "
          f"compared methods' φ at that N and the VAEs, and for TPA their cells of Fig. 5), how "
          f"many met the convergence criterion of the table below; ⚠ marks a verdict resting on "
          f"trainings that were still learning."]
    return L


def detail_lines(H, envs):
    L = ["", "## The paper's claims in detail", ""]
    for env in envs:
        rows = [h for h in H if h["env"] == env]
        if not rows:
            continue
        L.append(f"### {env_title(env)}")
        for h in rows:
            if h["deciding"] is None:
                L.append(f"- **{h['claim']}**: not evaluated (no data)")
                continue
            L.append(f"- **{h['claim']}: {h['verdict']}** (paired t-test over seeds, α = {ALPHA}, "
                     f"Holm within the claim; Δ with its 95 % CI). "
                     + "; ".join(comparison_text(c) for c in h["comparisons"]))
        L.append("")
    if not any(ENV.get(e, {}).get("vae_weak_claim") for e in envs):
        L.append("- *VAE weak on JacoRobot*: not evaluated — this run has no JacoRobot cells.")
    return L


def compute_lines(res, tim):
    a = res.provenance
    if not len(tim):
        return []
    tim = tim.copy()
    tim["cores"] = tim["threads"] if "threads" in tim else 1  # files before engine 0.4.0: 1
    tim["core_seconds"] = tim.seconds * tim.cores
    by = tim.groupby("kind").agg(tasks=("key", "count"), seconds=("seconds", "sum"),
                                 core_seconds=("core_seconds", "sum"),
                                 wide=("cores", lambda x: int((x > 1).sum())),
                                 gflop=("flops", lambda x: x.sum() / 1e9))
    by["GFLOP/s"] = by.gflop / by.seconds.where(by.seconds > 0)
    by["per core"] = by.gflop / by.core_seconds.where(by.core_seconds > 0)
    roof = float(a.get("roof_fp32_gflops_per_core", 0) or 0)  # one core's, measured by the run
    roof_bf16 = float(a.get("roof_bf16_gflops_per_core", 0) or 0)  # bf16 runs with a bf16 unit
    # Each task's compute roof: that of its precision on its cores (a column from 2026-12-03 on;
    # before, the fp32 roof of its cores). A kind's share of a roof: the seconds its tasks would
    # take at their roofs over the seconds they took.
    if "compute_roof_gflops" in tim and (tim.compute_roof_gflops > 0).all():
        compute = tim.compute_roof_gflops
    else:
        compute = roof * tim.cores
    if roof:
        tim["compute_seconds"] = tim.flops / 1e9 / compute
        by["compute"] = tim.groupby("kind").compute_seconds.sum() / by.seconds.where(by.seconds > 0)
    # The relevant roof of each task: the lower of its compute roof and its memory roof (tasks that
    # stream their weights and Adam state; engines from 0.7.0 on).
    relevant = "memory_roof_gflops" in tim and roof > 0
    if relevant:
        limit = compute.where(tim.memory_roof_gflops <= 0,
                              np.minimum(compute, tim.memory_roof_gflops))
        tim["ideal_seconds"] = tim.flops / 1e9 / limit
        tim["streams"] = tim.memory_roof_gflops > 0
        rel = tim.groupby("kind").agg(ideal=("ideal_seconds", "sum"), streams=("streams", "sum"))
        by["relevant"] = rel.ideal / by.seconds.where(by.seconds > 0)
        by["streams"] = rel.streams
    L = ["", "## Compute by task kind (task-seconds, summed over tasks)", ""]
    if roof:
        L += [f"A task runs on one core, or on several when nothing else was ready or its chain "
              f"was critical (column "
              f"*on > 1 core*); this machine's fp32 roof is {roof:.0f} GFLOP/s per core (measured "
              "at the start of the run), and % of roof is the share of its cores' roof a kind "
              "held." + (f" Tasks whose products ran in bf16 are held to the bf16 unit's roof, "
                         f"{roof_bf16:.0f} GFLOP/s per core." if roof_bf16 else ""), ""]
    if relevant:
        L += ["Tasks whose weights and Adam state do not fit a core's share of the caches stream "
              "them from main memory every step (*memory-bound*, as the cost model counts bytes): "
              "their memory roof is their FLOPs per byte streamed times the bandwidth the run "
              "measured on one core (a STREAM triad). *% of the relevant roof* counts each task "
              "against the lower of its two roofs.", ""]
        L += ["| kind | tasks | on > 1 core | memory-bound | seconds | GFLOP | GFLOP/s | % of roof | "
              "% of the relevant roof |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    else:
        L += ["| kind | tasks | on > 1 core | seconds | GFLOP | GFLOP/s | % of roof |",
              "|---|---:|---:|---:|---:|---:|---:|"]
    for k, r in by.iterrows():
        pct = f"{100 * r.compute:.0f} %" if roof and r.compute == r.compute else "—"
        if relevant:
            rp = f"{100 * r.relevant:.0f} %" if r.relevant == r.relevant else "—"
            L.append(f"| {k} | {int(r.tasks)} | {int(r.wide)} | {int(r.streams)} | {r.seconds:.1f} | "
                     f"{r.gflop:.1f} | {r['GFLOP/s']:.1f} | {pct} | {rp} |")
        else:
            L.append(f"| {k} | {int(r.tasks)} | {int(r.wide)} | {r.seconds:.1f} | {r.gflop:.1f} | "
                     f"{r['GFLOP/s']:.1f} | {pct} |")
    return L


FIGURES = [("fig3_grid_similar", "Fig. 3"), ("fig4_fpe", "Fig. 4"), ("fig5_tpa", "Fig. 5"),
           ("fig7_ablation", "Fig. 7")]


def report(res, t, envs, out, notes, fig3_key, beyond=None):
    """report.md and report.html: the summary table of claims first, then the figures, the
    learning curves with their convergence table, the claims in detail, compute, diagnostics,
    notes, and the profile's text last."""
    fpe, tpa, tim = t["fpe"], t["tpa"], t["timings"]
    beyond = beyond or {}
    envs = [e for e in envs if ENV.get(e, {}).get("in_claims", 1)]  # e.g. Fig. 3's own env
    a = res.provenance
    H = hypotheses(fpe, tpa, envs, t.get("training"))
    title = f"sirl-bench report: profile `{a.get('profile_name')}`"
    L = [f"# {title}", ""] + summary_lines(H)
    L += ["", f"Engine {a.get('engine_version')} (commit {a.get('git_commit')}), host "
          f"{a.get('host')}, {a.get('threads')} threads; started {a.get('started')}, finished "
          f"{a.get('finished')}, wall time {float(a.get('wall_seconds', 0)):.0f} s; tasks: "
          f"{a.get('tasks_done')} of {a.get('tasks_total')} done"
          + ("." if a.get("complete") else " — **PARTIAL RUN**: figures show gaps.")]
    L += ["", "## Figures", ""]
    for name, cap in FIGURES:
        if os.path.exists(os.path.join(out, name + ".png")):
            L += [f"![{cap}]({name}.png)", ""]
    L += plot_beyond.active_lines(fpe, tim, beyond.get("active", []))
    L += plot_beyond.robustness_lines(fpe, tpa, t["robust_fpe"], t["robust_tpa"],
                                      beyond.get("robustness", []))
    L += external_lines(fpe, tpa, envs)
    L += beyond.get("hyper", [])
    L += ["", "## Learning curves and convergence", ""]
    if os.path.exists(os.path.join(out, "fig_learning_curves.png")):
        L += ["![Learning curves](fig_learning_curves.png)", ""]
    L += convergence_lines(t)
    L += detail_lines(H, envs)
    L += compute_lines(res, tim)
    L += vae_lines(res, t)
    if fig3_key:
        L += ["", f"Fig. 3 uses the representation `{fig3_key}`."]
    if notes:
        L += ["", "## Notes", ""] + [f"- {n}" for n in notes]
    prof = a.get("profile_text", "")
    if prof:
        L += ["", "## Configuration (the profile this file was run with)", "", "```toml",
              prof.strip(), "```"]
    L.append("")
    text = "\n".join(L)
    with open(os.path.join(out, "report.md"), "w") as fh:
        fh.write(text)
    with open(os.path.join(out, "report.html"), "w") as fh:
        fh.write(report_html(title, "\n".join(L[2:])))
    with open(os.path.join(out, "claims.json"), "w") as fh:
        json.dump(json_safe([{k: v for k, v in h.items() if k != "deciding"} for h in H]), fh,
                  indent=1)
    return text


def external_lines(fpe, tpa, envs):
    """Each external method next to SIRL, per environment: FPE at the largest N and TPA (Fig. 5's
    cells, mean over M) at the largest N, paired over seeds. Reported, not decided: these are not
    claims of the paper."""
    ext = sorted({v for d in (fpe, tpa) if not d.empty
                  for v in d[d.method == "external"].variant.unique()})
    if not ext:
        return []
    L = ["", "## Methods evaluated from outside the engine (`sirl evaluate`)", "",
         "Each method's embeddings of Ξ ran through the engine's own FPE and frozen TPA cells (the "
         "same rows, test rewards, pairs, M values, head initialisations and seeds as SIRL's), "
         "so the difference from SIRL is paired by seed: Δ = method − SIRL with its 95 % t "
         "interval and the two-sided paired t-test's p. No verdict: these are not claims of the "
         "paper.", "",
         "| env | method | metric | N | method | SIRL | Δ [95 % CI] | p | seeds |",
         "|---|---|---|---:|---:|---:|---|---:|---:|"]
    m = main_tpa(tpa)
    for env in envs:
        for v in ext:
            rows = []
            d = fpe[fpe.env == env] if not fpe.empty else fpe
            if not d.empty and (d.variant == v).any():
                N = d[d.variant == v].N.max()
                at = [d[(d.variant == x) & (d.N == N)].set_index("seed").fpe for x in (v, "sirl")]
                rows.append(("FPE (lower is better)", N, at))
            d = m[m.env == env] if not m.empty else m
            if not d.empty and (d.variant == v).any():
                N = d[d.variant == v].N.max()
                at = [d[(d.variant == x) & (d.N == N)].groupby("seed").tpa.mean()
                      for x in (v, "sirl")]
                rows.append(("TPA (frozen, mean over M)", N, at))
            for metric, N, (a, b) in rows:
                c = claims_stats.paired(v, a, b)
                L.append(f"| {env_title(env)} | {v} | {metric} | {N} | {fmt(a.mean())} | "
                         f"{fmt(b.mean())} | {fmt(c['diff'], '+.4f')} [{fmt(c['lo'], '+.4f')}, "
                         f"{fmt(c['hi'], '+.4f')}] | {fmt(c['p'], '.3g')} | {c['n']} |")
    return L


def json_safe(x):
    """Plain JSON: numpy scalars as Python numbers, nan/inf as null."""
    if isinstance(x, dict):
        return {k: json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_safe(v) for v in x]
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    return x


CSS = ("body{font-family:system-ui,sans-serif;max-width:1200px;margin:1em auto;padding:0 1em}"
       "table{border-collapse:collapse;margin:0.5em 0 1em}th,td{border:1px solid #bbb;"
       "padding:3px 7px;font-size:0.9em;vertical-align:top}th{background:#eee}"
       "caption{font-size:1.4em;font-weight:bold;text-align:left;padding:0.3em 0}"
       "img{max-width:100%}pre{background:#f6f6f6;padding:0.6em;overflow-x:auto}")


def report_html(title, body_md):
    """The report's Markdown as HTML (Debian's python3-markdown, tables + fenced code). The
    first element of the page is the summary table, its caption the report's title."""
    import markdown
    body = markdown.markdown(body_md, extensions=["tables", "fenced_code"])
    t = html.escape(title.replace("`", ""))
    body = body.replace("<table>", f'<table id="summary"><caption>{t}</caption>', 1)
    return (f"<!doctype html><html><head><meta charset='utf-8'><title>{t}</title>"
            f"<style>{CSS}</style></head><body>{body}</body></html>\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results", help="HDF5 results file written by `sirl run`")
    ap.add_argument("--out", required=True, help="directory for the figures and the report")
    a = ap.parse_args()
    if not os.path.exists(a.results):
        sys.exit(f"plot_figures: {a.results}: no such file")
    os.makedirs(a.out, exist_ok=True)
    try:
        res, t = load(a.results)
    except sirl_bench.ResultsError as e:
        sys.exit(f"plot_figures: {e}")
    load_envs(res)
    add_external_styles(t)
    envs = [e for e in ENV if any(not t[k].empty and (t[k].env == e).any()
                                  for k in ("fpe", "tpa", "training"))] or list(ENV)[:1]
    notes = []
    if not t["tpa"].empty and "best_mode" not in t["tpa"]:
        # Which cells are a method's best mode is a column the engine writes (from 0.8.0 on);
        # this file predates it, and the rule is not restated here.
        msg = ("this file was written by an engine before 0.8.0: its tables carry no best_mode "
               "column, so Fig. 5 and H2 are not drawn; `sirl merge NEW.h5 THIS.h5` rewrites its "
               "tables with the current engine")
        notes.append(msg)
        print(f"plot_figures: {msg}", file=sys.stderr)
    prov = res.provenance
    if not prov.get("complete", 1):
        notes.append(f"partial run: {prov.get('tasks_done')} of {prov.get('tasks_total')} "
                     "tasks; missing cells are gaps, not zeros")
    shard = prov.get("shard", "")
    if shard:
        notes.append(f"this file is shard {shard} of a run: missing cells are in the other shards "
                     "(combine them with `sirl merge`)")
    fig3_key = plot_fig3(res, a.out, notes)
    plot_fig4(t["fpe"], envs, a.out, notes)
    plot_fig5(t["tpa"], envs, a.out, notes)
    plot_fig7(t["tpa"], envs, a.out, notes)
    plot_learning_curves(res, t, envs, a.out, notes)
    beyond = {"active": plot_beyond.plot_active(t["fpe"], t["tpa"], a.out, notes, DRAWN),
              "robustness": plot_beyond.plot_robustness(t["fpe"], t["tpa"], t["robust_fpe"],
                                                        t["robust_tpa"], a.out, notes, DRAWN)}
    beyond["hyper"] = plot_hyper.plot_hyper(t["all_points"]["fpe"], t["all_points"]["tpa"],
                                            res.hyper_points, STYLE, ORDER, mean_ci, save, a.out,
                                            notes, DRAWN)
    report(res, t, envs, a.out, notes, fig3_key, beyond)
    with open(os.path.join(a.out, "figures.json"), "w") as fh:
        json.dump(DRAWN, fh, indent=1)
    print(f"plot_figures: wrote figures and report.md to {a.out}/")


if __name__ == "__main__":
    main()
