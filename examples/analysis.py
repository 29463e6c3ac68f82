#!/usr/bin/python3
"""Compare two sirl-bench runs with pandas: a worked example of the sirl_bench reader.

    /usr/bin/python3 examples/analysis.py BASELINE.h5 TONIGHT.h5 [--out fig5_compare.png]

Prints, per environment and method in the paper's best mode (SIRL frozen, the others unfrozen),
the mean TPA at the largest N of each run and their difference; prints how many TPA heads
stopped early; and draws both runs' Fig. 5 curves (TPA against M) in one figure.
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

# The reader: installed by scripts/setup.sh; in a checkout it also sits in ../python.
sys.path.insert(1, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import sirl_bench  # noqa: E402


def fig5_cells(path):
    """The Fig. 5 cells of one run at its largest N (methods without N, VAE and Random, kept)."""
    tpa = sirl_bench.open(path).tables["tpa"]
    if "best_mode" not in tpa:
        raise sirl_bench.ResultsError(f"{path}: written by an engine before 0.8.0 (its tables "
                                      "carry no best_mode column); re-run it")
    # The paper's protocol, the methods only (linear evaluation and the references truth and raw
    # are rows of the same table: docs/linear-evaluation.md).
    main = tpa[tpa.in_main & tpa.best_mode & (tpa.protocol == "paper") & ~tpa.reference]
    largest = main.groupby("env").N.transform("max")
    return main[(main.N == largest) | main.N.isna()]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("baseline")
    ap.add_argument("tonight")
    ap.add_argument("--out", default="fig5_compare.png")
    a = ap.parse_args()
    try:
        runs = {"baseline": fig5_cells(a.baseline), "tonight": fig5_cells(a.tonight)}
    except sirl_bench.ResultsError as e:
        sys.exit(f"analysis: {e}")

    # Filter, group by, compare: one row per (env, variant), the two runs side by side.
    means = pd.DataFrame({name: d.groupby(["env", "variant"]).tpa.mean() for name, d in runs.items()})
    means["difference"] = means.tonight - means.baseline
    print(means.round(4).to_string())

    heads = sirl_bench.open(a.tonight).tables["tpa_heads"]
    print(f"\nTPA heads that stopped early (tpa.stop): {int(heads.stopped.sum())} of {len(heads)}")

    envs = sorted(set(runs["tonight"].env))
    fig, axes = plt.subplots(1, len(envs), figsize=(5 * len(envs), 3.6), squeeze=False)
    for ax, env in zip(axes[0], envs):
        for name, style in (("baseline", "--"), ("tonight", "-")):
            d = runs[name][runs[name].env == env]
            for variant, dv in d.groupby("variant"):
                m = dv.groupby("M").tpa.mean()
                ax.plot(m.index, m.values, style, marker="o", ms=3, label=f"{variant} ({name})")
        ax.set_title(env)
        ax.set_xlabel("preference queries per test reward M")
        ax.set_ylabel("TPA")
        ax.grid(alpha=0.3)
    axes[0][-1].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(a.out, dpi=120)
    print(f"analysis: wrote {a.out}")


if __name__ == "__main__":
    main()
