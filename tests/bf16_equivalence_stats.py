#!/usr/bin/python3
"""bench/bf16_equivalence.py's statistics and profile rewriting, against hand-worked cases:
the TOST p and 90 % CI against the closed-form Student t of 4 degrees of freedom
(F(t) = 1/2 + (3/4)·x·(1 − x²/3), x = t/√(4 + t²)), the degenerate cases, and the settings it
runs the profile with (name, seeds and precision, which sirl plan accepts)."""
import math
import os
import sys

sys.path.insert(0, os.path.join(os.environ["SIRL_SOURCE_DIR"], "bench"))
import bf16_equivalence as eq  # noqa: E402


def cdf4(t):
    x = t / math.sqrt(4 + t * t)
    return 0.5 + 0.75 * x * (1 - x * x / 3)


# Five paired differences: mean 0.004, sample sd √(Σ(d − 0.004)²/4).
d = [0.014, -0.006, 0.004, 0.024, -0.016]
mean = 0.004
sd = math.sqrt(sum((x - mean) ** 2 for x in d) / 4)  # = √(1e-4·(1+1+0+4+4)/4) = 0.0158114
se = sd / math.sqrt(5)
m, (lo, hi), p = eq.tost(d, 0.02)
assert abs(m - mean) < 1e-15, m
p_low = 1 - cdf4((mean + 0.02) / se)   # H0: mean ≤ −0.02
p_high = cdf4((mean - 0.02) / se)      # H0: mean ≥ +0.02
assert abs(p - max(p_low, p_high)) < 1e-9, (p, p_low, p_high)
assert p < 0.05, p  # inside the margin: equivalent
# The 90 % CI is mean ± t(0.95, 4)·se; t(0.95, 4) = 2.131847 solves F(t) = 0.95.
assert abs(cdf4((hi - mean) / se) - 0.95) < 1e-9 and abs((mean - lo) - (hi - mean)) < 1e-12
# A margin the CI crosses is not shown equivalent, and p says so.
m, (lo, hi), p = eq.tost(d, 0.01)
assert hi > 0.01 and p > 0.05, (hi, p)
# Identical runs (no network: Random's FPE) are equivalent; one seed cannot be judged.
assert eq.tost([0.0, 0.0, 0.0], 0.005)[2] == 0.0
assert eq.tost([0.01, 0.01, 0.01], 0.005)[2] == 1.0
assert math.isnan(eq.tost([0.001], 0.005)[2])

# The profile the tool runs: the base profile with name, seeds and precision set on top (sirl
# run --set), which sirl accepts: the plan has those seeds and the environment's own ones stay.
sets = eq.settings("bf16", 10, "mid-bf16")
assert sets == ['name="mid-bf16"', "seeds=[0, 1, 2, 3, 4, 5, 6, 7, 8, 9]", 'precision="bf16"'], sets
if os.environ.get("SIRL"):
    import subprocess
    cmd = [os.environ["SIRL"], "plan", os.path.join(os.environ["SIRL_SOURCE_DIR"], "bench",
                                                   "mid.toml")]
    for s in sets:
        cmd += ["--set", s]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    assert "profile mid-bf16 " in out and "seeds: 10" in out, out[:300]
print("ok: TOST p and CI match the closed-form t(4); degenerate cases; the profile settings")
