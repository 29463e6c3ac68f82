#!/usr/bin/python3
"""Does bf16 change the science? An equivalence test (TOST) of precision = "bf16" against fp32.

Runs one profile (default bench/mid.toml) twice over the same seeds (default 10: 0..9), once in
fp32 and once with every network's matrix products in bf16 (fp32 accumulation, master weights and
Adam state), then asks, per environment and method, whether the two give the same FPE and TPA:

  per seed, the method's mean FPE (over its N cells) and mean TPA (over its N × M × frozen cells);
  d = bf16 − fp32 per seed (paired: same seed, same queries, same initial weights);
  two one-sided t-tests at α = 0.05 against the margins ±0.005 (FPE) and ±0.02 (TPA):
  *equivalent* when the 90 % confidence interval of the mean d lies inside the margin.

The overall verdict needs every (env, method, metric) to be equivalent. That is an
intersection-union test: it needs no multiplicity correction (each part at α keeps the whole at α).

Both runs resume (`sirl run` skips committed tasks), so a killed run continues where it stopped.
Writes the two results files (each recording its resolved profile), and OUT/bf16-equivalence.{md,json}.

  /usr/bin/python3 bench/bf16_equivalence.py [--profile bench/mid.toml] [--seeds 10]
                                            [--threads 2] [--out out/bf16-equivalence]
"""
import argparse
import json
import math
import os
import subprocess
import sys

from scipy import stats

# The reader package: installed by scripts/setup.sh, or beside this folder in a checkout.
sys.path.insert(1, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import sirl_bench  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MARGINS = {"fpe": 0.005, "tpa": 0.02}
ALPHA = 0.05


def settings(precision, seeds, name):
    """What the tool sets on top of the profile (`sirl run --set`): its name, the top-level seeds
    (an environment's own seeds stay) and the precision of every network."""
    return [f'name="{name}"', f"seeds={list(range(seeds))}", f'precision="{precision}"']


def run(sirl, profile, sets, out, threads, extra=()):
    cmd = [sirl, "run", profile, "--out", out, "--threads", str(threads), *extra]
    for s in sets:
        cmd += ["--set", s]
    print("+", " ".join(cmd), flush=True)
    if subprocess.run(cmd).returncode != 0:  # sirl said why (e.g. another --seeds in that --out)
        sys.exit(f"bf16_equivalence: `{' '.join(cmd)}` failed")


def per_seed_means(path, kind):
    d = sirl_bench.open(path).tables[kind]
    return d.groupby(["env", "variant", "seed"])[kind].mean()


def tost(diffs, margin):
    """Mean, 90 % CI, TOST p (the larger of the two one-sided p) of paired differences."""
    n = len(diffs)
    mean = sum(diffs) / n
    sd = math.sqrt(sum((x - mean) ** 2 for x in diffs) / (n - 1)) if n > 1 else float("nan")
    if n < 2:
        return mean, (float("nan"), float("nan")), float("nan")
    if sd == 0:  # identical in every seed (e.g. no network in the method)
        return mean, (mean, mean), 0.0 if abs(mean) < margin else 1.0
    se = sd / math.sqrt(n)
    t95 = stats.t.ppf(1 - ALPHA, n - 1)
    p_low = stats.t.sf((mean + margin) / se, n - 1)  # H0: mean ≤ −margin
    p_high = stats.t.cdf((mean - margin) / se, n - 1)  # H0: mean ≥ +margin
    return mean, (mean - t95 * se, mean + t95 * se), max(p_low, p_high)


def compare(fp32_path, bf16_path):
    rows = []
    for kind, margin in MARGINS.items():
        a, b = per_seed_means(fp32_path, kind), per_seed_means(bf16_path, kind)
        if set(a.index) != set(b.index):
            sys.exit(f"bf16_equivalence: the two runs' {kind} cells differ")
        for (env, variant), _ in a.groupby(level=[0, 1]):
            seeds = sorted(a.loc[(env, variant)].index)
            diffs = [float(b.loc[(env, variant, s)] - a.loc[(env, variant, s)]) for s in seeds]
            mean, ci, p = tost(diffs, margin)
            rows.append({
                "metric": kind, "env": env, "method": variant, "seeds": len(seeds),
                "fp32": float(a.loc[(env, variant)].mean()),
                "bf16": float(b.loc[(env, variant)].mean()),
                "diff": mean, "ci90": ci, "margin": margin, "p_tost": p,
                "equivalent": bool(p < ALPHA),
            })
    return rows


def report(rows, seeds, profile):
    ok = all(r["equivalent"] for r in rows)
    lines = [
        f"# bf16 against fp32: equivalence (TOST, α = {ALPHA}) on {profile}, {seeds} seeds",
        "",
        "Per seed: the method's mean over its cells; d = bf16 − fp32, paired by seed. Equivalent when"
        " the 90 % CI of the mean d lies inside ±margin (FPE ±0.005, TPA ±0.02).",
        "",
        "| metric | env | method | fp32 | bf16 | mean d | 90 % CI | margin | TOST p | verdict |",
        "|---|---|---|---:|---:|---:|---|---:|---:|---|",
    ]
    for r in rows:
        lo, hi = r["ci90"]
        lines.append(
            f"| {r['metric'].upper()} | {r['env']} | {r['method']} | {r['fp32']:.4f} |"
            f" {r['bf16']:.4f} | {r['diff']:+.5f} | [{lo:+.5f}, {hi:+.5f}] | ±{r['margin']} |"
            f" {r['p_tost']:.2g} | {'equivalent' if r['equivalent'] else 'not shown equivalent'} |")
    failed = [f"{r['metric'].upper()} {r['env']} {r['method']}" for r in rows if not r["equivalent"]]
    lines += ["", "**Verdict: bf16 is equivalent to fp32 on every method and metric.**" if ok else
              "**Verdict: equivalence not shown** for " + ", ".join(failed) +
              ": quick stays on fp32."]
    return "\n".join(lines) + "\n", ok


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--profile", default=os.path.join(ROOT, "bench", "mid.toml"))
    ap.add_argument("--seeds", type=int, default=10, help="seeds 0..N-1 (default 10)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bf16-equivalence"))
    ap.add_argument("--sirl", default=os.path.join(ROOT, "build", "release", "app", "sirl"))
    ap.add_argument("--analyse-only", action="store_true", help="compare existing results files")
    a = ap.parse_args()
    if a.seeds < 2:
        sys.exit("bf16_equivalence: a paired test needs at least 2 seeds")
    if not a.analyse_only and not os.access(a.sirl, os.X_OK):
        sys.exit(f"bf16_equivalence: no sirl binary at {a.sirl} (./scripts/build.sh release)")
    os.makedirs(a.out, exist_ok=True)
    stem = os.path.splitext(os.path.basename(a.profile))[0]
    paths = {}
    for precision in ("fp32", "bf16"):
        paths[precision] = os.path.join(a.out, precision + ".h5")
        if not a.analyse_only:
            run(a.sirl, a.profile, settings(precision, a.seeds, f"{stem}-{precision}"),
                paths[precision], a.threads)
    for path in paths.values():
        if not os.path.isfile(path):
            sys.exit(f"bf16_equivalence: {path}: no results file (run without --analyse-only)")
    rows = compare(paths["fp32"], paths["bf16"])
    text, ok = report(rows, a.seeds, os.path.relpath(a.profile, ROOT))
    with open(os.path.join(a.out, "bf16-equivalence.md"), "w", encoding="utf-8") as f:
        f.write(text)
    with open(os.path.join(a.out, "bf16-equivalence.json"), "w", encoding="utf-8") as f:
        json.dump({"seeds": a.seeds, "profile": a.profile, "equivalent": ok, "rows": rows}, f,
                  indent=1)
    print(text)


if __name__ == "__main__":
    main()
