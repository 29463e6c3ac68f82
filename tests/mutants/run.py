#!/usr/bin/python3
"""The mutation check: apply each mutation of tests/mutants/mutants.py to a scratch copy of the
repository, rebuild incrementally, run the tests that should catch it, report caught / survived.

    /usr/bin/python3 tests/mutants/run.py [--scratch DIR] [--only N,M] [--report FILE]

It takes minutes (one incremental build per mutant), not seconds: bench/nightly runs it, not CI.
A mutant is caught when the named tests fail (a gtest filter, or "ctest:NAME" for an end-to-end
test); a mutant that does not compile is reported separately (the mutation was not plausible).
"""
import argparse
import os
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
from mutants import EQUIVALENT, MUTANTS  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--scratch", default="/tmp/sirl-mutants", help="scratch copy (rebuilt incrementally)")
ap.add_argument("--only", default="", help="comma-separated mutant numbers")
ap.add_argument("--report", default="", help="write the report (markdown) here too")
a = ap.parse_args()


def sh(cmd, cwd, timeout=1800):
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout,
                          stdin=subprocess.DEVNULL)


# A scratch copy of the tracked files at HEAD (the working tree's edits included), built once.
os.makedirs(a.scratch, exist_ok=True)
files = sh(["git", "ls-files"], SRC).stdout.split()
for f in files:
    dst = os.path.join(a.scratch, f)
    os.makedirs(os.path.dirname(dst), exist_ok=True)
    if not os.path.exists(dst) or open(os.path.join(SRC, f), "rb").read() != open(dst, "rb").read():
        # A fresh mtime (not copy2's): objects built from an older content must not look newer.
        shutil.copy(os.path.join(SRC, f), dst)
build = os.path.join(a.scratch, "build", "release")
if not os.path.exists(os.path.join(build, "build.ninja")):
    p = sh(["cmake", "--preset", "release", "-DSIRL_BUILD_BENCH=OFF"], a.scratch)
    if p.returncode:
        sys.exit("configure failed:\n" + p.stderr[-3000:])
p = sh(["cmake", "--build", "--preset", "release", "--target", "sirl_tests"], a.scratch)
if p.returncode:
    sys.exit("the unmutated scratch copy does not build:\n" + p.stdout[-3000:])
tests = os.path.join(build, "tests", "sirl_tests")

only = {int(x) for x in a.only.split(",") if x}
rows, caught, survived, broken = [], 0, 0, 0
for n, (path, old, new, filt, what) in enumerate(MUTANTS, 1):
    if only and n not in only:
        continue
    target = os.path.join(a.scratch, path)
    text = open(target).read()
    if text.count(old) != 1:
        rows.append((n, path, what, "NOT APPLIED", f"the text occurs {text.count(old)} times"))
        broken += 1
        continue
    t0 = time.time()
    open(target, "w").write(text.replace(old, new))
    try:
        # an end-to-end test runs the `sirl` binary: rebuild it too
        targets = ["sirl_tests"] + (["sirl"] if filt.startswith("ctest:") else [])
        b = sh(["cmake", "--build", "--preset", "release", "--target", *targets], a.scratch)
        if b.returncode:
            verdict, detail = "compile error", "the mutant does not compile"
            broken += 1
        else:
            if filt.startswith("ctest:"):  # an end-to-end test (minutes): ctest -R NAME
                r = sh(["ctest", "-R", filt[len("ctest:"):], "--output-on-failure"], build,
                       timeout=1800)
            else:
                r = sh([tests, f"--gtest_filter={filt}", "--gtest_brief=1"], build, timeout=900)
            if r.returncode:
                failed = [l.split("] ")[1].split(" (")[0] for l in r.stdout.splitlines()
                          if l.startswith("[  FAILED  ]") and "(" in l]
                verdict, detail = "caught", ", ".join(failed[:3]) or f"{filt} failed"
                caught += 1
            else:
                verdict = "survived"
                detail = EQUIVALENT.get(what, f"{filt} passed")
                survived += 1
    finally:
        open(target, "w").write(text)
    rows.append((n, path, what, verdict, detail))
    print(f"{n:3d} {verdict:13s} {time.time() - t0:5.0f} s  {path}: {what} — {detail}", flush=True)

# Restore the scratch build to the unmutated code.
sh(["cmake", "--build", "--preset", "release", "--target", "sirl_tests", "sirl"], a.scratch)
applied = caught + survived
lines = [f"# Mutation check ({time.strftime('%Y-%m-%d')})", "",
         f"{caught} of {applied} applied mutants caught ({100.0 * caught / max(1, applied):.0f} %); "
         f"{survived} survived; {broken} not applied or not compiling.", "",
         "| # | file | mutation | verdict | detail |", "|---|---|---|---|---|"]
lines += [f"| {n} | {p} | {w} | {v} | {d} |" for n, p, w, v, d in rows]
report = "\n".join(lines) + "\n"
print(report)
if a.report:
    with open(a.report, "w") as f:
        f.write(report)
sys.exit(0 if survived == 0 else 1)
