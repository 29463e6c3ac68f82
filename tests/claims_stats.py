#!/usr/bin/python3
"""report/claims.py against hand-computed cases and closed forms: the paired t-test and its CI
(df = 2 has a closed-form t distribution), Holm's adjusted p-values, the verdict rules, and the
simulated power against scipy's noncentral-t power for one comparison.

And report/hypotheses.py on synthetic tables (issue 56): the TPA claims are decided per protocol
("paper", "linear"); adding linear and reference (truth φ*, raw input) rows with wild values
leaves every FPE and paper-protocol claim bit for bit as it was; the linear claims rest on the
linear rows only; the references are never a baseline; a protocol a file lacks is "not run"; a
table of an older engine (no protocol or reference column) decides as before; the schema-1
fixture reads with the columns filled."""
import math
import os
import sys

import numpy as np
import pandas as pd
from scipy import stats

sys.path.insert(0, os.path.join(os.environ.get("SIRL_SOURCE_DIR", os.path.dirname(__file__) + "/.."),
                                "report"))
import claims  # noqa: E402


def close(a, b, tol, what):
    assert abs(a - b) <= tol, f"{what}: {a} vs {b} (tol {tol})"


# --- paired: differences 1, 2, 3 over three seeds (b has a seed a lacks: it is dropped) -------
a = pd.Series([1.0, 2.0, 3.0], index=[0, 1, 2])
b = pd.Series([0.0, 0.0, 0.0, 9.0], index=[0, 1, 2, 3])
c = claims.paired("x", a, b)
# mean 2, sd 1, t = 2√3; for df = 2 the t tail is sf(t) = (1 − t/√(t² + 2)) / 2 and the 97.5 %
# quantile is 0.95 / √(2 · 0.975 · 0.025).
t = 2 * math.sqrt(3)
assert c["n"] == 3, c
close(c["diff"], 2.0, 1e-12, "mean difference")
close(c["p"], 1 - t / math.sqrt(t * t + 2), 1e-9, "paired p (df 2 closed form)")
q = 0.95 / math.sqrt(2 * 0.975 * 0.025)
close(c["lo"], 2 - q / math.sqrt(3), 1e-9, "CI low")
close(c["hi"], 2 + q / math.sqrt(3), 1e-9, "CI high")
close(c["dz"], 2.0, 1e-12, "d_z = mean / sd")
# A sign error (b − a) or a population sd (ddof 0) would move diff, dz or p well past these tolerances.
c2 = claims.paired("x", b, a)
assert c2["diff"] == -2.0 and c2["dz"] == -2.0 and abs(c2["p"] - c["p"]) < 1e-12
one = claims.paired("x", pd.Series([1.0]), pd.Series([0.0]))
assert one["n"] == 1 and math.isnan(one["p"]) and math.isnan(one["dz"]), one
# Every seed differing by the same amount: no t statistic; the exact sign test (2 · 0.5ⁿ), no
# interval, no d_z, so no power. (It used to give p = 0: "not held" from 2 seeds of untrained
# heads whose accuracy did not depend on the seed.)
same = claims.paired("x", pd.Series([1.0, 2.0]), pd.Series([0.5, 1.5]))
assert same["test"] == "sign" and same["p"] == 0.5 and math.isnan(same["dz"]), same
assert math.isnan(same["lo"]) and math.isnan(same["hi"]), same
six = claims.paired("x", pd.Series(np.arange(6.0)), pd.Series(np.arange(6.0) + 0.25))
assert six["p"] == 2 * 0.5 ** 6 and six["diff"] == -0.25, six
zero = claims.paired("x", pd.Series([1.0, 2.0, 3.0]), pd.Series([1.0, 2.0, 3.0]))
assert zero["p"] == 1.0 and zero["diff"] == 0.0, zero
assert math.isnan(claims.power([same], ">")), "no d_z, no power"
assert claims.decide([dict(same)], ">")[0] == "inconclusive"
print("ok: paired t-test, CI and d_z equal the df = 2 closed forms")

# --- Holm ------------------------------------------------------------------------------------
# sorted 0.01, 0.03, 0.04 → ×3, ×2, ×1 = 0.03, 0.06, 0.04 → monotone 0.03, 0.06, 0.06
h = claims.holm([0.01, 0.04, 0.03])
assert np.allclose(h, [0.03, 0.06, 0.06]), h
h = claims.holm([0.5, float("nan"), 0.01])  # nan is not counted in m
assert np.allclose(h[[0, 2]], [0.5, 0.02]) and math.isnan(h[1]), h
assert np.allclose(claims.holm([0.6, 0.7]), [1.0, 1.0])  # capped at 1
print("ok: Holm's adjusted p-values by hand")


# --- decide ----------------------------------------------------------------------------------
def comp(name, diff, p, n=5, dz=1.0):
    return {"name": name, "diff": diff, "p": p, "n": n, "dz": dz, "lo": 0, "hi": 0}


v, d = claims.decide([comp("a", -1, 0.001), comp("b", -1, 0.02)], "<")
assert v == "held" and d["name"] == "b", (v, d)  # Holm: 0.002, 0.02 — both < 0.05
# Raw p's all below 0.05, but Holm's 0.003, 0.06, 0.06 are not: without the correction this
# would be *held*.
v, d = claims.decide([comp("a", -1, 0.001), comp("b", -1, 0.03), comp("c", -1, 0.04)], "<")
assert v == "inconclusive" and d["name"] in ("b", "c"), (v, d)
v, d = claims.decide([comp("a", -1, 0.001), comp("b", +1, 0.004)], "<")
assert v == "not held" and d["name"] == "b", (v, d)  # significant the other way
v, d = claims.decide([comp("a", +1, 0.001)], ">")
assert v == "held"
v, d = claims.decide([comp("a", +1, 0.2), comp("b", -1, 0.5)], ">")
assert v == "inconclusive" and d["name"] == "a", (v, d)
assert claims.decide([], "<") == ("not evaluated", None)
print("ok: verdict rules (held, not held, inconclusive; Holm makes a raw 'held' inconclusive)")


# --- power -----------------------------------------------------------------------------------
def exact_power(dz, n, alpha=0.05):
    """Two-sided one-sample t-test power at effect d_z with n seeds (scipy's noncentral t)."""
    df, nc = n - 1, dz * math.sqrt(n)
    if nc == 0:
        return alpha
    tc = stats.t.ppf(1 - alpha / 2, df)
    return stats.nct.sf(tc, df, nc) + stats.nct.cdf(-tc, df, nc)


# One comparison: the simulation (4000 draws, s.e. ≤ 0.008) must match the closed form to 0.03;
# a one-sided test, a wrong df (n instead of n − 1) or a missing √n would miss it by more.
for dz, n in [(1.0, 10), (0.5, 20), (2.0, 4), (0.0, 8), (-1.2, 6)]:
    got = claims.power([comp("a", dz, 0.5, n=n, dz=dz)], ">" if dz >= 0 else "<")
    close(got, exact_power(dz, n), 0.03, f"power d_z={dz} n={n}")
# seeds for 80 %: the closed form's smallest n, ±1 for the simulation's noise at the boundary.
for dz in (1.0, 0.7, 2.5):
    want = next(n for n in range(2, 200) if exact_power(dz, n) >= 0.8)
    got = claims.seeds_for_power([comp("a", dz, 0.5, n=3, dz=dz)], ">")
    assert got is not None and abs(got - want) <= 1, (dz, got, want)
assert claims.seeds_for_power([comp("a", 0.01, 0.5, n=3, dz=0.01)], ">") is None  # > MAX_SEEDS
# Two comparisons, one with no effect: a decision needs that one significant too (held) or a
# wrong-way significance (not held), so power stays near α however strong the other is.
p2 = claims.power([comp("a", 1, 0.01, n=6, dz=50.0), comp("b", 0, 0.9, n=6, dz=0.0)], ">")
assert p2 < 0.1, p2
assert math.isnan(claims.power([comp("a", 1, 0.5, n=1, dz=float("nan"))], ">"))
# A report asks for the same comparisons' power twice (claims and ledger): the second answer is
# the first, served from the cache, not simulated again.
hits = claims._simulated_decisions.cache_info().hits
again = claims.power([comp("a", 1.0, 0.5, n=10, dz=1.0)], ">")
assert again == claims.power([comp("b", 1.0, 0.7, n=10, dz=1.0)], ">"), "same d_z and n, same power"
assert claims._simulated_decisions.cache_info().hits >= hits + 2, claims._simulated_decisions.cache_info()
print("ok: simulated power equals the noncentral-t closed form; seeds for 80 % as well")


# --- the claims per TPA protocol, on synthetic tables (issue 56) -----------------------------
import hypotheses  # noqa: E402  (report/: figures, run_tables, sirl_bench)
import run_tables  # noqa: E402
import sirl_bench  # noqa: E402


import declared_methods  # noqa: E402  (tests/)

hypotheses.figures.load_styles(declared_methods.Declared)
SEEDS = range(6)
rng = np.random.default_rng(56)
BASE = {"sirl": 0.80, "vae": 0.62, "multipref10": 0.70, "multipref50": 0.72, "singlepref": 0.66,
        "random": 0.69}
NFREE = ("vae", "random")


def fpe_row(env, variant, N, seed, value, reference=False):
    return {"env": env, "method": variant, "variant": variant, "vae": variant == "vae",
            "N": N, "seed": seed, "fpe": value, "train_mse": value, "selection": "uniform",
            "teacher": "", "reference": reference}


def tpa_row(env, variant, N, M, seed, value, frozen, in_main, in_ablation, best_mode,
            protocol="paper", reference=False):
    return {"env": env, "method": variant, "variant": variant, "vae": variant == "vae",
            "frozen": frozen, "N": N, "M": M, "seed": seed, "tpa": value, "tpa_std": 0.01,
            "tpa_train": value, "in_main": in_main, "in_ablation": in_ablation,
            "selection": "uniform", "teacher": "", "best_mode": best_mode, "protocol": protocol,
            "reference": reference}


def typed_frames(fpe_rows, tpa_rows):
    """The rows as the reader types them (N, M Int64 with <NA>; flags boolean)."""
    out = []
    for rows in (fpe_rows, tpa_rows):
        d = pd.DataFrame(rows)
        for c in ("N", "M"):
            if c in d:
                d[c] = d[c].astype("Int64")
        for c in sirl_bench.FLAG_COLUMNS:
            if c in d:
                d[c] = d[c].astype("boolean")
        out.append(d)
    return out


def paper_tables(envs=("grid", "jaco")):
    """FPE and the paper's TPA cells: the main grid (SIRL frozen, the others unfrozen) and the
    ablation's other mode, with effects strong enough for decided verdicts and noise per seed."""
    F, T = [], []
    for env in envs:
        for s in SEEDS:
            for v, b in BASE.items():
                for N in ([None] if v in NFREE else [50, 100]):
                    F.append(fpe_row(env, v, N, s, 0.3 - (b - 0.6) + 0.01 * rng.standard_normal()))
                    for M in (10, 40):
                        x = b + 0.02 * rng.standard_normal() + (0.02 if M == 40 else 0)
                        T.append(tpa_row(env, v, N, M, s, x, v == "sirl", True, False, True))
                        if v not in NFREE:  # the ablation's other mode (not the best)
                            T.append(tpa_row(env, v, N, M, s, x - 0.05 if v == "sirl" else x + 0.01,
                                             v != "sirl", False, True, False))
    return typed_frames(F, T)


def with_new_rows(fpe, tpa, wild=True):
    """The tables plus the engine's new rows: linear-protocol cells of every method (frozen, best
    mode, main grid), and the references truth (paper and linear TPA, FPE) and raw (linear TPA,
    FPE), N <NA>. With `wild`, values that would flip every verdict if they leaked in: a truth
    reference far better than SIRL, linear cells where SIRL is the worst."""
    F, T = [], []
    for env in sorted(set(fpe.env)):
        for s in SEEDS:
            F.append(fpe_row(env, "truth", None, s, 0.0 + 1e-4 * s, reference=True))
            F.append(fpe_row(env, "raw", None, s, 0.001 * (s + 1) if wild else 0.5, reference=True))
            for M in (10, 40):
                T.append(tpa_row(env, "truth", None, M, s, 0.99 - 0.001 * s, True, True, False, True,
                                 "paper", True))
                for ref, x in (("truth", 1.0 - 0.002 * s), ("raw", 0.999 - 0.001 * s)):
                    T.append(tpa_row(env, ref, None, M, s, x, True, True, False, True, "linear",
                                     True))
                for v, b in BASE.items():
                    for N in ([None] if v in NFREE else [50, 100]):
                        x = (0.3 if v == "sirl" else 0.95) + 0.01 * rng.standard_normal()
                        T.append(tpa_row(env, v, N, M, s, x if wild else b, True, True, False,
                                         True, "linear"))
    f2, t2 = typed_frames(F, T)
    return (pd.concat([fpe, f2], ignore_index=True), pd.concat([tpa, t2], ignore_index=True))


def essence(h, across=False):
    """Everything a claim reports, comparable with ==; `across`: a claim whose Holm runs over
    several protocols, so its adjusted p and verdict are left out (checked by hand below)."""
    keys = ("env", "claim", "protocol", "main", "better") + (() if across else
                                                          ("verdict", "power", "seeds80"))
    out = {k: h.get(k) for k in keys}
    out["comparisons"] = [{k: c[k] for k in ("name", "n", "diff", "lo", "hi", "p", "dz", "test")
                           + (() if across else ("p_holm",))} for c in h["comparisons"]]
    return repr(out)  # nan == nan as text


run_tables.ENV.update({"grid": {"title": "GridRobot"},
                       "jaco": {"title": "JacoRobot", "vae_weak_claim": 1}})
envs = ["grid", "jaco"]
fpe, tpa = paper_tables()
before = hypotheses.hypotheses(fpe, tpa, envs)
# An older engine's tables: no protocol, no reference column. The same claims.
old = hypotheses.hypotheses(fpe.drop(columns="reference"), tpa.drop(columns=["protocol", "reference"]), envs)
paper_before = [h for h in before if h["protocol"] != "linear"]
assert [essence(h) for h in paper_before] == [essence(h) for h in old if h["protocol"] != "linear"]
verdicts = {(h["env"], h["claim"][:2], h["protocol"]): h["verdict"] for h in before}
assert verdicts[("grid", "H1", None)] == "held" and verdicts[("grid", "H2", "paper")] == "held", verdicts
assert verdicts[("grid", "H2", "linear")] == "not run", verdicts  # the file has no linear cells
fpe2, tpa2 = with_new_rows(fpe, tpa)
after = hypotheses.hypotheses(fpe2, tpa2, envs)
paper_after = [h for h in after if h["protocol"] != "linear"]
across = [bool(h.get("holm_across")) for h in paper_after]
assert [essence(h, x) for h, x in zip(paper_after, across)] == \
    [essence(h, x) for h, x in zip(paper_before, across)], \
    "adding linear and reference rows changed an FPE or paper-protocol claim"
# A TPA claim under both protocols is one claim: Holm over both protocols' comparisons, by hand.
assert sum(across) == 4, across  # H2 and Random-vs-preference, per environment
for env in envs:
    for fam in ("H2", "random-vs-preference"):
        hs = [h for h in after if h["env"] == env and h.get("family") == fam]
        assert [h["protocol"] for h in hs] == ["paper", "linear"], hs
        cs = [c for h in hs for c in h["comparisons"]]
        ps = np.array([c["p"] for c in cs])
        order, adj, run = np.argsort(ps, kind="stable"), np.empty(len(ps)), 0.0
        for k, i in enumerate(order):
            run = max(run, min(1.0, (len(ps) - k) * ps[i]))
            adj[i] = run
        for c, q in zip(cs, adj):
            close(c["p_holm"], q, 1e-12, f"{env} {fam}: Holm across protocols")
assert len(paper_after) == 2 * 7 + 1, [h["claim"] for h in paper_after]  # H1, H2, Random, 4 ablation; VAE weak
print(f"ok: {len(paper_after)} FPE and paper-protocol claims identical with wild linear and "
      "reference rows added, and on an older engine's tables (no protocol, no reference column)")

# The paper's protocol first: every FPE / paper row before the first linear row.
prot = [h["protocol"] or "fpe" for h in after]
assert prot.index("linear") == len(paper_after) and set(prot[len(paper_after):]) == {"linear"}, prot
# References are never a baseline (or the claimed method) of any claim.
names = {c["name"] for h in after for c in h["comparisons"]}
assert not names & {"truth", "raw"}, names

# The linear claims rest on the linear rows only: H2 recomputed by hand from them.
lin = tpa2[(tpa2.protocol == "linear") & ~tpa2.reference.astype(bool)]
for env in envs:
    h2 = next(h for h in after if h["env"] == env and h["protocol"] == "linear" and h["claim"].startswith("H2"))
    d = lin[lin.env == env]
    at = lambda v: d[(d.variant == v) & ((d.N == 100) | d.N.isna())].groupby("seed").tpa.mean()  # noqa: E731
    assert "N = 100" in h2["claim"] and h2["main"], h2["claim"]
    got = {c["name"]: c for c in h2["comparisons"]}
    assert sorted(got) == sorted(BASE.keys() - {"sirl"}), sorted(got)
    for v, c in got.items():
        t_ = stats.ttest_rel(at("sirl"), at(v))
        close(c["p"], t_.pvalue, 1e-12, f"{env} linear H2 vs {v}: p")
        close(c["diff"], (at("sirl") - at(v)).mean(), 1e-12, f"{env} linear H2 vs {v}: Δ")
    assert h2["verdict"] == "not held", h2["verdict"]  # SIRL's wild linear cells are the worst
    rnd = next(h for h in after if h["env"] == env and h["protocol"] == "linear" and "Random" in h["claim"])
    assert rnd["verdict"] in ("held", "not held", "inconclusive") and rnd["comparisons"], rnd
assert not any(h["protocol"] == "linear" and "ablation" in h["claim"] for h in after)
print("ok: the linear protocol's claims are decided from its rows only (H2 by hand: scipy's "
      "paired t), after every paper row; truth and raw are never a baseline")

# Only one protocol run: the other's claims are "not run", never a crash; no references at all.
only_linear = tpa2[tpa2.protocol == "linear"]
H = hypotheses.hypotheses(fpe, only_linear, envs)
v = {(h["env"], h["claim"][:2], h["protocol"]): h for h in H}
assert v[("grid", "H2", "paper")]["verdict"] == "not run" and v[("grid", "H2", "paper")]["deciding"] is None
assert v[("grid", "H2", "linear")]["verdict"] == "not held"
assert not any("ablation" in h["claim"] for h in H)
L = hypotheses.summary_lines(H)
assert L[0].startswith("| claim | environment | protocol | verdict |"), L[0]
assert any("| linear (secondary) | **not held**" in x for x in L) and \
    any("| paper (primary) | not run |" in x for x in L), L
assert any("| — | **held**" in x for x in L), "H1's protocol cell is —"
D = "\n".join(hypotheses.detail_lines(H, envs))
assert "[paper protocol]: not run" in D and "[linear protocol] (paired t-test" in D, D
no_tpa = hypotheses.hypotheses(fpe2, tpa2.iloc[0:0], envs)
assert all(h["protocol"] is None for h in no_tpa), [h["claim"] for h in no_tpa]  # FPE claims only
print("ok: a linear-only table: the paper's TPA claims 'not run', the linear ones decided; the "
      "summary table has a protocol column (— for FPE claims)")

# The schema-1 fixture (engine 0.1.0): the reader fills the columns it lacks.
SRC = os.environ.get("SIRL_SOURCE_DIR", os.path.dirname(__file__) + "/..")
with sirl_bench.open(os.path.join(SRC, "tests", "data", "results_v1.h5")) as r:
    t, f = r.tables["tpa"], r.tables["fpe"]
    assert list(t.protocol) == ["paper"] * len(t) and len(t), t
    assert str(t.reference.dtype) == "boolean" and not t.reference.any(), t.reference
    assert str(f.reference.dtype) == "boolean" and not f.reference.any() and "protocol" not in f
    assert "protocol" not in r.raw_table("tpa") and "reference" not in r.raw_table("tpa")
    assert [essence(h) for h in hypotheses.hypotheses(f, t, ["grid"])] == \
        [essence(h) for h in hypotheses.hypotheses(f.drop(columns="reference"),
                                                   t.drop(columns=["protocol", "reference"]), ["grid"])]
print("ok: the schema-1 fixture reads with protocol 'paper' and reference False filled in")
print("PASS")
