#!/usr/bin/python3
"""Runs the roofline, the C++ kernel benchmarks and the PyTorch reference in one invocation and
prints a Markdown table: GFLOP/s, % of this CPU's fp32 roof, and the speed-up over the best
PyTorch form (medians of repeated runs).

The roof is measured here (bench/bench_roofline.cpp: peak fp32 FMA, one core and all cores).
Rows on 1 thread compare with PyTorch on 1 thread and with one core's roof. Rows on 2 threads
compare machine throughput: with the better of PyTorch on 2 threads and two PyTorch processes of
1 thread each run at once (summed), and with the roof of all cores. For the 20 TPA heads the
PyTorch figure is the fastest of the forms torch_reference.py writes (a loop over heads, a
batched form with torch.baddbmm, a triplet's or pair's members stacked into one pass).
A second table times whole TPA cells of JacoRobot as a quick run trains them (20 heads, one
after another, 15 epochs; bench/bench_pipeline.cpp) against the same cells written in PyTorch
(each reward its own network and Adam), one thread each: the engine's own unit of work, where the
step rows above time all 20 heads taking one step in turn.
Last, the performance issue's targets checked on this run's numbers (one thread): each target's
measured value, whether it holds, and the GFLOP/s it would take here with its share of the roof.
Usage: /usr/bin/python3 bench/compare_kernels.py [--build build/release] [--repetitions 5]
                                                 [--no-cells]
"""
import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
TORCH = [sys.executable, os.path.join(HERE, "torch_reference.py")]


def gbench(exe, repetitions, filt=None):
    args = [exe, "--benchmark_format=json", f"--benchmark_repetitions={repetitions}",
            "--benchmark_report_aggregates_only=true", "--benchmark_min_time=0.5"]
    if filt:
        args.append(f"--benchmark_filter={filt}")
    out = json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout)
    want = "median" if repetitions > 1 else None  # one repetition: no aggregates, the run itself
    return {b["run_name"]: b for b in out["benchmarks"] if b.get("aggregate_name") == want}


def roof(build, repetitions, probe="BM_PeakFp32Fma"):
    """Peak GFLOP/s of one probe: {threads: value} for 1 thread and all cores ({} when the CPU
    lacks the instruction: the probe then reports an error and no rate)."""
    med = gbench(os.path.join(build, "bench", "sirl_bench_roofline"), repetitions, probe)
    return {int(k.split("threads:")[1].split("/")[0]): v["GFLOP/s"] for k, v in med.items()
            if "GFLOP/s" in v}


def milliseconds(bench):
    """A Google Benchmark entry's real time in ms (the kernels report ms, the rest ns)."""
    return bench["real_time"] if bench["time_unit"] == "ms" else bench["real_time"] * 1e-6


def torch_two_processes():
    """Two 1-thread PyTorch processes at once (one per core): per case, the summed GFLOP/s."""
    procs = [subprocess.Popen(TORCH + ["--threads", "1"], stdout=subprocess.PIPE, text=True)
             for _ in range(2)]
    outs = [json.loads(p.communicate()[0]) for p in procs]
    assert all(p.returncode == 0 for p in procs)
    return {k: {"gflops": sum(o[k]["gflops"] for o in outs), "ms": max(o[k]["ms"] for o in outs)}
            for k in outs[0] if isinstance(outs[0][k], dict)}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(HERE, "..", "build", "release"))
    ap.add_argument("--repetitions", type=int, default=5)
    ap.add_argument("--no-cells", action="store_true",
                    help="skip the whole-cell table (about 4 minutes, 3 repetitions a side)")
    args = ap.parse_args()
    exe = os.path.join(args.build, "bench", "sirl_bench_kernels")
    if not os.path.exists(exe):
        sys.exit(f"compare_kernels: {exe} not found; build with `cmake --build --preset release`")
    peak = roof(args.build, args.repetitions)
    med = gbench(exe, args.repetitions)
    run = lambda threads: json.loads(subprocess.run(TORCH + ["--threads", str(threads)], check=True,
                                                    capture_output=True, text=True).stdout)
    torch1, torch2, torch1x2 = run(1), run(2), torch_two_processes()

    def best_torch(case, threads):
        forms = [case] + [case + f for f in ("_stacked", "_batched") if case + f in torch1]
        pool = [(torch1[f], f"{f}, 1 thread") for f in forms] if threads == 1 else \
            [(torch2[f], f"{f}, 2 threads") for f in forms] + \
            [(torch1x2[f], f"{f}, 2 processes") for f in forms]
        return max(pool, key=lambda t: t[0]["gflops"])

    rows = [
        ("SIRL step, Grid 19→128→128→6, 64 triplets", "BM_SirlStep/in:19/hidden:128/threads:{}/real_time", "sirl_step_grid"),
        ("SIRL step, Jaco 2037→1024→1024→6, 64 triplets", "BM_SirlStep/in:2037/hidden:1024/threads:{}/real_time", "sirl_step_jaco"),
        ("20 TPA heads 6→128→128→1, 64 pairs", "BM_TpaHeadsStep/hidden:128/threads:{}/real_time", "tpa_heads_grid"),
        ("Jaco frozen TPA cell step: 20 heads 6→1024→1024→1, 64 pairs",
         "BM_TpaHeadsStep/hidden:1024/threads:{}/real_time", "tpa_heads_jaco"),
        ("Jaco unfrozen TPA cell: 20 × (φ 2037→1024→1024→6 + head 6→1024→1024→1), 32 pairs",
         "BM_TpaUnfrozenStep/in:2037/hidden:1024/B:32/threads:{}/real_time", "tpa_unfrozen_jaco"),
    ]
    cores = max(peak)
    print(f"Roof (measured, fp32 FMA): {peak[1]:.0f} GFLOP/s on one core, {peak[cores]:.0f} on "
          f"{cores} cores. PyTorch {torch1['torch']}, same machine, same run; medians of "
          f"{args.repetitions} repetitions.\n")
    print("| case | threads | ours ms | ours GFLOP/s | % of roof | best PyTorch form | PyTorch GFLOP/s | speed-up |")
    print("|---|---:|---:|---:|---:|---|---:|---:|")
    one = {}  # case -> our fp32, our bf16 and the best PyTorch GFLOP/s, one thread
    for threads in (1, 2):
        for label, key, case in rows:
            o = med[key.format(threads)]
            ms = milliseconds(o)
            t, form = best_torch(case, threads)
            if threads == 1:
                one[case] = {"ours": o["GFLOP/s"], "torch": t["gflops"]}
            print(f"| {label} | {threads} | {ms:.3f} | {o['GFLOP/s']:.1f} | "
                  f"{100 * o['GFLOP/s'] / peak[min(threads, cores)]:.0f} % | {form} | "
                  f"{t['gflops']:.1f} | {o['GFLOP/s'] / t['gflops']:.2f}x |")

    # Precision "bf16" (kernels/gemm_bf16.h): the same cases, against the bf16 dot-product roof
    # where the CPU has one (else the products are emulated, and the fp32 roof applies), our fp32
    # and the best PyTorch (fp32) form. FLOPs are counted alike in both precisions.
    # On a CPU with AMX (Sapphire Rapids and later) oneDNN runs them on the tiles, whose roof is
    # several times vdpbf16ps' (there half the fp32 FMA rate): the roof is the faster unit's.
    dot16 = roof(args.build, args.repetitions, "BM_PeakBf16Dot")
    amx16 = roof(args.build, args.repetitions, "BM_PeakAmxBf16")
    native = bool(dot16)
    unit = "AMX tdpbf16ps" if amx16 and amx16[1] > dot16.get(1, 0) else "vdpbf16ps"
    ref = (amx16 if unit.startswith("AMX") else dot16) if native else peak
    print(f"\nPrecision bf16 ({'native: ' + unit if native else 'emulated: no AVX512-BF16 here'}); "
          f"roof {ref[1]:.0f} GFLOP/s on one core, {ref[max(ref)]:.0f} on {max(ref)} cores "
          f"({unit if native else 'fp32 FMA'}"
          f"{f'; vdpbf16ps {dot16[1]:.0f} on one core' if amx16 and native else ''}).\n")
    print("| case | threads | ours bf16 ms | GFLOP/s | % of roof | vs ours fp32 | best PyTorch form (fp32) | speed-up |")
    print("|---|---:|---:|---:|---:|---:|---|---:|")
    for threads in (1, 2):
        for label, key, case in rows:
            k16 = key.replace("Step/", "StepBf16/", 1).format(threads)
            if k16 not in med:
                continue
            o, o32 = med[k16], med[key.format(threads)]
            if threads == 1:
                one[case]["bf16"] = o["GFLOP/s"]
            ms = milliseconds(o)
            t, form = best_torch(case, threads)
            print(f"| {label} | {threads} | {ms:.3f} | {o['GFLOP/s']:.1f} | "
                  f"{100 * o['GFLOP/s'] / ref[min(threads, max(ref))]:.0f} % | "
                  f"{o['GFLOP/s'] / o32['GFLOP/s']:.2f}x | {form} | "
                  f"{t['gflops']:.1f} | {o['GFLOP/s'] / t['gflops']:.2f}x |")

    cells = None if args.no_cells else print_cells(args.build, peak[1])
    print("\nThe performance issue's targets, one thread, this run (\"takes\": the GFLOP/s our case "
          "would need, and its share of one core's roof: fp32's, or for bf16 that of the unit its "
          "products run on).\n")
    print("| target | measured | holds | takes |")
    print("|---|---:|---|---:|")
    for name, measured, holds, need, precision in target_rows(peak[1], one, cells):
        top = ref[1] if precision == "bf16" else peak[1]
        print(f"| {name} | {measured} | {'yes' if holds else '**no**'} | "
              f"{need:.0f} GFLOP/s, {100 * need / top:.0f} % |")
    print("\nNot checked here: the whole quick run ≥ 300 GFLOP/s on 2 threads (the aggregate "
          "`sirl run quick` prints).")


def target_rows(roof1, one, cells=None):
    """The issue's targets on one thread's numbers: [(target, measured, holds, GFLOP/s needed,
    the precision whose roof applies: "fp32" or "bf16")].
    one: {case: {"ours": fp32 GFLOP/s, "torch": the best PyTorch form's, "bf16": ours in bf16
    (absent when not measured)}}; cells: print_cells' {PyTorch cell case: {"speedup", "torch"}}
    or None."""
    out = []

    def share(name, case, goal):
        pct = one[case]["ours"] / roof1
        out.append((name, f"{100 * pct:.0f} %", pct >= goal, goal * roof1, "fp32"))

    def ratio(name, case, goal, ours="ours", of="torch", what="PyTorch"):
        if ours not in one[case]:
            return
        x = one[case][ours] / one[case][of]
        out.append((name, f"{x:.2f}× {what}", x >= goal, goal * one[case][of],
                    "bf16" if ours == "bf16" else "fp32"))

    share("Grid SIRL step ≥ 70 % of the roof", "sirl_step_grid", 0.70)
    share("Jaco SIRL step ≥ 80 % of the roof", "sirl_step_jaco", 0.80)
    share("20 Grid TPA heads ≥ 70 % of the roof", "tpa_heads_grid", 0.70)
    ratio("20 Grid TPA heads ≥ 4.5× the best PyTorch form", "tpa_heads_grid", 4.5)
    ratio("frozen Jaco TPA cell step ≥ 2.5× PyTorch", "tpa_heads_jaco", 2.5)
    if cells and "tpa_quick_cell_jaco_frozen" in cells:
        c = cells["tpa_quick_cell_jaco_frozen"]
        out.append(("frozen Jaco TPA cell (whole, M = 100) ≥ 2.5× PyTorch",
                    f"{c['speedup']:.2f}× PyTorch", c["speedup"] >= 2.5, 2.5 * c["torch"], "fp32"))
    ratio("Jaco bf16 step ≥ 1.7× our fp32", "sirl_step_jaco", 1.7, "bf16", "ours", "our fp32")
    ratio("Jaco bf16 step ≥ 3.5× PyTorch", "sirl_step_jaco", 3.5, "bf16")
    ratio("Grid bf16 step ≥ 7× PyTorch", "sirl_step_grid", 7.0, "bf16")
    return out


CELLS = [  # (label, ours in sirl_bench_pipeline, the PyTorch case)
    ("Jaco TPA cell, M = 100, frozen (20 heads 6→1024→1024→1)", "BM_TpaQuickCell/frozen:1/real_time",
     "tpa_quick_cell_jaco_frozen"),
    ("Jaco TPA cell, M = 100, unfrozen (20 × φ + head)", "BM_TpaQuickCell/frozen:0/real_time",
     "tpa_quick_cell_jaco_unfrozen"),
    ("Jaco TPA cell, M = 10, frozen", "BM_TpaSmallCell/frozen:1/real_time",
     "tpa_small_cell_jaco_frozen"),
    ("Jaco TPA cell, M = 10, unfrozen", "BM_TpaSmallCell/frozen:0/real_time",
     "tpa_small_cell_jaco_unfrozen"),
]


def print_cells(build, roof1, repetitions=3):
    """Whole cells, one thread, medians of `repetitions` (after one warm-up run on PyTorch's side).
    Returns, per PyTorch cell case, our speed-up over PyTorch and PyTorch's GFLOP/s."""
    med = gbench(os.path.join(build, "bench", "sirl_bench_pipeline"), repetitions,
                 "BM_TpaQuickCell|BM_TpaSmallCell")
    torch1 = json.loads(subprocess.run(
        TORCH + ["--threads", "1", "--repeats", str(repetitions), "--cases",
                 ",".join(c + f for _, _, c in CELLS for f in ("", "_stacked"))], check=True,
        capture_output=True, text=True).stdout)
    print(f"\nWhole cells as a quick run trains them (15 epochs, heads one after another), one "
          f"thread; medians of {repetitions}.\n")
    print("| cell | ours s | ours GFLOP/s | % of roof | PyTorch s | PyTorch GFLOP/s | speed-up |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    measured = {}
    for label, key, case in CELLS:
        o = med[key]
        t = min((torch1[case], torch1[case + "_stacked"]), key=lambda c: c["ms"])  # its faster form
        s = milliseconds(o) * 1e-3
        measured[case] = {"speedup": t["ms"] * 1e-3 / s, "torch": t["gflops"]}
        print(f"| {label} | {s:.2f} | {o['GFLOP/s']:.1f} | {100 * o['GFLOP/s'] / roof1:.0f} % | "
              f"{t['ms'] * 1e-3:.2f} | {t['gflops']:.1f} | {t['ms'] * 1e-3 / s:.2f}x |")
    return measured


if __name__ == "__main__":
    main()
