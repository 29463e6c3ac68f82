#!/usr/bin/python3
"""report/ledger.py: the docs list and the code list are the same statements; verdicts on
synthetic tables against hand-computed tests (scipy's paired t and one-sided t, Holm by hand):
a family's Holm, TOST's equivalence and 'outside the margin', the study rows, and "not run"."""
import os
import re
import sys

import numpy as np
import pandas as pd
from scipy import stats

SRC = os.environ.get("SIRL_SOURCE_DIR", os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(SRC, "report"))
import ledger  # noqa: E402

# --- the docs list is the code list -----------------------------------------------------------
doc = open(os.path.join(SRC, "docs", "ledger.md")).read()
section = doc.split("## The statements")[1].split("## Statements the tables cannot check")[0]
doc_ids = re.findall(r"^\| ([SAU]\d\d) \|", section, re.M)
code_ids = [s.id for s in ledger.STATEMENTS]
assert doc_ids == code_ids, f"docs/ledger.md lists {doc_ids}, report/ledger.py {code_ids}"
for s in ledger.STATEMENTS:
    row = next(line for line in section.splitlines() if line.startswith(f"| {s.id} |"))
    assert s.section in row and s.paper in row, f"{s.id}: docs row differs from the code: {row}"

# --- synthetic tables: GridRobot, 6 seeds ---------------------------------------------------
rng = np.random.default_rng(7)
seeds = range(6)
VARIANTS = ["sirl", "sirl+vae", "vae", "multipref10", "multipref50", "singlepref", "random"]
fpe_mean = {"sirl": 0.010, "sirl+vae": 0.0102, "vae": 0.05, "multipref10": 0.030,
            "multipref50": 0.020, "singlepref": 0.040, "random": 0.045}
rows = []
for v in VARIANTS:
    for s in seeds:
        for N in ([100, 1000] if v not in ("vae", "random") else [None]):
            rows.append({"env": "grid", "variant": v, "method": v.replace("+vae", ""), "N": N,
                         "seed": s, "fpe": fpe_mean[v] + rng.normal(0, 0.001),
                         "reference": False})
fpe = pd.DataFrame(rows).astype({"N": "Int64"})
tpa = pd.DataFrame({"env": [], "variant": [], "N": [], "M": [], "seed": [], "tpa": []})

L = ledger.ledger(fpe, tpa, ["grid"])
by = {(r["id"], r["env"]): r for r in L}
# S01: SIRL below every baseline by ≥ 0.01 with sd 0.0014: confirmed. Holm over the family H1
# (S01's 5 comparisons and S02's 5) by hand.
fam = [r for r in L if r["family"] == "grid/H1"]
ps = [stats.ttest_rel(fpe[(fpe.variant == a) & (fpe.N.isna() | (fpe.N == 1000))].fpe.values,
                      fpe[(fpe.variant == b) & (fpe.N.isna() | (fpe.N == 1000))].fpe.values).pvalue
      for a in ("sirl", "sirl+vae") for b in ledger.BASELINES]
order = np.argsort(ps)
adj = np.empty(len(ps))
run = 0
for k, i in enumerate(order):
    run = max(run, min(1, (len(ps) - k) * ps[i]))
    adj[i] = run
got = [c["p_holm"] for r in fam for c in r["comparisons"]]
assert np.allclose(got, adj, rtol=1e-9), (got, adj)
assert by[("S01", "grid")]["verdict"] == "confirmed", by[("S01", "grid")]
# S05: the paper says MultiPref-50 is worse than Random; here it is 0.025 better: contradicted.
assert by[("S05", "grid")]["verdict"] == "contradicted", by[("S05", "grid")]
# S04: MultiPref-10 (0.030) is worse than MultiPref-50 (0.020): contradicted too.
assert by[("S04", "grid")]["verdict"] == "contradicted"
# S09: FPE falls with N? Both N have the same mean here: undecided, never confirmed.
assert by[("S09", "grid")]["verdict"] in ("undecided", "contradicted")
# S03: SIRL and SIRL+VAE 0.0002 apart with margin 0.005: equivalent. TOST by hand.
a = fpe[(fpe.variant == "sirl") & (fpe.N == 1000)].set_index("seed").fpe
b = fpe[(fpe.variant == "sirl+vae") & (fpe.N == 1000)].set_index("seed").fpe
d = (a - b).values
p_lo = stats.ttest_1samp(d, -0.005, alternative="greater").pvalue
p_hi = stats.ttest_1samp(d, 0.005, alternative="less").pvalue
c = by[("S03", "grid")]["comparisons"][0]
assert abs(c["p_equiv"] - max(p_lo, p_hi)) < 1e-9, (c["p_equiv"], p_lo, p_hi)
assert by[("S03", "grid")]["verdict"] == "confirmed"
# No TPA rows: every TPA statement is "not run", and JacoRobot's are absent.
assert by[("S15", "grid")]["verdict"] == "not run"
assert not any(r["env"] == "jaco" for r in L)

# --- an equivalence outside its margin is contradicted --------------------------------------
far = fpe.copy()
far.loc[far.variant == "sirl+vae", "fpe"] += 0.02
r = {x["id"]: x for x in ledger.ledger(far, tpa, ["grid"])}["S03"]
assert r["verdict"] == "contradicted", r

# --- TPA: Fig. 5's cells, mean over M; the ablation's per-method rows -----------------------
trows = []
for v in VARIANTS + ["truth"]:
    for s in seeds:
        for N in ([100, 1000] if v not in ("vae", "random", "truth") else [None]):
            for M in (10, 100):
                base = {"truth": 0.95, "sirl": 0.80}.get(v, 0.70)
                trows.append({"env": "grid", "variant": v, "method": v.replace("+vae", ""), "N": N,
                              "M": M, "seed": s, "tpa": base + 0.01 * (M == 100) + rng.normal(0, .005),
                              "protocol": "paper", "in_main": v != "truth", "best_mode": True,
                              "in_ablation": False, "frozen": v.startswith("sirl"),
                              "vae": v == "sirl+vae", "reference": v == "truth"})
for m in ["sirl", "multipref10", "vae"]:
    for s in seeds:
        for fr in (0, 1):
            for vae in (0, 1):
                good = (fr == 1) if m == "sirl" else (fr == 0)
                trows.append({"env": "grid", "variant": m + ("+vae" if vae else ""), "method": m,
                              "N": 1000, "M": 100, "seed": s,
                              "tpa": 0.6 + 0.1 * good + 0.05 * (m == "sirl") + rng.normal(0, .005),
                              "protocol": "paper",
                              "in_main": False, "best_mode": good, "in_ablation": True,
                              "frozen": bool(fr), "vae": bool(vae), "reference": False})
tpa = pd.DataFrame(trows).astype({"N": "Int64", "M": "Int64"})
by = {(r["id"], r["env"]): r for r in ledger.ledger(fpe, tpa, ["grid"])}
assert by[("S15", "grid")]["verdict"] == "confirmed", by[("S15", "grid")]["deciding"]
assert by[("S27", "grid")]["verdict"] == "confirmed"  # truth above SIRL
assert by[("S28", "grid")]["verdict"] == "confirmed"  # M = 100 above M = 10 by 0.01
assert by[("A01", "grid")]["verdict"] == "confirmed"  # SIRL frozen better
a02 = by[("A02", "grid")]
assert [c["name"] for c in a02["comparisons"]] == ["multipref10"], a02["comparisons"]
assert a02["verdict"] == "confirmed"
# A04: with and without VAE are equal here: undecided (never confirmed).
assert by[("A04", "grid")]["verdict"] in ("undecided", "contradicted")
# S17: each baseline's best configuration here (unfrozen) is 0.05 below SIRL frozen.
s17 = by[("S17", "grid")]
assert {c["config"].split(",")[0] for c in s17["comparisons"]} == {"unfrozen"}, s17
assert s17["after_data"] and s17["verdict"] == "confirmed"

# --- one N in the profile: a trend in N has nothing to compare ("not run", never a crash) -------
one_n = fpe[fpe.N.isna() | (fpe.N == 1000)]
by1 = {(r["id"], r["env"]): r for r in ledger.ledger(one_n, tpa[tpa.N.isna() | (tpa.N == 1000)], ["grid"])}
assert by1[("S09", "grid")]["verdict"] == "not run", by1[("S09", "grid")]
assert by1[("S10", "grid")]["verdict"] == "not run", by1[("S10", "grid")]
assert by1[("S01", "grid")]["verdict"] == "confirmed"

# --- the study rows: the paper's tests on the analysis' arrays -------------------------------
study = {"fpe_sirl": np.array([0.01, 0.012, 0.011]), "fpe_random": np.array([0.03, 0.028, 0.031]),
         "real_sirl": np.array([0.7, 0.72, 0.69, 0.71]), "real_random": np.array([0.7, 0.69, 0.72, 0.7])}
L = ledger.ledger(fpe, tpa, ["grid"], study)
st = {r["id"]: r for r in L if r["env"] == "study"}
assert st["U01"]["verdict"] == "confirmed"
p = stats.ttest_ind(study["fpe_sirl"], study["fpe_random"], equal_var=False).pvalue
assert abs(st["U01"]["deciding"]["p"] - p) < 1e-12
assert st["U02"]["verdict"] == "undecided"
assert abs(st["U02"]["deciding"]["p"] - stats.f_oneway(study["real_sirl"], study["real_random"]).pvalue) < 1e-12
assert st["U04"]["verdict"] == "not run"
text = "\n".join(ledger.lines(L, []))
assert "Paper says, we find" in text and "| U01 |" in text
print("ledger: ok")
