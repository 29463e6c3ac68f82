"""The statistics behind the report's verdicts: paired comparisons over seeds, Holm's correction
within a hypothesis, effect sizes with 95 % confidence intervals, and the power of a verdict.

A hypothesis ("SIRL's FPE is lower than every baseline's") is a list of paired comparisons over
seeds, each a difference claimed-better − other. Its verdict:
  held          every comparison goes the claimed way with Holm-adjusted p < α;
  not held      at least one goes the other way with Holm-adjusted p < α;
  inconclusive  otherwise.
Power is the probability that a run with n seeds *decides* (held or not held) if the true
per-seed effects were the observed ones (d_z = mean / sd of the per-seed differences), by
simulation of each comparison's t statistic (noncentral t, comparisons taken as independent).
It is a planning number for the next run, not evidence: with 2–3 seeds d_z itself is very
uncertain. Pure numpy/scipy; no file access.
"""
import functools
import math

import numpy as np
import pandas as pd
from scipy import stats

ALPHA = 0.05
POWER_TARGET = 0.8
POWER_DRAWS = 4000  # simulated runs per power value; ±0.6 % standard error at power 0.8
MAX_SEEDS = 64      # "seeds for 80 %" searches n = 2 … MAX_SEEDS


def paired(name, a, b):
    """Paired comparison of a − b over the seeds both have (a, b: Series indexed by seed).
    Returns a dict: name, n, diff (mean), lo/hi (its 95 % t interval), p (two-sided paired t),
    dz (mean / sd of the differences), test ("t", or "sign" below).

    When every seed differs by exactly the same amount the t statistic is not defined (0 / 0 or
    x / 0). That happens with discrete metrics when a method's outputs do not depend on the seed
    (TPA heads that did not learn predict one label, whose accuracy is then the test pairs'
    label balance), so it is no evidence of an effect. The comparison then falls back to the
    exact two-sided sign test, p = 2 · 0.5ⁿ (1 for no difference), with no interval and no d_z
    (so no power either)."""
    j = pd.concat([a.rename("a"), b.rename("b")], axis=1).dropna()
    d = (j.a - j.b).to_numpy(dtype=float)
    n = len(d)
    c = {"name": name, "n": n, "diff": d.mean() if n else math.nan, "lo": math.nan,
         "hi": math.nan, "p": math.nan, "dz": math.nan, "test": "t"}
    if n < 2:
        return c
    sd = d.std(ddof=1)
    if sd == 0 or sd < 1e-12 * max(1.0, abs(d.mean())):
        c.update(test="sign", p=min(1.0, 2 * 0.5 ** n) if d.mean() != 0 else 1.0)
        return c
    half = stats.t.ppf(0.975, n - 1) * sd / math.sqrt(n)
    t = d.mean() / (sd / math.sqrt(n))
    c.update(lo=d.mean() - half, hi=d.mean() + half, p=2 * stats.t.sf(abs(t), n - 1),
             dz=d.mean() / sd)
    return c


def holm(ps):
    """Holm–Bonferroni adjusted p-values (same order as ps; nan stays nan)."""
    ps = np.asarray(ps, dtype=float)
    out = np.full(len(ps), np.nan)
    ok = np.flatnonzero(np.isfinite(ps))
    m = len(ok)
    order = ok[np.argsort(ps[ok], kind="stable")]
    running = 0.0
    for rank, i in enumerate(order):
        running = max(running, min(1.0, (m - rank) * ps[i]))
        out[i] = running
    return out


def _goes_claimed_way(diff, better):
    return diff < 0 if better == "<" else diff > 0


def decide(comparisons, better, alpha=ALPHA, adjusted=False):
    """Adds 'p_holm' to every comparison and returns (verdict, deciding comparison); with
    `adjusted`, the comparisons' 'p_holm' is already set (Holm over a larger family) and kept.
    The deciding comparison is the one the verdict rests on: for *held* the weakest (largest
    adjusted p), for *not held* the strongest against the claim, for *inconclusive* the weakest
    of those going the claimed way (or the first, if none does)."""
    if not comparisons:
        return "not evaluated", None
    if not adjusted:
        for c, q in zip(comparisons, holm([c["p"] for c in comparisons])):
            c["p_holm"] = q
    sig = [c for c in comparisons if np.isfinite(c["p_holm"]) and c["p_holm"] < alpha]
    good = [c for c in sig if _goes_claimed_way(c["diff"], better)]
    bad = [c for c in sig if not _goes_claimed_way(c["diff"], better) and c["diff"] != 0]
    key = lambda c: c["p_holm"] if np.isfinite(c["p_holm"]) else 2.0  # noqa: E731
    if len(good) == len(comparisons):
        return "held", max(comparisons, key=key)
    if bad:
        return "not held", min(bad, key=key)
    ways = [c for c in comparisons if _goes_claimed_way(c["diff"], better)]
    return "inconclusive", max(ways, key=key) if ways else comparisons[0]


@functools.lru_cache(maxsize=4096)
def _simulated_decisions(dzs, n, better, alpha):
    """Fraction of POWER_DRAWS simulated runs with n seeds whose Holm verdict is held or not held,
    each comparison's t drawn from a noncentral t with df n − 1 and noncentrality d_z √n (dzs: a
    tuple). The draws are seeded by n alone, so a value depends only on the arguments and is kept:
    a report asks for the same comparisons' power in its claims and in its ledger."""
    rng = np.random.default_rng(20230313 + n)
    df = n - 1
    m = len(dzs)
    dz = np.clip(np.asarray(dzs, dtype=float), -1e3, 1e3)  # a tiny spread: a huge d_z
    z = rng.standard_normal((POWER_DRAWS, m)) + dz * math.sqrt(n)
    t = z / np.sqrt(rng.chisquare(df, (POWER_DRAWS, m)) / df)  # (POWER_DRAWS, m)
    # Holm, vectorised over draws and done on |t| (every comparison of a draw has df n − 1): the
    # comparison with the k-th largest |t| (k = 0 …) is significant when it and every larger one
    # exceed the two-sided critical value at α / (m − k). That is "Holm-adjusted p < α" without a
    # p-value per draw (the t distribution's tail function was most of a report's claims time).
    crit = stats.t.isf(alpha / (2.0 * (m - np.arange(m))), df)  # (m,), growing with k
    order = np.argsort(-np.abs(t), axis=1, kind="stable")
    sig_sorted = np.logical_and.accumulate(np.take_along_axis(np.abs(t), order, axis=1) > crit,
                                           axis=1)
    sig = np.empty_like(sig_sorted)
    np.put_along_axis(sig, order, sig_sorted, axis=1)
    claimed = t < 0 if better == "<" else t > 0
    held = (sig & claimed).all(axis=1)
    not_held = (sig & ~claimed).any(axis=1)
    return float((held | not_held).mean())


def power(comparisons, better, n=None, alpha=ALPHA):
    """Power to decide with n seeds (default: the seeds the comparisons had), at the observed
    d_z's. nan when an effect size is unknown (fewer than 2 seeds)."""
    dzs = [c["dz"] for c in comparisons]
    n = n if n is not None else min((c["n"] for c in comparisons), default=0)
    if n < 2 or not dzs or not all(np.isfinite(d) for d in dzs):
        return math.nan
    return _simulated_decisions(tuple(float(d) for d in dzs), n, better, alpha)


def seeds_for_power(comparisons, better, target=POWER_TARGET, alpha=ALPHA):
    """The smallest seed count (2 … MAX_SEEDS) whose power reaches target; None if none does."""
    if not comparisons or any(not np.isfinite(c["dz"]) for c in comparisons):
        return None
    for n in range(2, MAX_SEEDS + 1):
        if power(comparisons, better, n, alpha) >= target:
            return n
    return None
