#!/usr/bin/python3
"""Runs the C++ kernel benchmarks and the PyTorch reference in one invocation and prints a
Markdown table of GFLOP/s and the ratio ours / PyTorch (medians of repeated runs).
Usage: /usr/bin/python3 bench/compare_kernels.py [--build build/release] [--repetitions 5]
"""
import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(HERE, "..", "build", "release"))
    ap.add_argument("--repetitions", type=int, default=5)
    args = ap.parse_args()
    exe = os.path.join(args.build, "bench", "sirl_bench_kernels")
    if not os.path.exists(exe):
        sys.exit(f"compare_kernels: {exe} not found; build with `cmake --build --preset release`")
    ours = json.loads(subprocess.run(
        [exe, "--benchmark_format=json", f"--benchmark_repetitions={args.repetitions}",
         "--benchmark_report_aggregates_only=true", "--benchmark_min_time=0.5"],
        check=True, capture_output=True, text=True).stdout)
    med = {b["run_name"]: b for b in ours["benchmarks"] if b.get("aggregate_name") == "median"}
    torch1 = json.loads(subprocess.run([sys.executable, os.path.join(HERE, "torch_reference.py"), "--threads", "1"],
                                       check=True, capture_output=True, text=True).stdout)
    torch2 = json.loads(subprocess.run([sys.executable, os.path.join(HERE, "torch_reference.py"), "--threads", "2"],
                                       check=True, capture_output=True, text=True).stdout)
    rows = [
        ("SIRL step, Grid 19→128→128→6, 64 triplets, 1 thread", "BM_SirlStep/in:19/hidden:128/threads:1/real_time", "sirl_step_grid", 1),
        ("SIRL step, Grid 19→128→128→6, 64 triplets, 2 threads", "BM_SirlStep/in:19/hidden:128/threads:2/real_time", "sirl_step_grid", 2),
        ("SIRL step, Jaco 2037→1024→1024→6, 64 triplets, 1 thread", "BM_SirlStep/in:2037/hidden:1024/threads:1/real_time", "sirl_step_jaco", 1),
        ("SIRL step, Jaco 2037→1024→1024→6, 64 triplets, 2 threads", "BM_SirlStep/in:2037/hidden:1024/threads:2/real_time", "sirl_step_jaco", 2),
        ("20 TPA heads 6→128→128→1, 64 pairs, 1 thread", "BM_TpaHeadsStep/hidden:128/threads:1/real_time", "tpa_heads_grid", 1),
        ("20 TPA heads 6→128→128→1, 64 pairs, 2 threads", "BM_TpaHeadsStep/hidden:128/threads:2/real_time", "tpa_heads_grid", 2),
    ]
    print(f"PyTorch {torch1['torch']} (same machine, same run); medians of {args.repetitions} repetitions\n")
    print("| case | ours ms | ours GFLOP/s | PyTorch ms | PyTorch GFLOP/s | speed-up |")
    print("|---|---:|---:|---:|---:|---:|")
    for label, ours_key, torch_key, threads in rows:
        o = med[ours_key]
        t = (torch1 if threads == 1 else torch2)[torch_key]
        ms = o["real_time"] if o["time_unit"] == "ms" else o["real_time"] * 1e-6
        print(f"| {label} | {ms:.3f} | {o['GFLOP/s']:.1f} | "
              f"{t['ms']:.3f} | {t['gflops']:.1f} | {t['ms'] / ms:.2f}x |")


if __name__ == "__main__":
    main()
