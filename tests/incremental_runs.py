#!/usr/bin/python3
"""Incremental runs through the task cache (ctest; Debian's python3), on the smoke plan with
narrow networks (tests/data/engine-test.toml: smoke's tasks, keys and counts, a fraction of its
arithmetic; what is checked here is the cache's bookkeeping):

- one more seed: exactly the new seed's tasks are computed (counted from the cache's new files);
- a comment added and the profile's tables reordered: nothing is computed;
- "sirl.epochs" changed for GridRobot: exactly GridRobot's SIRL-trained representations and every
  task that reads them, directly or not, are computed (the set from `sirl plan --tasks`' inputs
  and the records' methods, not from the engine's digests);
- each resulting file equals a fresh run's (fresh cache) in every table but timings, every
  dataset and record field under /runs (timing excepted) and /datasets;
- two runs of different profiles sharing one fresh cache at once: no task computed twice, both
  files equal fresh runs', the cache's every file sound;
- a corrupted file in the cache is named, never read, and its task computed again;
- `sirl plan --cache` counts what the cache holds; `sirl gc` keeps what a profile needs and
  removes the rest.
"""
import collections
import glob
import json
import os
import shutil
import subprocess
import sys
import tempfile

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

SIRL = sirl_testing.sirl_binary()
SRC = sirl_testing.source_dir()
SMOKE = sirl_testing.data_path("engine-test.toml")
TIMING = {"seconds", "threads"}  # record fields that describe the run, not the result
fail = sirl_testing.make_fail("incremental_runs")


def run(*args, expect=0):
    p = sirl_testing.run_sirl(*args, stdin=None)
    if p.returncode != expect:
        fail(f"sirl {' '.join(args)} exited {p.returncode}, not {expect}:\n{p.stderr[-3000:]}")
    return p


def computed(p):
    """(reused, computed, by another run) from `sirl run`'s summary line (p: a finished process
    or its standard output)."""
    text = p if isinstance(p, str) else p.stdout
    line = [ln for ln in text.splitlines() if ln.startswith("sirl run:")][-1]
    inner = line[line.index("(") + 1:line.index(")")]
    nums = [int(w) for w in inner.replace(",", " ").split() if w.isdigit()]
    return nums[0], nums[1], (nums[2] if len(nums) > 2 else 0)


def cache_keys(cache):
    """{file name: task key} of the committed results in a cache (their /r attributes)."""
    out = {}
    for path in glob.glob(os.path.join(cache, "*.h5")):
        with h5py.File(path, "r") as f:
            out[os.path.basename(path)] = f["r"].attrs["task_key"]
    return out


def plan_inputs(*args):
    """{task key: [keys of the tasks it reads]} from `sirl plan --tasks`."""
    deps = {}
    for line in run("plan", *args, "--tasks").stdout.splitlines():
        words = line.split(" ")
        deps[words[0]] = words[4:]
    return deps


def same(a, b):
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype.kind == "f":
        return a.shape == b.shape and np.array_equal(a, b, equal_nan=True)
    return a.shape == b.shape and np.array_equal(a, b)


def compare_files(got, want):
    """Every table but timings, every dataset and record field under /runs and /datasets."""
    with h5py.File(got, "r") as g, h5py.File(want, "r") as w:
        for name in w["tables"]:
            if name == "timings":
                continue
            wt, gt = w["tables"][name][()], g["tables"][name][()]
            if wt.dtype != gt.dtype or wt.shape != gt.shape:
                fail(f"{got}: /tables/{name} has another shape or columns than a fresh run's")
            for col in wt.dtype.names:
                if not same(gt[col], wt[col]):
                    fail(f"{got}: /tables/{name} column {col} differs from a fresh run's")
        for root in ("runs", "datasets"):
            names = []
            w[root].visit(names.append)
            got_names = []
            g[root].visit(got_names.append)
            if sorted(names) != sorted(got_names):
                fail(f"{got}: /{root} holds other objects than a fresh run's")
            for n in names:
                wo, go = w[root][n], g[root][n]
                if isinstance(wo, h5py.Dataset) and not same(go[()], wo[()]):
                    fail(f"{got}: /{root}/{n} differs from a fresh run's")
                for a in wo.attrs:
                    if a in TIMING:
                        continue
                    if a not in go.attrs or not same(go.attrs[a], wo.attrs[a]):
                        fail(f"{got}: /{root}/{n}@{a} differs from a fresh run's")


def fresh(tmp, name, *args):
    out = os.path.join(tmp, name + "-fresh.h5")
    run("run", *args, "--out", out, "--cache", os.path.join(tmp, name + "-fresh-cache"))
    return out


def reordered_profile(tmp):
    """The profile with comments added and its tables in reverse order (same settings)."""
    lines = open(SMOKE).read().splitlines()
    first = next(i for i, ln in enumerate(lines) if ln.startswith("["))
    blocks, cur = [], []
    for ln in lines[first:]:
        if ln.startswith("[") and cur:
            blocks.append(cur)
            cur = []
        cur.append(ln)
    blocks.append(cur)
    text = "# a comment that changes nothing\n" + "\n".join(lines[:first]) + "\n"
    for b in reversed(blocks):
        text += "\n# another comment\n" + "\n".join(b) + "\n"
    path = os.path.join(tmp, "smoke-reordered.toml")
    with open(path, "w") as f:
        f.write(text)
    return path


def main():
    tmp = tempfile.mkdtemp(prefix="sirl-incremental-")
    try:
        cache = os.path.join(tmp, "cache")
        base = os.path.join(tmp, "base.h5")
        p = run("run", SMOKE, "--out", base, "--cache", cache)
        n_tasks = len(plan_inputs(SMOKE))
        if computed(p) != (0, n_tasks, 0):
            fail(f"a first run computed {computed(p)}, not all {n_tasks} tasks")
        with h5py.File(base, "r") as f:
            records = {}
            for n, o in f["runs"].items():
                o.visititems(lambda k, v: records.__setitem__(v.attrs["task_key"], dict(v.attrs))
                             if "task_key" in v.attrs else None)
            cls = f.attrs["cpu_class"]
            tim = f["tables"]["timings"]
            if not all(c.decode() == cls for c in tim["cpu_class"][()]):
                fail("timings' cpu_class is not the run's class for every task")
            if any(len(d) != 32 for d in tim["task_digest"][()]):
                fail("timings' task_digest is not 32 hex digits for every task")

        # 1. One more seed: exactly its tasks.
        before = cache_keys(cache)
        seeds = ["--set", "seeds=[0,1,2]"]
        p = run("run", SMOKE, *seeds, "--out", os.path.join(tmp, "seeds.h5"), "--cache", cache)
        new = {k for f, k in cache_keys(cache).items() if f not in before}
        deps3 = plan_inputs(SMOKE, *seeds)
        added = set(deps3) - set(plan_inputs(SMOKE))
        if new != added or computed(p)[1] != len(added):
            fail(f"one more seed computed {computed(p)} ({len(new)} new files), "
                 f"not the {len(added)} tasks the seed adds")
        compare_files(os.path.join(tmp, "seeds.h5"), fresh(tmp, "seeds", SMOKE, *seeds))
        print(f"incremental_runs: one more seed: {len(added)} of {len(deps3)} tasks computed")

        # 2. A comment and reordered tables: nothing.
        p = run("run", reordered_profile(tmp), "--out", os.path.join(tmp, "reordered.h5"),
                "--cache", cache)
        if computed(p) != (n_tasks, 0, 0):
            fail(f"a reordered, commented profile computed {computed(p)}")
        compare_files(os.path.join(tmp, "reordered.h5"), base)

        # 3. sirl.epochs for GridRobot: its SIRL-trained φ and everything downstream.
        epochs = ["--set", 'hyper.grid."sirl.epochs"=31']
        deps = plan_inputs(SMOKE, *epochs)
        changed = {k for k, r in records.items()
                   if r.get("env") == "grid" and r.get("task_kind") in ("rep", "active")
                   and r.get("method") == "sirl"}
        if not changed:
            fail("smoke has no GridRobot SIRL representation to change")
        grew = True
        while grew:  # every reader of a changed task, however indirect
            more = {k for k, ins in deps.items() if changed.intersection(ins)} - changed
            changed |= more
            grew = bool(more)
        before = cache_keys(cache)
        p = run("run", SMOKE, *epochs, "--out", os.path.join(tmp, "epochs.h5"), "--cache", cache)
        new = {k for f, k in cache_keys(cache).items() if f not in before}
        if new != changed or computed(p)[1] != len(changed):
            fail(f"sirl.epochs for grid computed {computed(p)}: "
                 f"{sorted(new ^ changed)[:5]} differ from the expected {len(changed)} tasks")
        compare_files(os.path.join(tmp, "epochs.h5"), fresh(tmp, "epochs", SMOKE, *epochs))
        print(f"incremental_runs: grid sirl.epochs: {len(changed)} of {len(deps)} tasks computed")

        # 3b. Both values as a hyper-parameter axis: the base point is the plain run's (cached);
        # the other point's tasks (keys of their own) are computed once, with the bits the
        # changed run gave the same cells.
        axis = ["--set", 'hyper.grid."sirl.epochs"=[30,31]']
        out = os.path.join(tmp, "axis.h5")
        p = run("run", SMOKE, *axis, "--out", out, "--cache", cache)
        if computed(p) != (n_tasks, len(changed), 0):
            fail(f"an axis of sirl.epochs 30 (cached) and 31 computed {computed(p)}, not the "
                 f"{len(changed)} tasks of the new point")
        if computed(run("run", SMOKE, *axis, "--out", out, "--cache", cache))[1] != 0:
            fail("a finished axis run recomputed tasks")
        point = "sirl.epochs=31"
        with h5py.File(out, "r") as f, h5py.File(base, "r") as b, \
                h5py.File(os.path.join(tmp, "epochs.h5"), "r") as e:
            if f.attrs["hyper_points"] != "grid\tsirl.epochs=30\tsirl.epochs=31\n":
                fail(f"/@hyper_points is {f.attrs['hyper_points']!r}")
            for name in ("fpe", "tpa"):
                t = f["tables"][name][()]
                at_base = t[t["hyper_point"] == b""]
                if not all(same(at_base[c], b["tables"][name][()][c]) for c in b["tables"][name].dtype.names):
                    fail(f"/tables/{name}: the base point's rows are not the plain run's")
                own = t[t["hyper_point"] == point.encode()]
                want = e["tables"][name][()]
                # a cell: its fields, and for TPA its M, mode and protocol (paper, linear)
                cell = ("env", "variant", "N", "seed") + (
                    ("M", "frozen") + (("protocol",) if "protocol" in want.dtype.names else ())
                    if name == "tpa" else ())
                keyed = {tuple(r[c] for c in cell): r for r in want}
                if len(own) == 0:
                    fail(f"/tables/{name} has no row at {point}")
                for r in own:
                    k = tuple(r[c] for c in cell)
                    if k not in keyed or not same(r[name], keyed[k][name]):
                        fail(f"/tables/{name} {k} at {point} is not the sirl.epochs=31 run's")
        # The figures: the paper's from the base point only (as the plain run's), and the axis's
        # own figure with the changed run's values at the point.
        figs = {}
        for name, path in (("axis", out), ("base", base), ("epochs", os.path.join(tmp, "epochs.h5"))):
            d = os.path.join(tmp, "figs-" + name)
            p = subprocess.run(["/usr/bin/python3", os.path.join(SRC, "report", "plot_figures.py"),
                                path, "--out", d], capture_output=True, text=True)
            if p.returncode != 0:
                fail(f"plot_figures {name}: {p.stderr[-1500:]}")
            figs[name] = json.load(open(os.path.join(d, "figures.json")))
        for fig in ("fig4", "fig5"):
            if figs["axis"][fig] != figs["base"][fig]:
                fail(f"{fig} of the axis run is not the base point's")
        drawn = figs["axis"].get("hyper", {}).get("grid", {}).get("fpe", {}).get("sirl", {})
        n_max = max(figs["epochs"]["fig4"]["grid"]["sirl"], key=int)
        if set(drawn) != {"sirl.epochs=30", point} or \
                abs(drawn[point] - figs["epochs"]["fig4"]["grid"]["sirl"][n_max]) > 1e-12 or \
                abs(drawn["sirl.epochs=30"] - figs["base"]["fig4"]["grid"]["sirl"][n_max]) > 1e-12:
            fail(f"the axis figure drew {drawn}")
        if "## Hyper-parameter axes" not in open(os.path.join(tmp, "figs-axis", "report.md")).read():
            fail("the report has no section on the hyper-parameter axes")
        print(f"incremental_runs: an axis of both values: {len(changed)} computed, {point} rows "
              "equal the changed run's; figures from the base point, the axis figure from both")

        # 3c. One method's own stop rule ([tpa] stop): exactly that method's TPA cells (every
        # environment's, [tpa]'s and [ablation]'s, frozen and unfrozen) are computed again, their
        # records name the rule, and their values are the base run's: smoke's 20 head epochs are
        # below the rule's 100-epoch minimum, so no head stops sooner.
        rule = ["--set", 'tpa.stop.sirl="converged"']
        ruled = {k for k, r in records.items()
                 if r.get("task_kind") == "tpa" and r.get("variant") == "sirl"}
        before = cache_keys(cache)
        out = os.path.join(tmp, "rule.h5")
        p = run("run", SMOKE, *rule, "--out", out, "--cache", cache)
        new = {k for f, k in cache_keys(cache).items() if f not in before}
        if not ruled or new != ruled or computed(p)[1] != len(ruled):
            fail(f"a stop rule for sirl computed {computed(p)}: {sorted(new ^ ruled)[:5]} differ "
                 f"from SIRL's {len(ruled)} TPA cells")
        with h5py.File(out, "r") as f, h5py.File(base, "r") as b:
            for k, r in records.items():
                if r.get("task_kind") != "tpa":
                    continue
                got, want = f["runs/" + k].attrs, b["runs/" + k].attrs
                if got["stop"] != ("converged" if k in ruled else "fixed") or want["stop"] != "fixed":
                    fail(f"{k}: stop {got['stop']!r} (base {want['stop']!r})")
                if not same(got["tpa"], want["tpa"]):
                    fail(f"{k}: TPA {got['tpa']} under the rule, {want['tpa']} without")
        print(f"incremental_runs: a stop rule for sirl: its {len(ruled)} TPA cells computed, "
              "their records name it, their values unchanged")

        # 4. Two profiles at once on one fresh cache.
        shared = os.path.join(tmp, "shared")
        outs = [os.path.join(tmp, "one.h5"), os.path.join(tmp, "two.h5")]
        procs = [subprocess.Popen([SIRL, "run", SMOKE, *extra, "--out", o, "--cache", shared,
                                   "--threads", "1"],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                 for o, extra in zip(outs, ([], seeds))]
        results = [pr.communicate() for pr in procs]
        for pr, (out, err) in zip(procs, results):
            if pr.returncode != 0:
                fail(f"a concurrent run exited {pr.returncode}:\n{err[-2000:]}")
        counts = [computed(out) for out, _ in results]
        union = set(plan_inputs(SMOKE)) | set(deps3)
        files = cache_keys(shared)
        if len(files) != len(union) or sorted(files.values()) != sorted(union):
            fail(f"the shared cache holds {len(files)} results for {len(union)} distinct tasks")
        if sum(c[1] for c in counts) != len(union):
            fail(f"two runs at once computed {[c[1] for c in counts]}: a task twice or none")
        compare_files(outs[0], base)
        compare_files(outs[1], os.path.join(tmp, "seeds-fresh.h5"))
        p = run("run", SMOKE, *seeds, "--out", os.path.join(tmp, "again.h5"), "--cache", shared)
        if computed(p)[1] != 0:
            fail("after two concurrent runs a third found damaged or missing results")
        print(f"incremental_runs: two runs at once: {[c[1] for c in counts]} computed, "
              f"{[c[2] for c in counts]} waited for, {len(union)} distinct tasks")

        # 5. A corrupted result: named, removed, computed again.
        # A task of smoke's own plan that no earlier --set step filed under another digest.
        # (A key filed twice, e.g. under the stop rule's settings, may be the copy smoke never reads.)
        entries = sorted(cache_keys(cache).items())
        count = collections.Counter(k for _, k in entries)
        smoke_tasks = plan_inputs(SMOKE)
        candidates = [e for e in entries if count[e[1]] == 1 and e[1] in smoke_tasks]
        if not candidates:
            fail("no task of smoke's plan is filed exactly once in the cache")
        fixed = [e for e in candidates if e[1] == "grid/s0/sirl/N100/fpe"]
        victim_file, victim_key = fixed[0] if fixed else candidates[0]
        with open(os.path.join(cache, victim_file), "r+b") as f:
            f.seek(-100, os.SEEK_END)
            b = f.read(1)
            f.seek(-100, os.SEEK_END)
            f.write(bytes([b[0] ^ 0xFF]))
        out = os.path.join(tmp, "healed.h5")
        p = run("run", SMOKE, "--out", out, "--cache", cache)
        if victim_key not in p.stderr or "corrupted" not in p.stderr:
            fail(f"a corrupted result of {victim_key} was not named:\n{p.stderr[-2000:]}")
        if victim_key in plan_inputs(SMOKE) and computed(p)[1] != 1:
            fail(f"after corrupting {victim_key} the run computed {computed(p)}, not 1 task")
        compare_files(out, base)

        # 6. plan --cache and gc.
        text = run("plan", SMOKE, *seeds, "--cache", cache).stdout
        if f"cache {cache}: {len(deps3)} of {len(deps3)} tasks" not in text:
            fail(f"sirl plan --cache did not count the cached tasks:\n{text[-800:]}")
        run("gc", cache, expect=2)  # neither profiles nor --all
        p = run("gc", cache, SMOKE, "--dry-run")
        kept_before = len(cache_keys(cache))
        run("gc", cache, SMOKE)
        left = set(cache_keys(cache).values())
        if left != set(plan_inputs(SMOKE)):
            fail(f"gc kept {len(left)} results, not smoke's {n_tasks} (had {kept_before})")
        p = run("run", SMOKE, "--out", os.path.join(tmp, "after-gc.h5"), "--cache", cache)
        if computed(p)[1] != 0:
            fail("gc removed a result smoke needs")
        run("gc", cache, "--all")
        if cache_keys(cache):
            fail("gc --all left results behind")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print("incremental_runs: OK")


if __name__ == "__main__":
    main()
