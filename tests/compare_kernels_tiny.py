#!/usr/bin/python3
"""bench/compare_kernels.py end to end on tiny shapes (--tiny: the GridRobot cases, one repetition
of 0.1 s a benchmark, no whole cells), both sides for real: the C++ benchmarks of SIRL_BUILD_DIR
and bench/torch_reference.py. Exit 0; one row per case and thread count with both sides' numbers
(positive, finite) and the speed-up their quotient; torch_reference.py's "baseline" entry (what
PyTorch ran on) printed as such, never a row. Then, against a stand-in reference (no torch, fixed
numbers): two 1-thread processes summed, a case the reference leaves out and a refused 2-thread run
reported as rows saying so (exit 1 after every table), and rows already printed when the run dies
part-way. SIRL_COMPARE_KERNELS overrides the script (to run this test against another version)."""
import math
import os
import signal
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

SRC = os.environ["SIRL_SOURCE_DIR"]
BUILD = os.environ["SIRL_BUILD_DIR"]
SCRIPT = os.environ.get("SIRL_COMPARE_KERNELS", os.path.join(SRC, "bench", "compare_kernels.py"))
PY = "/usr/bin/python3"
# Block-buffered output when piped, as a plain run has it: rows must be flushed as they are printed.
ENV = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
GRID_STEP = "SIRL step, Grid 19→128→128→6, 64 triplets"
GRID_HEADS = "20 TPA heads 6→128→128→1, 64 pairs"
FORMS = {GRID_STEP: ("sirl_step_grid", "sirl_step_grid_stacked"),
         GRID_HEADS: ("tpa_heads_grid", "tpa_heads_grid_batched")}
FP32_HEADER = "| case | threads | ours ms | ours GFLOP/s |"
BF16_HEADER = "| case | threads | ours bf16 ms |"


fail = sirl_testing.make_fail("compare_kernels_tiny")


def compare(*args, timeout=240):
    t0 = time.monotonic()
    try:
        p = subprocess.run([PY, SCRIPT, "--build", BUILD, *args], capture_output=True, text=True,
                           stdin=subprocess.DEVNULL, env=ENV, timeout=timeout)
    except subprocess.TimeoutExpired as e:
        fail(f"{SCRIPT} {' '.join(args)} still running after {timeout} s; stdout so far:\n"
             f"{e.stdout}")
    return p, time.monotonic() - t0


def table(out, header):
    """The rows of the Markdown table whose header line starts with `header`: lists of cells."""
    lines = out.splitlines()
    starts = [i for i, ln in enumerate(lines) if ln.startswith(header)]
    if len(starts) != 1:
        return None
    rows = []
    for ln in lines[starts[0] + 2:]:  # past the header and the |---| line
        if not ln.startswith("|"):
            break
        rows.append([c.strip() for c in ln.strip().strip("|").split("|")])
    return rows


def number(text, suffix="", p=None, zero_ok=False):
    """A printed number (a rate, a time, a ratio, a share): finite and positive (or zero, if
    zero_ok), ending in `suffix`; else the test fails."""
    x = math.nan
    if text.endswith(suffix):
        try:
            x = float(text[:len(text) - len(suffix)])
        except ValueError:
            pass
    if not (math.isfinite(x) and (x > 0 or (zero_ok and x == 0))):
        fail(f"{text!r} is not a positive finite number{' with ' + repr(suffix) if suffix else ''}",
             p)
    return x


def quotient_of(ratio, num, den, num_step=0.05, ratio_step=0.005):
    """Whether a printed ratio (2 decimals) can be the quotient of two printed rates (1 decimal):
    the exact quotient of some values that round to them, rounded."""
    lo = (num - num_step) / (den + num_step) - ratio_step
    hi = (num + num_step) / (den - num_step) + ratio_step if den > num_step else math.inf
    return lo <= ratio <= hi


def rows_by_case(rows, p):
    got = {}
    for r in rows:
        if len(r) != 8:
            fail(f"a row of {len(r)} cells, not 8: {r}", p)
        key = (r[0], int(r[1]))
        if key in got:
            fail(f"two rows for {key}", p)
        got[key] = r
    want = {(case, t) for case in FORMS for t in (1, 2)}
    if set(got) != want:
        fail(f"rows {sorted(got)}, want one for each of {sorted(want)}", p)
    return got


def no_baseline_row(p):
    for header in (FP32_HEADER, BF16_HEADER, "| target |"):
        for r in table(p.stdout, header) or []:
            if any("baseline" in c.lower() for c in r):
                fail(f"a row made of the reference's \"baseline\" entry: {r}", p)


# --- 1. For real: the C++ benchmarks and PyTorch, tiny shapes.
p, seconds = compare("--tiny")
if p.returncode != 0:
    fail("compare_kernels.py --tiny did not exit 0", p)
fp32 = table(p.stdout, FP32_HEADER)
if fp32 is None:
    fail("no fp32 table", p)
fp32 = rows_by_case(fp32, p)
for (case, threads), r in fp32.items():
    _, _, ms, ours, share, form, torch, ratio = r
    number(ms, p=p), number(share, " %", p, zero_ok=True)  # a share of the roof may round to 0 %
    ours, torch, ratio = number(ours, p=p), number(torch, p=p), number(ratio, "x", p)
    if not quotient_of(ratio, ours, torch):
        fail(f"{case}, {threads} thread(s): speed-up {ratio} is not {ours} / {torch}", p)
    name, how = form.split(", ", 1)
    if name not in FORMS[case] or how not in (
            ("1 thread",) if threads == 1 else ("2 threads", "2 processes")):
        fail(f"{case}, {threads} thread(s): best PyTorch form {form!r}", p)
print(f"ok: --tiny exits 0 in {seconds:.0f} s with one row per case and thread count, both sides "
      "measured, the speed-up their quotient")

# The bf16 rows (this CPU's bf16 products: native or emulated) against the same PyTorch forms.
for r in table(p.stdout, BF16_HEADER) or []:
    case, threads, ms, g16, share, vs32, form, ratio = r
    f32 = fp32[(case, int(threads))]
    number(ms, p=p), number(share, " %", p, zero_ok=True)
    g16, vs32, ratio = number(g16, p=p), number(vs32, "x", p), number(ratio, "x", p)
    if form != f32[5] or not quotient_of(ratio, g16, number(f32[6], p=p)) or \
            not quotient_of(vs32, g16, number(f32[3], p=p)):
        fail(f"bf16 row {r} against fp32 row {f32}", p)

no_baseline_row(p)
if "PyTorch baseline (torch_reference.py's own record): torch " not in p.stdout:
    fail("the reference's baseline (what PyTorch ran on) is not printed", p)
targets = table(p.stdout, "| target |")
if not targets or not all(r[0].startswith(("Grid", "20 Grid")) for r in targets):
    fail(f"the targets table on the Grid cases: {targets}", p)
print("ok: the reference's \"baseline\" entry is printed as what PyTorch ran on, never a row; "
      "the bf16 and targets tables follow")

# --- 2. A stand-in reference: fixed rates, tpa_heads_grid left out, --threads 2 refused; and in
# a third run, it kills compare_kernels.py when asked for the second case.
STAND_IN = r'''
import json, os, signal, sys
a = sys.argv[1:]
threads, cases = int(a[a.index("--threads") + 1]), a[a.index("--cases") + 1].split(",")
if os.environ.get("STAND_IN_KILL") and "tpa_heads_grid" in cases:
    os.kill(os.getppid(), signal.SIGKILL)
    sys.exit(0)
if threads == 2:
    sys.exit("torch_reference: with --threads 2 these cases used more than two cores (stand-in)")
rates = {"sirl_step_grid": 2.0, "sirl_step_grid_stacked": 1.0}
out = {"torch": "stand-in", "threads": threads,
       "baseline": {"torch": "stand-in", "config": "default", "threads": threads,
                    "ms": 1e-9, "gflops": 1e9},
       "notes": {"ms": 1e-9, "gflops": 1e9},
       "tpa_heads_grid_extra": {"ms": 1e-9, "gflops": 1e9}}
out.update({c: {"ms": 1.0 / rates[c], "gflops": rates[c]} for c in cases if c in rates})
print(json.dumps(out))
'''
with tempfile.TemporaryDirectory() as tmp:
    stand_in = os.path.join(tmp, "stand_in_reference.py")
    with open(stand_in, "w") as f:
        f.write(STAND_IN)
    p, seconds = compare("--tiny", "--reference", stand_in)
    if p.returncode != 1 or "measurement(s) missing" not in p.stderr:
        fail("with a case missing on PyTorch's side: not exit 1 with the missing ones named", p)
    got = rows_by_case(table(p.stdout, FP32_HEADER), p)
    want_torch = {(GRID_STEP, 1): ("sirl_step_grid, 1 thread", 2.0),
                  (GRID_STEP, 2): ("sirl_step_grid, 2 processes", 4.0)}  # 2.0 + 2.0, at once
    for key, r in got.items():
        ours = number(r[3], p=p)
        if key in want_torch:
            form, rate = want_torch[key]
            if r[5] != form or r[6] != f"{rate:.1f}" or \
                    not quotient_of(number(r[7], "x", p), ours, rate):
                fail(f"{key}: {r}, want {form}, {rate} and {ours} / {rate}", p)
        elif r[5:] != ["not measured", "—", "—"]:
            fail(f"{key}: {r}, want PyTorch's side reported as not measured", p)
    no_baseline_row(p)
    if "1000000000" in p.stdout or "1e+09" in p.stdout:
        fail("an entry that is not an asked-for case was taken as one", p)
    for what in ("- tpa_heads_grid: PyTorch on 1 thread: no tpa_heads_grid or "
                 "tpa_heads_grid_batched in the reference's output",
                 "- sirl_step_grid: PyTorch on 2 threads: exit 1: torch_reference: with --threads 2"):
        if what not in p.stdout:
            fail(f"the list of what was not measured lacks {what!r}", p)
    print(f"ok: stand-in reference ({seconds:.0f} s): two 1-thread processes summed, a case left "
          "out and a refused run are rows saying so, exit 1 after every table")

    env = dict(ENV, STAND_IN_KILL="1")
    p = subprocess.run([PY, SCRIPT, "--build", BUILD, "--tiny", "--reference", stand_in],
                       capture_output=True, text=True, stdin=subprocess.DEVNULL, env=env,
                       timeout=240)
    if p.returncode != -signal.SIGKILL:
        fail("the stand-in did not kill the run part-way", p)
    rows = table(p.stdout, FP32_HEADER) or []
    if sorted((r[0], r[1]) for r in rows) != [(GRID_STEP, "1"), (GRID_STEP, "2")] or \
            any(r[5] == "not measured" or r[3] == "—" for r in rows):
        fail(f"killed at the second case: the first case's rows were not printed: {rows}", p)
    print("ok: a run killed at its second case has printed the first case's rows")
print("compare_kernels tiny: ok")
