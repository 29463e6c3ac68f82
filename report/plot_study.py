#!/usr/bin/python3
"""Fig. 6 and the report lines for H3/H4 from a study analysis: `sirl study analyze`'s
study_analysis.h5, or a results file whose profile ran the study (its /tables/study).

    /usr/bin/python3 report/plot_study.py DIR/study_analysis.h5 --out DIR
    /usr/bin/python3 report/plot_study.py out/quick.h5 --out out/quick-figures/study

FPE: SIRL vs Random over training seeds, two-sided t-test (H3). TPA: Real, Held-out and
Simulated, each with a one-way ANOVA with method as the factor (H4), also restricted to the
participants whose preference involves every feature.
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
matplotlib.rcParams["text.parse_math"] = False  # labels from the file are text, never TeX
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

# The reader package: installed by scripts/setup.sh, or beside this folder in a checkout.
sys.path.insert(1, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_bench  # noqa: E402
from figures import STUDY_COLOURS, better_note, chance_line  # noqa: E402
from safe_output import save_figure, write_text  # noqa: E402

# The colours of every figure (figures.py's palette): SIRL red, Random orange.
SIRL, RANDOM = STUDY_COLOURS["sirl"], STUDY_COLOURS["random"]

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("analysis")
ap.add_argument("--out", required=True)
ap.add_argument("--study-file", help="the study file the answers are in, when the analysis is a "
                "results file's (sirl reproduce writes the simulated cohort's beside the figure)")
a = ap.parse_args()
try:
    g = sirl_bench.study_analysis(a.analysis)
except sirl_bench.ResultsError as e:
    sys.exit(f"plot_study: {e}")
v = {k: g[k] for k in ("fpe_sirl", "fpe_random", "real_sirl", "real_random", "heldout_sirl",
                       "heldout_random", "simulated_sirl", "simulated_random",
                       "real_random_other", "heldout_random_other", "simulated_random_other")
     if k in g}
both = g["both_features"].astype(bool)
attrs = g["attrs"]
if a.study_file:
    attrs["study_file"] = a.study_file
MODE = attrs.get("random_mode", "frozen")  # files of older engines evaluated Random frozen
OTHER = "frozen" if MODE == "unfrozen" else "unfrozen"


def simulated_participants(analysis, attrs, ids):
    """How many of the analysed participants (ids) are simulated, or None when that cannot be
    told. A results file's study (/tables/study, no /study_analysis) is always the profile's
    simulated cohort ([study]); a study file keeps a simulated participant's true reward
    (/study/participants/<id>/reward: `sirl study simulate`), never a person's (served or
    imported); without the study file, the ids `sirl study simulate` gives (sim01, sim02, …)."""
    import re
    import h5py
    try:
        with h5py.File(analysis, "r") as f:
            if "study_analysis" not in f:
                return len(ids)  # a results file: its profile's simulated cohort
    except OSError:
        pass
    path = str(attrs.get("study_file", ""))
    if path and os.path.isfile(path):
        try:
            with h5py.File(path, "r") as f:
                g = f["study/participants"]
                return sum(1 for i in ids if i in g and "reward" in g[i])
        except (OSError, KeyError):
            pass
    if ids and all(re.fullmatch(r"sim\d+", i) for i in ids):
        return len(ids)
    return None


IDS = [x.decode() if isinstance(x, bytes) else str(x) for x in g["participants"]]
P = len(IDS)
SIM = simulated_participants(a.analysis, attrs, IDS)
if SIM == P and P:
    WHO, COHORT = f"{P} simulated participants", "simulated novices"
    HEAD = "simulated novices (noisy simulated teachers), not real people"
elif SIM:
    WHO, COHORT = f"{P} participants ({SIM} simulated, {P - SIM} real)", "participants"
    HEAD = "participants, some of them simulated"
else:
    WHO, COHORT, HEAD = f"{P} participants", "participants", "participants"


def ci(x):
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    if len(x) < 2:
        return (x.mean() if len(x) else np.nan), np.nan
    return x.mean(), stats.t.ppf(0.975, len(x) - 1) * x.std(ddof=1) / np.sqrt(len(x))


def anova(s, r):
    s, r = np.asarray(s, float), np.asarray(r, float)
    s, r = s[np.isfinite(s)], r[np.isfinite(r)]
    if len(s) < 2 or len(r) < 2 or (np.ptp(np.r_[s, r]) == 0):
        return np.nan, np.nan, len(s) + len(r) - 2
    F, p = stats.f_oneway(s, r)
    return F, p, len(s) + len(r) - 2


def verdict(p, diff, better):
    if not np.isfinite(p):
        return "inconclusive"
    ok = diff < 0 if better == "<" else diff > 0
    return "held" if ok and p < 0.05 else ("not held" if (not ok and p < 0.05) else "inconclusive")


fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(10, 3.9), gridspec_kw={"width_ratios": [1, 3]},
                               constrained_layout=True)
for i, (key, col, lab) in enumerate([("fpe_sirl", SIRL, "SIRL"), ("fpe_random", RANDOM, "Random")]):
    m, h = ci(v[key])
    ax0.bar(i, m, yerr=0 if np.isnan(h) else h, color=col, label=lab, capsize=4)
ax0.set_xticks([0, 1])
ax0.set_xticklabels(["SIRL", "Random"])
ax0.set_ylabel(f"FPE (test MSE, normalised features)\n({better_note('fpe')})", fontsize=9)
ax0.set_title("FPE")
# The paper's three TPA measures (Real, Held-out, Simulated): with a simulated cohort its "Real"
# participants are simulated novices, and the tick says so; "Simulated" is the paper's perfect
# teacher on random rewards, whoever the cohort is.
if COHORT == "simulated novices":
    groups = [("Own answers (simulated novices; the paper's Real)", "real",
               "own answers\n(simulated novices)"),
              ("Held-out (simulated novices)", "heldout", "held-out φ\n(simulated novices)"),
              ("Simulated (perfect teacher, random rewards)", "simulated",
               "perfect teacher\n(random rewards)")]
else:
    groups = [("Real", "real", "Real\n(own answers)"), ("Held-out", "heldout", "Held-out φ"),
              ("Simulated", "simulated", "Simulated\n(perfect teacher, random rewards)")]
for j, (name, key, tick) in enumerate(groups):
    for k, (meth, col) in enumerate([("sirl", SIRL), ("random", RANDOM)]):
        m, h = ci(v[f"{key}_{meth}"])
        ax1.bar(j + (k - 0.5) * 0.35, m, 0.35, yerr=0 if np.isnan(h) else h, color=col, capsize=4,
                label=("SIRL (frozen)" if meth == "sirl" else f"Random ({MODE})") if j == 0 else None)
ax1.set_xticks(range(3))
ax1.set_xticklabels([gr[2] for gr in groups], fontsize=9)
ax1.set_ylim(0.4, 1.0)
chance_line(ax1, text=False, zorder=3)
ax1.set_ylabel(f"TPA (held-out accuracy)\n({better_note('tpa')})", fontsize=9)
ax1.set_title("TPA")
handles, labels = ax1.get_legend_handles_labels()
order = sorted(range(len(labels)), key=lambda i: labels[i].startswith("chance"))  # bars first
handles, labels = [handles[i] for i in order], [labels[i] for i in order]
fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=len(labels),
           fontsize=8, frameon=False)
fig.suptitle(f"Fig. 6: user study on {attrs.get('env')}: {HEAD}\n{WHO}, "
             f"{attrs.get('triplets')} similarity answers; mean ± 95 % CI", fontsize=10)
os.makedirs(a.out, exist_ok=True)
for ext in ("png", "pdf"):
    save_figure(fig, os.path.join(a.out, f"fig6_study.{ext}"), dpi=150, bbox_inches="tight")

L = ["# User study analysis", "",
     f"- study file `{attrs.get('study_file')}` ({attrs.get('env')}): {WHO} with preference "
     f"answers, {attrs.get('triplets')} pooled similarity answers",
     f"- SIRL {attrs.get('sirl_epochs')} epochs, {attrs.get('seeds')} training seeds; reward heads "
     f"{attrs.get('tpa_epochs')} epochs; {attrs.get('cv_splits')} cross-validation splits (70/30)",
     f"- SIRL is evaluated frozen (its best mode); Random **{MODE}** (the paper compares SIRL with "
     f"\"Random, the best performing realistic baseline\", unfrozen in its Fig. 5); Random {OTHER} "
     f"is reported below for comparison", "",
     "![Fig. 6](fig6_study.png)", ""]
t = stats.ttest_ind(v["fpe_sirl"], v["fpe_random"], equal_var=False)
d = v["fpe_sirl"].mean() - v["fpe_random"].mean()
L.append(f"- **H3 — SIRL's FPE is lower than Random's: {verdict(t.pvalue, d, '<')}** "
         f"(two-sided Welch t-test over {len(v['fpe_sirl'])} seeds: SIRL {v['fpe_sirl'].mean():.4f}, "
         f"Random {v['fpe_random'].mean():.4f}, t = {t.statistic:.3f}, p = {t.pvalue:.3g})")
for name, key, _ in groups:
    for subset, mask in [("all participants", None), ("participants whose preference involves every feature", both)]:
        if key == "simulated" and mask is not None:
            continue
        s, r = v[f"{key}_sirl"], v[f"{key}_random"]
        if mask is not None:
            if mask.sum() < 2:
                L.append(f"- {name}, {subset}: fewer than 2 such participants")
                continue
            s, r = s[mask], r[mask]
        F, p, df = anova(s, r)
        diff = np.nanmean(s) - np.nanmean(r)
        L.append(f"- **H4 — {name} TPA, {subset}: {verdict(p, diff, '>')}** (one-way ANOVA, method as "
                 f"the factor: F(1, {df}) = {F:.3f}, p = {p:.3g}; SIRL {np.nanmean(s):.3f}, Random "
                 f"{np.nanmean(r):.3f})")
if "real_random_other" in v:
    L += ["", f"### The same comparisons against Random {OTHER}", ""]
    for name, key, _ in groups:
        s, r = v[f"{key}_sirl"], v[f"{key}_random_other"]
        F, p, df = anova(s, r)
        diff = np.nanmean(s) - np.nanmean(r)
        L.append(f"- {name} TPA, all participants: {verdict(p, diff, '>')} (F(1, {df}) = {F:.3f}, "
                 f"p = {p:.3g}; SIRL {np.nanmean(s):.3f}, Random {OTHER} {np.nanmean(r):.3f}, "
                 f"Random {MODE} {np.nanmean(v[f'{key}_random']):.3f})")
L += ["", "Verdicts: *held* = the claimed direction with p < 0.05; *not held* = significant the "
      "other way; *inconclusive* otherwise.", ""]
write_text(os.path.join(a.out, "study_report.md"), "\n".join(L))
print(f"plot_study: wrote fig6_study.png/pdf and study_report.md to {a.out}/")
