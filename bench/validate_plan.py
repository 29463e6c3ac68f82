#!/usr/bin/python3
"""How well `sirl plan` predicts a run's wall time on this machine: for each profile and mode it
asks `sirl plan` for the simulated makespan, then runs the profile into a scratch file and times
it, and prints predicted vs measured.

    /usr/bin/python3 bench/validate_plan.py [--sirl build/release/app/sirl]
        [--profiles configs/smoke.toml bench/mid.toml] [--modes 1 2 mpi3] [--out DIR]

Modes: a thread count (`sirl run --threads N`) or `mpiK` (`mpirun --oversubscribe -np K`, which
`sirl plan --mpi --cores-per-node K` simulates). The measured time is the whole command (dataset
generation, the roof probe and the final write included); the prediction covers the tasks only,
so small profiles show that fixed part. Run it on an otherwise idle machine.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def predicted(sirl, profile, mode):
    args = [sirl, "plan", profile]
    if mode.startswith("mpi"):
        args += ["--mpi", "--cores-per-node", mode[3:]]
    else:
        args += ["--threads", mode]
    p = subprocess.run(args, capture_output=True, text=True, stdin=subprocess.DEVNULL)
    if p.returncode != 0:
        sys.exit(f"validate_plan: {' '.join(args)} failed:\n{p.stderr}")
    m = re.search(r"predicted makespan: \S+ \(([\d.]+) s\)", p.stdout)
    cp = re.search(r"critical path: (\d+) task\(s\), (\S+)", p.stdout)
    if not m:
        sys.exit(f"validate_plan: no prediction in the output of {' '.join(args)}")
    return float(m.group(1)), (cp.group(2) if cp else "?")


def measured(sirl, profile, mode, scratch):
    out = os.path.join(scratch, "run.h5")
    for leftover in (out, out + ".tasks", out + ".sum", out + ".lock"):
        if os.path.isdir(leftover):
            shutil.rmtree(leftover)
        elif os.path.exists(leftover):
            os.remove(leftover)
    if mode.startswith("mpi"):
        args = ["mpirun", "--oversubscribe", "--allow-run-as-root", "-np", mode[3:], sirl, "run",
                profile, "--out", out, "--quiet"]
    else:
        args = [sirl, "run", profile, "--out", out, "--threads", mode, "--quiet"]
    t0 = time.monotonic()
    p = subprocess.run(args, capture_output=True, text=True, stdin=subprocess.DEVNULL)
    wall = time.monotonic() - t0
    if p.returncode != 0:
        sys.exit(f"validate_plan: {' '.join(args)} failed:\n{p.stderr[-2000:]}")
    return wall


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sirl", default=os.path.join(HERE, "..", "build", "release", "app", "sirl"))
    ap.add_argument("--profiles", nargs="+",
                    default=[os.path.join(HERE, "..", "configs", "smoke.toml"), os.path.join(HERE, "mid.toml")])
    ap.add_argument("--modes", nargs="+", default=["1", "2", "mpi3"])
    ap.add_argument("--out", help="keep the runs' files here (default: a temporary directory)")
    a = ap.parse_args()
    scratch = a.out or tempfile.mkdtemp(prefix="validate_plan.")
    os.makedirs(scratch, exist_ok=True)
    rows = []
    try:
        for prof in a.profiles:
            for mode in a.modes:
                pred, cp = predicted(a.sirl, prof, mode)
                wall = measured(a.sirl, prof, mode, scratch)
                rows.append((os.path.basename(prof), mode, pred, wall, cp))
                print(f"{rows[-1][0]} {mode}: predicted {pred:.0f} s, measured {wall:.1f} s "
                      f"({100 * (pred / wall - 1):+.0f} %)", flush=True)
    finally:
        if not a.out:
            shutil.rmtree(scratch, ignore_errors=True)
    print("\n| profile | mode | predicted (s) | measured (s) | error | critical path |")
    print("|---|---|---:|---:|---:|---:|")
    for prof, mode, pred, wall, cp in rows:
        label = f"mpirun -np {mode[3:]}" if mode.startswith("mpi") else f"{mode} thread(s)"
        print(f"| {prof} | {label} | {pred:.0f} | {wall:.1f} | {100 * (pred / wall - 1):+.0f} % | {cp} |")


if __name__ == "__main__":
    main()
