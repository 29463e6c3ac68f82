#!/usr/bin/python3
"""How many epochs does each kind of training need? Read from a results file's learning curves.

For every training in the file (the VAE, each representation φ, each TPA cell's 20 heads) it
takes the loss curve (a TPA cell: the mean of its heads' curves) and finds

  e95: the first epoch from which the curve, averaged over a trailing window of a fiftieth of its
       epochs (mini-batch noise), stays within 5 % of its total decrease from its final value:
         |mean(curve[e−w+1 .. e]) − final| ≤ 0.05 · |curve[0] − final|   for every later e,
       final = the mean over the last tenth. "95 % of the way down, for good."

and prints, per kind of training (VAE; φ by method and N; TPA by frozen/unfrozen and M), the
median and largest e95 over the file's trainings, as epochs and as a share of the epochs run, and
how many met the engine's own convergence rule (engine/convergence.h) at the end.

With --against FILE (the same grid run with fewer epochs), it also compares the final metrics:
per method and N (FPE) or method, N, M and mode (TPA), the mean over seeds of the short run minus
the long run.

  /usr/bin/python3 bench/convergence_epochs.py out/grid-paper-epochs.h5 [--against short.h5]
"""
import argparse
import os
import sys

import numpy as np
import pandas as pd

# The reader package: installed by scripts/setup.sh, or beside this folder in a checkout.
sys.path.insert(1, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import sirl_bench  # noqa: E402

TOL = 0.05


def e95(curve):
    curve = np.asarray(curve, dtype=float)
    n = len(curve)
    if n < 2:
        return None
    final = curve[-max(1, n // 10):].mean()
    w = max(1, n // 50)
    drop = abs(curve[0] - final)
    smooth = np.convolve(curve, np.ones(w) / w, mode="full")[:n]  # trailing means
    smooth[: w - 1] = [curve[: i + 1].mean() for i in range(w - 1)]
    outside = np.abs(smooth - final) > TOL * drop + 1e-12
    if not outside.any():
        return 1
    return int(np.nonzero(outside)[0][-1]) + 2  # 1-based epoch after the last one outside


def label(r):
    """What a training is, from its record's fields (a row of sirl_bench's records)."""
    if r.kind == "vae":
        return f"{r.env}: VAE"
    if r.kind == "rep":
        return f"{r.env}: φ {r.variant} N={int(r.N)}"
    mode = "frozen" if r.frozen else "unfrozen"
    return f"{r.env}: TPA heads, {mode}, M={int(r.M)}"


def curves(path):
    res = sirl_bench.open(path)
    recs = res.records
    # the VAE, every φ but the VAE baseline's own encoder (its curve is the VAE's), TPA cells
    recs = recs[recs.kind.isin(["vae", "rep", "tpa"])]
    if "variant" in recs:
        recs = recs[~((recs.kind == "rep") & (recs.variant == "vae"))]
    rows = []
    for r in recs.itertuples():
        names = r.arrays.split(",")
        if "loss_curve" in names:
            c = res.array(r.key, "loss_curve")
        elif "loss_curves" in names:
            c = res.array(r.key, "loss_curves")
            c = np.nanmean(c[:, ~np.isnan(c).all(0)], axis=0)  # stopped heads: NaN after
        else:
            continue
        if len(c) < 2:
            continue
        rows.append({"label": label(r), "key": r.key, "epochs": len(c), "e95": e95(c),
                     "converged": bool(r.converged) if "converged" in recs else False})
    return pd.DataFrame(rows)


def metric_deltas(long_path, short_path):
    out = []
    for kind, by in (("fpe", ["env", "variant", "N"]), ("tpa", ["env", "variant", "N", "M", "frozen"])):
        frames = []
        for p in (long_path, short_path):
            d = sirl_bench.open(p).tables[kind]
            frames.append(d.groupby(by, dropna=False)[kind].mean())
        delta = (frames[1] - frames[0]).dropna()
        out.append((kind, pd.DataFrame({"long": frames[0], "short": frames[1], "short − long": delta}).dropna()))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("results")
    ap.add_argument("--against", help="the same grid with fewer epochs: compare final metrics")
    a = ap.parse_args()
    for p in filter(None, (a.results, a.against)):
        if not os.path.isfile(p):
            sys.exit(f"convergence_epochs: {p}: no such results file")
    d = curves(a.results)
    if d.empty:
        sys.exit(f"convergence_epochs: no learning curves in {a.results}")
    d["share"] = d["e95"] / d["epochs"]
    print(f"# Epochs to 95 % of the loss decrease, for good ({a.results})\n")
    print("| training | runs | epochs run | e95 median | e95 max | converged (engine rule) |")
    print("|---|---:|---:|---:|---:|---:|")
    for lab, g in d.groupby("label", sort=True):
        print(f"| {lab} | {len(g)} | {int(g.epochs.max())} | {int(g.e95.median())} ({g.share.median():.0%})"
              f" | {int(g.e95.max())} ({g.share.max():.0%}) | {int(g.converged.sum())} of {len(g)} |")
    if a.against:
        for kind, t in metric_deltas(a.results, a.against):
            print(f"\n## {kind.upper()}: final metric, fewer epochs ({a.against}) against these\n")
            cols = list(t.index.names) + list(t.columns)
            print("| " + " | ".join(cols) + " |")
            print("|" + "---|" * len(cols))
            for idx, r in t.iterrows():
                idx = idx if isinstance(idx, tuple) else (idx,)
                print("| " + " | ".join(str(v) for v in idx) + " | " +
                      " | ".join(f"{v:.4f}" for v in r) + " |")
            print(f"\nlargest |short − long|: {t['short − long'].abs().max():.4f}")


if __name__ == "__main__":
    main()
