#!/usr/bin/python3
"""report/claims.py against hand-computed cases and closed forms: the paired t-test and its CI
(df = 2 has a closed-form t distribution), Holm's adjusted p-values, the verdict rules, and the
simulated power against scipy's noncentral-t power for one comparison."""
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
print("ok: simulated power equals the noncentral-t closed form; seeds for 80 % as well")
print("PASS")
