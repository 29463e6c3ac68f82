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
Each case is measured on both sides before the next starts, and its rows are printed as soon as
it is done; a case one side could not measure (a failed or refused run, a missing entry) gets a
row saying so, and the script goes on (exit 1 at the end, after every table). The reference's
"baseline" entry (what PyTorch ran on) is printed under the first table; it is not a case.
A second table times whole TPA cells of JacoRobot as a quick run trains them (20 heads, one
after another, 15 epochs; bench/bench_pipeline.cpp) against the same cells written in PyTorch
(each reward its own network and Adam), one thread each: the engine's own unit of work, where the
step rows above time all 20 heads taking one step in turn.
Last, the performance issue's targets checked on this run's numbers (one thread): each target's
measured value, whether it holds, and the GFLOP/s it would take here with its share of the roof.
--tiny runs only the GridRobot cases (the smallest shapes both sides have), one repetition of
0.1 s a benchmark, no whole cells: both sides and every table but the cells' in under a minute
(ctest compare_kernels_tiny), its numbers too short to quote.
Usage: /usr/bin/python3 bench/compare_kernels.py [--build build/release] [--repetitions 5]
                                                 [--no-cells] [--cases a,b] [--min-time S] [--tiny]
"""
import argparse
import json
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REFERENCE = os.path.join(HERE, "torch_reference.py")

# (case, label, our benchmark with its thread count as {}, the forms torch_reference.py writes it
# in: suffixes of the case's name there). Order: the tables'.
CASES = [
    ("sirl_step_grid", "SIRL step, Grid 19→128→128→6, 64 triplets",
     "BM_SirlStep/in:19/hidden:128/threads:{}/real_time", ("", "_stacked")),
    ("sirl_step_jaco", "SIRL step, Jaco 2037→1024→1024→6, 64 triplets",
     "BM_SirlStep/in:2037/hidden:1024/threads:{}/real_time", ("", "_stacked")),
    ("tpa_heads_grid", "20 TPA heads 6→128→128→1, 64 pairs",
     "BM_TpaHeadsStep/hidden:128/threads:{}/real_time", ("", "_batched")),
    ("tpa_heads_jaco", "Jaco frozen TPA cell step: 20 heads 6→1024→1024→1, 64 pairs",
     "BM_TpaHeadsStep/hidden:1024/threads:{}/real_time", ("", "_batched")),
    ("tpa_unfrozen_jaco",
     "Jaco unfrozen TPA cell: 20 × (φ 2037→1024→1024→6 + head 6→1024→1024→1), 32 pairs",
     "BM_TpaUnfrozenStep/in:2037/hidden:1024/B:32/threads:{}/real_time", ("", "_batched")),
]
TINY = ("sirl_step_grid", "tpa_heads_grid")
THREADS = (1, 2)
DASH = "—"


class Unmeasured(Exception):
    """One side could not measure something; the message says why (one line)."""


def gbench(exe, repetitions, filt=None, min_time=0.5):
    args = [exe, "--benchmark_format=json", f"--benchmark_repetitions={repetitions}",
            "--benchmark_report_aggregates_only=true", f"--benchmark_min_time={min_time}"]
    if filt:
        args.append(f"--benchmark_filter={filt}")
    p = subprocess.run(args, capture_output=True, text=True)
    if p.returncode != 0:
        raise Unmeasured(f"{os.path.basename(exe)} exited {p.returncode}: {last_line(p.stderr)}")
    try:
        out = json.loads(p.stdout)
    except ValueError as e:
        raise Unmeasured(f"{os.path.basename(exe)} wrote no JSON ({e})") from None
    want = "median" if repetitions > 1 else None  # one repetition: no aggregates, the run itself
    return {b["run_name"]: b for b in out.get("benchmarks", []) if b.get("aggregate_name") == want}


def exact(names):
    """A --benchmark_filter matching exactly these benchmark names."""
    return "^(" + "|".join(re.escape(n) for n in names) + ")$"


def roof(build, repetitions, probe="BM_PeakFp32Fma", min_time=0.5):
    """Peak GFLOP/s of one probe: {threads: value} for 1 thread and all cores ({} when the CPU
    lacks the instruction: the probe then reports an error and no rate)."""
    med = gbench(os.path.join(build, "bench", "sirl_bench_roofline"), repetitions, probe, min_time)
    return {int(k.split("threads:")[1].split("/")[0]): v["GFLOP/s"] for k, v in med.items()
            if "GFLOP/s" in v}


def milliseconds(bench):
    """A Google Benchmark entry's real time in ms (the kernels report ms, the rest ns)."""
    return bench["real_time"] if bench["time_unit"] == "ms" else bench["real_time"] * 1e-6


def last_line(text):
    lines = [ln.strip() for ln in (text or "").splitlines() if ln.strip()]
    return lines[-1][-300:] if lines else "no message"


def cell(text):
    """Text safe in one Markdown table cell."""
    return " ".join(str(text).split()).replace("|", "\\|")


def is_case(entry):
    """A timed case of torch_reference.py's output: a dict with its step time and rate. The other
    entries ("torch", "threads", "baseline": what it ran on) are not cases."""
    return isinstance(entry, dict) and all(
        isinstance(entry.get(k), (int, float)) and not isinstance(entry.get(k), bool)
        for k in ("ms", "gflops"))


class Reference:
    """torch_reference.py run on a few cases at a time: {form: its entry} for the forms asked
    for that it timed; the first run's "baseline" entry is kept (self.baseline) for the header."""

    def __init__(self, script, repeats, min_time):
        self.script, self.repeats, self.min_time = script, repeats, min_time
        self.baseline = {}  # threads -> the reference's "baseline" entry of a run on that many

    def command(self, threads, forms):
        cmd = [sys.executable, self.script, "--threads", str(threads), "--cases", ",".join(forms)]
        if self.repeats is not None:
            cmd += ["--repeats", str(self.repeats)]
        if self.min_time is not None:
            cmd += ["--min-time", str(self.min_time)]
        return cmd

    def parse(self, returncode, stdout, stderr, what, threads, forms):
        if returncode != 0:
            raise Unmeasured(f"{what}: exit {returncode}: {last_line(stderr)}")
        try:
            doc = json.loads(stdout)
        except ValueError as e:
            raise Unmeasured(f"{what}: no JSON ({e})") from None
        if not isinstance(doc, dict):
            raise Unmeasured(f"{what}: its output is not a JSON object")
        if isinstance(doc.get("baseline"), dict):
            self.baseline.setdefault(threads, doc["baseline"])
        return {f: doc[f] for f in forms if is_case(doc.get(f))}  # only the cases asked for

    def run(self, threads, forms):
        p = subprocess.run(self.command(threads, forms), capture_output=True, text=True,
                           stdin=subprocess.DEVNULL)
        return self.parse(p.returncode, p.stdout, p.stderr, f"PyTorch on {on(threads)}", threads,
                          forms)

    def two_processes(self, forms):
        """Two 1-thread processes at once (one per core): per form timed by both, the summed
        GFLOP/s and the slower one's ms."""
        procs = [subprocess.Popen(self.command(1, forms), stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True)
                 for _ in range(2)]
        outs = [(p.communicate(), p.returncode) for p in procs]
        got = [self.parse(rc, o, e, "PyTorch, two 1-thread processes", 1, forms)
               for (o, e), rc in outs]
        return {f: {"gflops": got[0][f]["gflops"] + got[1][f]["gflops"],
                    "ms": max(got[0][f]["ms"], got[1][f]["ms"])}
                for f in forms if f in got[0] and f in got[1]}


def describe_baseline(baseline):
    """One line from torch_reference.py's "baseline" entry (what its PyTorch ran on)."""
    if not baseline:
        return "PyTorch baseline: not reported."
    b = baseline.get(1) or next(iter(baseline.values()))
    if "best_of" in b:  # --best-of-configs: one entry per configuration
        return "PyTorch baseline: best of configurations " + ", ".join(map(str, b["best_of"])) + "."
    libs = ", ".join(os.path.basename(x) for x in b.get("blas_libraries", [])) or b.get("blas", "?")
    cap = str(b.get("cpu_capability", "?")).split(":")[-1].strip()
    env = b.get("env", {})
    core = f", OPENBLAS_CORETYPE={env['OPENBLAS_CORETYPE']}" if env.get("OPENBLAS_CORETYPE") else ""
    threads = ", ".join(f"{b2.get('intra_op_threads', '?')} intra-op thread"
                        f"{'s' if b2.get('intra_op_threads') != 1 else ''} on the {t}-thread runs"
                        for t, b2 in sorted(baseline.items()))
    return (f"PyTorch baseline (torch_reference.py's own record): torch {b.get('torch', '?')}, "
            f"config {b.get('config', '?')}, CPU capability {cap}, BLAS {libs}{core}, "
            f"oneDNN {'on' if b.get('mkldnn') else 'off'}; {threads}.")


def best_torch(forms, threads, torch1, torch2, torch1x2):
    """The fastest PyTorch form of a case on `threads`: (its entry, "form, how it ran"), or None
    when none was measured."""
    if threads == 1:
        pool = [(torch1[f], f"{f}, 1 thread") for f in forms if f in torch1]
    else:
        pool = [(torch2[f], f"{f}, 2 threads") for f in forms if f in torch2] + \
               [(torch1x2[f], f"{f}, 2 processes") for f in forms if f in torch1x2]
    return max(pool, key=lambda t: t[0]["gflops"]) if pool else None


def measure(fn, *a):
    """fn(*a), or ({}, why) when a side could not measure it."""
    try:
        return fn(*a), None
    except Unmeasured as e:
        return {}, str(e)


def on(threads):
    return f"{threads} thread{'s' if threads != 1 else ''}"


def medians(repetitions):
    return f"medians of {repetitions} repetitions" if repetitions > 1 else "one repetition"


def pct(gflops, top):
    return f"{100 * gflops / top:.0f} %" if top else DASH


def speedup(ours, torch):
    return f"{ours / torch:.2f}x" if torch > 0 else DASH


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(HERE, "..", "build", "release"))
    ap.add_argument("--repetitions", type=int,
                    help="repetitions a benchmark, both sides (default 5; --tiny: 1)")
    ap.add_argument("--min-time", type=float,
                    help="seconds a benchmark: Google Benchmark's --benchmark_min_time (default "
                         "0.5) and torch_reference.py's --min-time a case (default its own, 2)")
    ap.add_argument("--cases", help="comma-separated cases (default all): "
                                    + ", ".join(c for c, *_ in CASES))
    ap.add_argument("--no-cells", action="store_true",
                    help="skip the whole-cell table (about 4 minutes, 3 repetitions a side)")
    ap.add_argument("--tiny", action="store_true",
                    help="the GridRobot cases only, 1 repetition of 0.1 s, no whole cells: "
                         "under a minute, for tests (explicit options still apply)")
    ap.add_argument("--reference", default=REFERENCE,
                    help="the PyTorch reference script (default bench/torch_reference.py)")
    args = ap.parse_args()
    if args.repetitions is None:
        args.repetitions = 1 if args.tiny else 5
    if args.min_time is None and args.tiny:
        args.min_time = 0.1  # past the first iteration's warm-up (JIT, page faults): ~70 ms here
    args.no_cells = args.no_cells or args.tiny
    wanted = args.cases.split(",") if args.cases else TINY if args.tiny else [c for c, *_ in CASES]
    unknown = [c for c in wanted if c not in {c for c, *_ in CASES}]
    if unknown:
        sys.exit(f"compare_kernels: no case {', '.join(unknown)}; cases: "
                 f"{', '.join(c for c, *_ in CASES)}")
    cases = [c for c in CASES if c[0] in wanted]
    exe = os.path.join(args.build, "bench", "sirl_bench_kernels")
    if not os.path.exists(exe):
        sys.exit(f"compare_kernels: {exe} not found; build with `cmake --build --preset release`")
    gmin = 0.5 if args.min_time is None else args.min_time
    ref = Reference(args.reference, args.repetitions, args.min_time)
    unmeasured = []  # (what, why)

    peak, why = measure(roof, args.build, args.repetitions, "BM_PeakFp32Fma", gmin)
    if why:
        unmeasured.append(("the fp32 roof", why))
    cores = max(peak) if peak else None
    if peak:
        print(f"Roof (measured, fp32 FMA): {peak[1]:.0f} GFLOP/s on one core, {peak[cores]:.0f} on "
              f"{cores} cores. PyTorch in the same run on the same machine; "
              f"{medians(args.repetitions)}.\n")
    else:
        print(f"Roof: not measured ({cell(why)}); {medians(args.repetitions)}.\n")
    print("| case | threads | ours ms | ours GFLOP/s | % of roof | best PyTorch form | PyTorch GFLOP/s | speed-up |")
    print("|---|---:|---:|---:|---:|---|---:|---:|", flush=True)
    one = {}  # case -> our fp32, our bf16 and the best PyTorch GFLOP/s, one thread
    measured = {}  # case -> (ours, torch1, torch2, torch1x2), for the bf16 table
    for case, label, key, suffixes in cases:
        names = [key.format(t) for t in THREADS]
        names += [n.replace("Step/", "StepBf16/", 1) for n in names]
        ours, why_ours = measure(gbench, exe, args.repetitions, exact(names), gmin)
        forms = [case + f for f in suffixes]
        torch1, why1 = measure(ref.run, 1, forms)
        torch2, why2 = measure(ref.run, 2, forms)
        torch1x2, why1x2 = measure(ref.two_processes, forms)
        measured[case] = (ours, torch1, torch2, torch1x2)
        one[case] = {}
        unmeasured += [(case, why) for why in (why_ours, why1, why2, why1x2) if why]
        for threads in THREADS:
            o = ours.get(key.format(threads))
            if o is not None and "GFLOP/s" not in o:
                unmeasured.append((case, f"ours on {on(threads)}: "
                                         f"{o.get('error_message', 'no GFLOP/s in its entry')}"))
                o = None
            elif o is None and not why_ours:
                unmeasured.append((case, f"ours on {on(threads)}: no {key.format(threads)} in "
                                         "sirl_bench_kernels' output"))
            best = best_torch(forms, threads, torch1, torch2, torch1x2)
            if best is None and not (why1 if threads == 1 else (why2 and why1x2)):
                unmeasured.append((case, f"PyTorch on {on(threads)}: no {' or '.join(forms)} in "
                                         "the reference's output"))
            if threads == 1:
                if o:
                    one[case]["ours"] = o["GFLOP/s"]
                if best:
                    one[case]["torch"] = best[0]["gflops"]
            top = peak.get(min(threads, cores)) if peak else None
            ours_cols = (f"{milliseconds(o):.3f} | {o['GFLOP/s']:.1f} | {pct(o['GFLOP/s'], top)}"
                         if o else f"not measured | {DASH} | {DASH}")
            torch_cols = (f"{best[1]} | {best[0]['gflops']:.1f}" if best
                          else f"not measured | {DASH}")
            ratio = speedup(o["GFLOP/s"], best[0]["gflops"]) if o and best else DASH
            print(f"| {label} | {threads} | {ours_cols} | {torch_cols} | {ratio} |", flush=True)
    print("\n" + describe_baseline(ref.baseline), flush=True)

    # Precision "bf16" (kernels/gemm_bf16.h): the same cases, against the bf16 dot-product roof
    # where the CPU has one (else the products are emulated, and the fp32 roof applies), our fp32
    # and the best PyTorch (fp32) form. FLOPs are counted alike in both precisions.
    # On a CPU with AMX (Sapphire Rapids and later) oneDNN runs them on the tiles, whose roof is
    # several times vdpbf16ps' (there half the fp32 FMA rate): the roof is the faster unit's.
    dot16, _ = measure(roof, args.build, args.repetitions, "BM_PeakBf16Dot", gmin)
    amx16, _ = measure(roof, args.build, args.repetitions, "BM_PeakAmxBf16", gmin)
    native = bool(dot16)
    unit = "AMX tdpbf16ps" if amx16 and amx16[1] > dot16.get(1, 0) else "vdpbf16ps"
    ref16 = (amx16 if unit.startswith("AMX") else dot16) if native else peak
    roof16 = (f"roof {ref16[1]:.0f} GFLOP/s on one core, {ref16[max(ref16)]:.0f} on {max(ref16)} "
              f"cores ({unit if native else 'fp32 FMA'}"
              f"{f'; vdpbf16ps {dot16[1]:.0f} on one core' if amx16 and native else ''})"
              if ref16 else "roof not measured")
    print(f"\nPrecision bf16 ({'native: ' + unit if native else 'emulated: no AVX512-BF16 here'}); "
          f"{roof16}.\n")
    print("| case | threads | ours bf16 ms | GFLOP/s | % of roof | vs ours fp32 | best PyTorch form (fp32) | speed-up |")
    print("|---|---:|---:|---:|---:|---:|---|---:|")
    for threads in THREADS:
        for case, label, key, suffixes in cases:
            ours, torch1, torch2, torch1x2 = measured[case]
            o = ours.get(key.replace("Step/", "StepBf16/", 1).format(threads))
            if not o or "GFLOP/s" not in o:
                continue
            o32 = ours.get(key.format(threads))
            if threads == 1:
                one[case]["bf16"] = o["GFLOP/s"]
            best = best_torch([case + f for f in suffixes], threads, torch1, torch2, torch1x2)
            top = ref16.get(min(threads, max(ref16))) if ref16 else None
            vs32 = speedup(o["GFLOP/s"], o32["GFLOP/s"]) if o32 and "GFLOP/s" in o32 else DASH
            torch_cols = (f"{best[1]} | {speedup(o['GFLOP/s'], best[0]['gflops'])}" if best
                          else f"not measured | {DASH}")
            print(f"| {label} | {threads} | {milliseconds(o):.3f} | {o['GFLOP/s']:.1f} | "
                  f"{pct(o['GFLOP/s'], top)} | {vs32} | {torch_cols} |", flush=True)

    cells = None
    if not args.no_cells:
        cells = print_cells(args.build, peak.get(1) if peak else None, ref=ref,
                            unmeasured=unmeasured)
    if peak:
        print("\nThe performance issue's targets, one thread, this run (\"takes\": the GFLOP/s our "
              "case would need, and its share of one core's roof: fp32's, or for bf16 that of the "
              "unit its products run on).\n")
        print("| target | measured | holds | takes |")
        print("|---|---:|---|---:|")
        for name, value, holds, need, precision in target_rows(peak[1], one, cells):
            top = ref16[1] if precision == "bf16" and ref16 else peak[1]
            print(f"| {name} | {value} | {'yes' if holds else '**no**'} | "
                  f"{need:.0f} GFLOP/s, {100 * need / top:.0f} % |")
        print("\nNot checked here: the whole quick run ≥ 300 GFLOP/s on 2 threads (the aggregate "
              "`sirl run quick` prints).")
    if unmeasured:
        print("\nNot measured (their rows say so):\n")
        for what, why in unmeasured:
            print(f"- {what}: {why}")
        sys.stdout.flush()
        sys.exit(f"compare_kernels: {len(unmeasured)} measurement(s) missing; the tables have "
                 "the rest")


def target_rows(roof1, one, cells=None):
    """The issue's targets on one thread's numbers: [(target, measured, holds, GFLOP/s needed,
    the precision whose roof applies: "fp32" or "bf16")].
    one: {case: {"ours": fp32 GFLOP/s, "torch": the best PyTorch form's, "bf16": ours in bf16
    (absent when not measured)}}; cells: print_cells' {PyTorch cell case: {"speedup", "torch"}}
    or None. A target whose case, or a side of it, was not measured (or not asked for) is left
    out."""
    out = []

    def share(name, case, goal):
        if "ours" not in one.get(case, {}):
            return
        pct = one[case]["ours"] / roof1
        out.append((name, f"{100 * pct:.0f} %", pct >= goal, goal * roof1, "fp32"))

    def ratio(name, case, goal, ours="ours", of="torch", what="PyTorch"):
        c = one.get(case, {})
        if ours not in c or not c.get(of):
            return
        x = c[ours] / c[of]
        out.append((name, f"{x:.2f}× {what}", x >= goal, goal * c[of],
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


def print_cells(build, roof1, repetitions=3, ref=None, unmeasured=None):
    """Whole cells, one thread, medians of `repetitions` (after one warm-up run on PyTorch's side),
    each cell's row printed when both sides have timed it (a side that could not: a row saying so,
    and (what, why) appended to `unmeasured`). ref: the Reference whose script to run.
    Returns, per PyTorch cell case, our speed-up over PyTorch and PyTorch's GFLOP/s."""
    ref = Reference(ref.script if ref else REFERENCE, repetitions, None)
    unmeasured = [] if unmeasured is None else unmeasured
    exe = os.path.join(build, "bench", "sirl_bench_pipeline")
    print(f"\nWhole cells as a quick run trains them (15 epochs, heads one after another), one "
          f"thread; {medians(repetitions)}.\n")
    print("| cell | ours s | ours GFLOP/s | % of roof | PyTorch s | PyTorch GFLOP/s | speed-up |")
    print("|---|---:|---:|---:|---:|---:|---:|", flush=True)
    measured = {}
    for label, key, case in CELLS:
        med, why_ours = measure(gbench, exe, repetitions, exact([key]))
        torch1, why_torch = measure(ref.run, 1, [case, case + "_stacked"])
        o = med.get(key)
        o = o if o and "GFLOP/s" in o else None
        forms = [torch1[f] for f in (case, case + "_stacked") if f in torch1]
        t = min(forms, key=lambda c: c["ms"]) if forms else None  # its faster form
        if o is None:
            unmeasured.append((case, why_ours or f"ours: no {key} in sirl_bench_pipeline's output"))
        if t is None:
            unmeasured.append((case, why_torch or f"PyTorch on 1 thread: no {case} or "
                                                  f"{case}_stacked in the reference's output"))
        ours_cols = f"not measured | {DASH} | {DASH}"
        if o:
            s = milliseconds(o) * 1e-3
            ours_cols = f"{s:.2f} | {o['GFLOP/s']:.1f} | {pct(o['GFLOP/s'], roof1)}"
        torch_cols = f"{t['ms'] * 1e-3:.2f} | {t['gflops']:.1f}" if t else f"not measured | {DASH}"
        ratio = DASH
        if o and t:
            measured[case] = {"speedup": t["ms"] * 1e-3 / s, "torch": t["gflops"]}
            ratio = f"{t['ms'] * 1e-3 / s:.2f}x"
        print(f"| {label} | {ours_cols} | {torch_cols} | {ratio} |", flush=True)
    return measured


if __name__ == "__main__":
    main()
