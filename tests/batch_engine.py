#!/usr/bin/python3
"""End-to-end checks of `sirl run` (ctest; Debian's python3 + h5py + pandas), on the smoke
profile's plan with narrow networks (tests/data/engine-test.toml: the same tasks and keys, a
fraction of the arithmetic), and once on smoke itself:

- the result tables are bit-identical for --threads 1 and --threads 2 (smoke and engine-test);
- a run killed with SIGKILL mid-way, then rerun, ends with the same file as a fresh run (every
  dataset and attribute under /runs, timing fields excepted) and recomputes nothing committed;
- a results file missing some cells (and JacoRobot's weights, which are not stored by default)
  resumes to the same file: the representations whose weights are gone are computed again;
- every representation stores its embedding of Ξ; weights are stored per store_weights;
- two shards merged equal the single-process run; a shard of another profile is refused;
- a file from another profile is refused (exit 2) unless --force; so is writing a shard into a
  whole run's file (it would drop half the tasks), and a second run on an --out being written;
- pandas reads /tables/* directly; `sirl export --csv` writes the same rows.
"""
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np
import pandas as pd

SIRL = os.environ["SIRL"]
SRC = os.environ["SIRL_SOURCE_DIR"]
sys.path.insert(0, os.path.join(SRC, "python"))
import sirl_bench  # noqa: E402
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

REAL_SMOKE = os.path.join(SRC, "configs", "smoke.toml")
SMOKE = os.path.join(SRC, "tests", "data", "engine-test.toml")


def run(*args, check=True):
    p = subprocess.run([SIRL, *args], capture_output=True, text=True, stdin=subprocess.DEVNULL)
    if check and p.returncode != 0:
        sys.exit(f"FAIL: sirl {' '.join(args)} exited {p.returncode}\n{p.stdout}\n{p.stderr}")
    return p


def tables(path):
    with h5py.File(path, "r") as f:
        assert f.attrs["complete"] == 1, f"{path} is not complete"
        return {k: pd.DataFrame(f["tables/" + k][:]) for k in ("fpe", "tpa")}


def params(path):
    with h5py.File(path, "r") as f:
        keys = [k.decode() for k in f["runs_index"][:]]
        return {k: f["runs/" + k + "/params"][:] for k in keys if "runs/" + k + "/params" in f}


# The only fields that may differ between two runs of one profile (threads: the cores the
# scheduler gave a task).
TIMING = {"seconds", "threads"}


def runs_tree(path):
    """Every dataset and attribute under /runs: {path: value} (timing fields excepted)."""
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            for a, v in obj.attrs.items():
                if a not in TIMING:
                    out[f"{name}@{a}"] = v.tolist() if hasattr(v, "tolist") else v
            if isinstance(obj, h5py.Dataset):
                out[name] = obj[:]
        f["runs"].visititems(visit)
    return out


def same_runs(a, b, what):
    ta, tb = runs_tree(a), runs_tree(b)
    if ta.keys() != tb.keys():
        sys.exit(f"FAIL: {what}: objects differ: only in first {sorted(ta.keys() - tb.keys())[:5]}, "
                 f"only in second {sorted(tb.keys() - ta.keys())[:5]}")
    for k in ta:
        x, y = ta[k], tb[k]
        eq = np.array_equal(x, y) if isinstance(x, np.ndarray) else x == y
        if not eq:
            sys.exit(f"FAIL: {what}: {k} differs: {str(x)[:200]} vs {str(y)[:200]}")
    print(f"ok: {what} ({len(ta)} datasets and attributes under /runs)")


def reseal(path):
    """Writes a results file's checksum frame (its first 1024 bytes) for its bytes as they are now
    (XXH3-128 of bytes 1024 on, by xxHash's own xxh128sum), after a deliberate edit with h5py."""
    with open(path, "rb") as f:
        f.seek(1024)
        digest = subprocess.run(["xxh128sum", "-"], input=f.read(), capture_output=True,
                                check=True).stdout.split()[0]
    frame = (b"SIRLRESULTS2\nxxh3-128 " + digest + b"\n").ljust(1024, b"\0")
    with open(path, "r+b") as f:
        f.write(frame)


def same(a, b, what):
    for k in a:
        if not a[k].equals(b[k]):
            sys.exit(f"FAIL: {what}: table {k} differs\n{a[k].compare(b[k])}")
    print(f"ok: {what}")


with tempfile.TemporaryDirectory() as tmp:
    # smoke's real widths (Grid's 128-wide layers: several GEMM slices per product).
    s1, s2 = os.path.join(tmp, "smoke1.h5"), os.path.join(tmp, "smoke2.h5")
    run("run", REAL_SMOKE, "--out", s1, "--threads", "1", "--quiet")
    # The --threads 2 side: the smoke fixture's file (`sirl run smoke --threads 2 --quiet` from an
    # empty cache, by this binary), or computed here without the fixture.
    if not sirl_testing.copy_fixture("smoke", s2, with_cache=False):
        run("run", REAL_SMOKE, "--out", s2, "--threads", "2", "--quiet")
    same(tables(s1), tables(s2), "smoke: --threads 1 and --threads 2 give identical tables")
    same_runs(s1, s2, "smoke: --threads 1 and --threads 2 give identical files")

    one = os.path.join(tmp, "one.h5")
    two = os.path.join(tmp, "two.h5")
    run("run", SMOKE, "--out", one, "--threads", "1", "--quiet")
    if not sirl_testing.copy_fixture("engine-test", two, with_cache=False):  # as s2 above
        run("run", SMOKE, "--out", two, "--threads", "2", "--quiet")
    ref = tables(one)
    with h5py.File(one, "r") as f:
        n_all = int(f.attrs["tasks_total"])
    same(ref, tables(two), "--threads 1 and --threads 2 give identical tables")
    same_runs(one, two, "--threads 1 and --threads 2 give identical files")
    # A big task alone in the ready queue takes both cores (here a frozen TPA cell of 17 GFLOP
    # and 10 MiB, which waits for its φ): the same bits as on one core, and the timings say so.
    wide = os.path.join(SRC, "tests", "data", "wide.toml")
    w1, w2 = os.path.join(tmp, "wide1.h5"), os.path.join(tmp, "wide2.h5")
    run("run", wide, "--out", w1, "--threads", "1", "--quiet")
    run("run", wide, "--out", w2, "--threads", "2", "--quiet")
    same(tables(w1), tables(w2), "a task on 2 cores gives the tables it gives on 1")
    same_runs(w1, w2, "a task on 2 cores gives the file it gives on 1")
    widths = {}
    for path in (w1, w2):
        with h5py.File(path, "r") as f:
            t = pd.DataFrame(f["tables/timings"][:])
        widths[path] = dict(zip(t.key.str.decode("utf-8"), t.threads))
    assert set(widths[w1].values()) == {1}, widths[w1]
    assert widths[w2]["grid/s0/sirl/N200/tpa/M40/frozen"] == 2, widths[w2]
    assert widths[w2]["grid/s0/sirl/N200/rep"] == 1, widths[w2]  # small steps: one core
    print(f"ok: on 2 threads the lone TPA cell ran on 2 cores ({widths[w2]})")
    # More threads than the process may use: one line says so, the run uses the cores it has.
    cores = len(os.sched_getaffinity(0))
    w3 = os.path.join(tmp, "wide3.h5")
    err = run("run", wide, "--out", w3, "--threads", "4096", "--quiet").stderr
    assert f"--threads 4096 is more than the {cores} core(s)" in err, err
    same(tables(w1), tables(w3), "--threads 4096 gives the tables --threads 1 gives")
    with h5py.File(w3, "r") as f:
        t = pd.DataFrame(f["tables/timings"][:])
        assert int(f.attrs["threads"]) == cores, dict(f.attrs)
    assert t.threads.max() <= cores, t
    print(f"ok: --threads 4096 ran on this machine's {cores} cores, with one line saying so")
    p1 = params(one)
    with h5py.File(one, "r") as f:
        keys = [k.decode() for k in f["runs_index"][:]]
        reps = [k for k in keys if k.endswith("/rep") and not k.startswith("study/")]
        # The user study ran as tasks of the plan: 2 seeds × (SIRL, Random), 4 users × (Held-out
        # φ, TPA), one simulated-TPA task, the analysis; its networks are never kept in the
        # results file.
        study = [k for k in keys if k.startswith("study/")]
        assert len(study) == 2 * 2 + 4 * 2 + 1 + 1, study
        assert not any(k in p1 for k in study), "study weights in the results file"
        seeded = [k for k in study if re.match(r"study/s\d+/(sirl|random)/rep$", k)]
        assert len(seeded) == 4 and all(0 < f[f"runs/{k}"].attrs["fpe"] < 1 for k in seeded), \
            "every study φ of a training seed has its FPE"
        for k in reps:
            env = f[f"runs/{k}"].attrs["env"]  # the record's field, not a piece of its key
            env = env.decode() if isinstance(env, bytes) else env
            T = f[f"datasets/{env}/inputs"].shape[0]
            e = f[f"runs/{k}/embedding"]
            assert e.shape == (T, 6), (k, e.shape)
            # weights: GridRobot's are kept, JacoRobot's are not (store_weights defaults)
            assert (k in p1) == (not env.startswith("jaco")), k
        vaes = [k.decode() for k in f["runs_index"][:] if k.decode().endswith("/vae")]
        assert vaes and all(f[f"runs/{k}/kl_per_dim"].shape == (6,) for k in vaes)
    print(f"ok: {len(reps)} embeddings [T, 6] stored; weights for GridRobot only ({len(p1)} arrays)")

    # An independent oracle for FPE: numpy's least squares on the stored embedding, the stored
    # normalised features and the stored split (the queries of the first seed) must give the
    # table's fpe and train_mse for every seed-0 cell (swapped columns, a probe fitted on the
    # test rows, or a wrong target would all differ far beyond the tolerance, which only absorbs
    # float32 embeddings against double least squares).
    with h5py.File(one, "r") as f:
        fpe = pd.DataFrame(f["tables/fpe"][:])
        for c in ("env", "variant"):
            fpe[c] = fpe[c].str.decode("utf-8")
        checked = 0
        # The references (truth, raw) have no rep task: tests/test_linear_tpa.cpp checks them.
        methods = fpe[fpe.reference == 0] if "reference" in fpe else fpe
        for _, row in methods[methods.seed == 0].iterrows():
            g = f"datasets/{row.env}"
            key = f"{row.env}/s0/{row.variant}" + (f"/N{row.N}" if row.N else "") + "/rep"
            E = f[f"runs/{key}/embedding"][:].astype(np.float64)
            Y = f[f"{g}/features"][:].astype(np.float64)
            tr, te = f[f"{g}/queries/fpe/train"][:], f[f"{g}/queries/fpe/test"][:]
            A = np.hstack([E, np.ones((len(E), 1))])
            beta = np.linalg.lstsq(A[tr], Y[tr], rcond=None)[0]
            test_mse = float(np.mean((A[te] @ beta - Y[te]) ** 2))
            train_mse = float(np.mean((A[tr] @ beta - Y[tr]) ** 2))
            assert abs(test_mse - row.fpe) <= 1e-4 * max(1e-3, test_mse), (key, test_mse, row.fpe)
            assert abs(train_mse - row.train_mse) <= 1e-4 * max(1e-3, train_mse), (key, train_mse)
            checked += 1
        assert checked >= 10, checked
    print(f"ok: FPE and train_mse of {checked} cells equal numpy's least squares on the stored "
          "embedding and split")

    # pandas reads the tables as the README promises; the table covers the grid.
    tpa = pd.DataFrame(h5py.File(one, "r")["tables/tpa"][:])
    for col in ("env", "method", "variant", "vae", "frozen", "N", "M", "seed", "tpa", "tpa_std"):
        assert col in tpa.columns, col
    assert tpa["tpa"].between(0, 1).all() and np.isfinite(tpa["tpa"]).all()
    assert set(tpa["seed"]) == {0, 1}
    print(f"ok: pandas reads /tables/tpa ({len(tpa)} rows)")

    # Killed mid-run (at an exact point: SIRL_CRASH_AFTER_COMMITS ends the process like kill -9
    # right after its 20th commit), rerun, compare.
    killed = os.path.join(tmp, "killed.h5")
    crash = dict(os.environ, SIRL_CRASH_AFTER_COMMITS="20")
    child = subprocess.run([SIRL, "run", SMOKE, "--out", killed, "--threads", "2", "--quiet"],
                           stdin=subprocess.DEVNULL, env=crash)
    assert child.returncode == 137, child.returncode
    staging = killed + ".tasks"
    committed = len([f for f in os.listdir(staging) if f.endswith(".h5")])
    assert committed == 20, committed
    assert not os.path.exists(killed), "a killed run must not leave a results file behind"
    out = run("run", SMOKE, "--out", killed, "--threads", "2").stdout
    reused = int(out.split("(")[1].split(" reused")[0])
    assert reused >= committed, f"rerun reused {reused} < {committed} committed tasks:\n{out}"
    same(ref, tables(killed), f"killed after {committed} commits, resumed ({reused} reused): same tables")
    same_runs(one, killed, "killed and resumed: the same file as a fresh run")
    kept = len([f for f in os.listdir(staging) if f.endswith(".h5")])
    assert kept == n_all, f"the task cache keeps every task: {kept} files"
    out = run("run", SMOKE, "--out", killed).stdout
    assert "0 computed" in out, out
    print("ok: rerunning a finished file recomputes nothing")

    # A full disk (simulated by a file-size limit: writes fail with EFBIG as they would with
    # ENOSPC): one line naming the cause, exit 1 and no crash, nothing half-written left behind,
    # and once there is room again the rerun reuses every committed task.
    import resource

    def limited(size):
        def f():
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))
        return f
    for size, where in ((3_000_000, "the results file could not be written"),
                        (20_000, "cannot save task")):
        full = os.path.join(tmp, f"full{size}.h5")
        p = subprocess.run([SIRL, "run", SMOKE, "--out", full, "--quiet"], preexec_fn=limited(size),
                           capture_output=True, text=True, stdin=subprocess.DEVNULL)
        assert p.returncode == 1 and where in p.stderr and "File too large" in p.stderr, \
            (p.returncode, p.stderr[-500:])
        assert p.stderr.count("\n") == 1, p.stderr
        leftovers = [n for n in os.listdir(tmp) if n.startswith(f"full{size}.h5.partial")]
        if os.path.isdir(full + ".tasks"):
            leftovers += [n for n in os.listdir(full + ".tasks") if n.endswith(".tmp")]
        assert not leftovers, leftovers
        out = run("run", SMOKE, "--out", full, "--threads", "2").stdout
        same(ref, tables(full), f"a write failing for want of space ({p.stderr.strip()[:90]}...), "
             "then resumed")

    # Killed during `sirl reproduce`'s user-study part (on one thread the commit order is fixed:
    # after 200 commits some study tasks are done and others are not), rerun: every committed
    # study task is reused, not recomputed, and the study report is written.
    study_out = os.path.join(tmp, "study.h5")
    figs = os.path.join(tmp, "study-figures")
    child = subprocess.run([SIRL, "reproduce", "--profile", SMOKE, "--out", study_out,
                            "--figures", figs, "--threads", "1"], stdin=subprocess.DEVNULL,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                           env=dict(os.environ, SIRL_CRASH_AFTER_COMMITS="200"))
    assert child.returncode == 137, child.returncode
    staging = study_out + ".tasks"
    seen, before = set(), {}
    for name in os.listdir(staging):
        if not name.endswith(".h5"):
            continue
        seen.add(name)
        with h5py.File(os.path.join(staging, name), "r") as f:
            key = f["r"].attrs["task_key"]
            key = key.decode() if isinstance(key, bytes) else key
            if key.startswith("study/"):  # params are dropped from the results file later
                before[key] = {a: f["r"].attrs[a] for a in f["r"].attrs
                               if a not in ("seconds", "threads", "record_arrays", "record_checksum")}
    assert len(seen) == 200, len(seen)
    assert 0 < len(before) < 14, f"the crash point is not inside the study part: {len(before)} " \
        "of 14 study tasks committed (the smoke plan changed: choose another count)"
    p = run("reproduce", "--profile", SMOKE, "--out", study_out, "--figures", figs,
            "--threads", "2")
    out = p.stdout + p.stderr
    reused = int(re.search(r"\((\d+) reused", out).group(1))
    assert reused >= len(seen), f"rerun reused {reused} < {len(seen)} committed tasks:\n{out}"
    with h5py.File(study_out, "r") as f:
        for key, attrs in before.items():
            after = f["runs/" + key].attrs
            for a, v in attrs.items():
                assert np.array_equal(np.asarray(after[a]), np.asarray(v)), (key, a)
    assert os.path.exists(os.path.join(figs, "study", "study_report.md"))
    # Fig. 6 was drawn from the results file's /tables/study (the analysis task's rows): the
    # reader rebuilds from it exactly the arrays `sirl study analyze` computes in one call on the
    # cohort reproduce wrote, with the profile's [study] settings.
    analyzed = os.path.join(tmp, "study-one-call")
    run("study", "analyze", os.path.join(figs, "study", "simulated_study.h5"), "--out", analyzed,
        "--seeds", "2", "--splits", "3", "--epochs", "5", "--tpa-epochs", "5")
    from_table, from_file = sirl_bench.study_analysis(study_out), sirl_bench.study_analysis(
        os.path.join(analyzed, "study_analysis.h5"))
    arrays = [k for k in from_file if k != "attrs"]
    assert sorted(arrays) == sorted(k for k in from_table if k != "attrs"), \
        (arrays, list(from_table))
    text = [x.decode() if isinstance(x, bytes) else x for x in from_file["participants"]]
    assert list(from_table["participants"]) == text, (list(from_table["participants"]), text)
    for k in arrays:
        if k != "participants":
            assert np.array_equal(np.asarray(from_table[k]), np.asarray(from_file[k]),
                                  equal_nan=True), k
    for k in ("env", "triplets", "seeds", "cv_splits", "sirl_epochs", "tpa_epochs", "random_mode"):
        assert from_table["attrs"][k] == from_file["attrs"][k], \
            (k, from_table["attrs"][k], from_file["attrs"][k])
    assert len(from_table["real_sirl"]) == 4 and len(from_table["fpe_sirl"]) == 2, from_table
    print(f"ok: killed during the study part ({len(before)} study tasks committed), rerun reused "
          f"{reused} tasks and kept the committed study results; the study report is written")

    # A results file that lost some cells: the JacoRobot cells need φ's weights, which the file
    # does not keep (store_weights = false), so their representations are computed again.
    holed = os.path.join(tmp, "holed.h5")
    with open(one, "rb") as src, open(holed, "wb") as dst:
        dst.write(src.read())
    with h5py.File(holed, "r+") as f:
        keys = [k.decode() for k in f["runs_index"][:]]
        drop = [k for k in keys if k.startswith("jaco/s1/sirl/N200/tpa")]
        drop += ["grid/s0/vae/rep"]  # φ of the VAE method: needs the (stored) grid VAE
        assert len(drop) > 2, drop
        for k in drop:
            del f["runs/" + k]
        del f["runs_index"]
        f.create_dataset("runs_index", data=[k.encode() for k in keys if k not in drop],
                         dtype=h5py.string_dtype())
        f.attrs["complete"] = 0
    reseal(holed)  # the edit is deliberate: give the file its new digest, as a rewrite would
    out = run("run", SMOKE, "--out", holed, "--threads", "2").stdout
    computed = int(out.split("reused, ")[1].split(" computed")[0])
    assert computed == len(drop) + 1, f"expected {len(drop)} cells + 1 φ recomputed:\n{out}"
    same_runs(one, holed, f"a file missing {len(drop)} records (and Jaco weights) resumed")

    # A shard into a complete whole-run file would rewrite it with half of its tasks: refused.
    with h5py.File(one, "r") as f:
        before = int(f.attrs["tasks_done"])
    p = run("run", SMOKE, "--out", one, "--shard", "0/2", "--quiet", check=False)
    assert p.returncode == 2 and "the whole run" in p.stderr and "shard 0/2" in p.stderr, p.stderr
    with h5py.File(one, "r") as f:
        assert int(f.attrs["tasks_done"]) == before and f.attrs["shard"] in (b"", "")
    print("ok: a shard into a whole run's file is refused:", p.stderr.strip())
    # Commands that write another kind of file refuse to replace a results file.
    size = os.path.getsize(one)
    for cmd in (["dataset", "--env", "grid", "--out", one],
                ["study", "simulate", "--env", "grid", "--users", "2", "--out", one]):
        p = run(*cmd, check=False)
        assert p.returncode == 2 and "is a results file" in p.stderr and "--force" in p.stderr, p.stderr
    assert os.path.getsize(one) == size and tables(one)["tpa"].equals(ref["tpa"])
    print("ok: dataset / study simulate refuse to replace a results file:", p.stderr.strip())

    # One writer per output: a second run on an --out that is being written is refused, naming
    # the first one's pid; the first finishes undisturbed.
    # The first run is stopped (SIGSTOP) while it holds the lock, so the second always meets it.
    busy = os.path.join(tmp, "busy.h5")
    first = subprocess.Popen([SIRL, "run", SMOKE, "--out", busy, "--threads", "1", "--quiet"],
                             stdin=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 30
    while time.time() < deadline and not (os.path.exists(busy + ".lock")
                                          and os.path.getsize(busy + ".lock") > 0):
        time.sleep(0.02)
    os.kill(first.pid, signal.SIGSTOP)
    assert first.poll() is None, "the first run ended before the second could meet its lock"
    p = run("run", SMOKE, "--out", busy, "--quiet", check=False)
    os.kill(first.pid, signal.SIGCONT)
    assert p.returncode == 2 and f"in use by sirl run (pid {first.pid})" in p.stderr, p.stderr
    assert first.wait() == 0, first.stderr.read()
    same(tables(one), tables(busy), f"a second writer refused ({p.stderr.strip()}); the first run")

    # Shards + merge.
    shards = [os.path.join(tmp, f"shard{i}.h5") for i in range(2)]
    for i, s in enumerate(shards):
        run("run", SMOKE, "--out", s, "--shard", f"{i}/2", "--quiet")
    merged = os.path.join(tmp, "merged.h5")
    run("merge", merged, *shards)
    same(ref, tables(merged), "shards 0/2 + 1/2 merged equal the single-process run")

    # Another profile (tpa.epochs changed) on the same cache: only TPA cells are computed; merging
    # shards of different profiles is refused.
    other = os.path.join(tmp, "other.toml")
    with open(other, "w") as f:
        f.write(f'extends = "{SMOKE}"\n[hyper.grid]\n"tpa.epochs" = 21\n')
    cache = one + ".tasks"
    before = set(os.listdir(cache))
    out = run("run", other, "--out", os.path.join(tmp, "other.h5"), "--cache", cache).stdout
    kinds = set()
    for name in set(os.listdir(cache)) - before:
        if name.endswith(".h5"):
            with h5py.File(os.path.join(cache, name), "r") as f:
                kinds.add(f["r"].attrs["task_kind"])
    assert kinds == {"tpa"}, (kinds, out)
    print("ok: another profile (tpa.epochs) on the same cache computes its TPA cells only:",
          out.strip())
    foreign = os.path.join(tmp, "foreign.h5")
    # Its tasks are all in `cache` (other.h5 above): the shard is written, nothing computed.
    run("run", other, "--out", foreign, "--shard", "1/2", "--quiet", "--cache", cache)
    p = run("merge", os.path.join(tmp, "bad.h5"), shards[0], foreign, check=False)
    assert p.returncode == 2 and "profile" in p.stderr, p.stderr
    print("ok: merging shards of different profiles is refused")

    # CSV export matches the table.
    csv = os.path.join(tmp, "csv")
    run("export", one, "--csv", csv)
    c = pd.read_csv(os.path.join(csv, "tpa.csv"))
    assert len(c) == len(ref["tpa"]) and np.allclose(c["tpa"], ref["tpa"]["tpa"])
    with h5py.File(one, "r") as f:
        # Every CSV: the same rows and every numeric column equal to the table's (17 digits).
        for name in ("fpe", "tpa", "timings", "training", "vae_latents", "tpa_heads"):
            t = pd.DataFrame(f["tables/" + name][:])
            # keep_default_na=False: an empty text field (the main teacher's "") stays "", not NaN
            c = pd.read_csv(os.path.join(csv, name + ".csv"), float_precision="round_trip",
                            keep_default_na=False)
            assert len(t) > 0 and len(c) == len(t), (name, len(c), len(t))
            assert list(c.columns) == list(t.columns), (name, list(c.columns))
            for col in t.columns:
                if t[col].dtype == object:
                    assert list(c[col].astype(str)) == [v.decode() for v in t[col]], (name, col)
                else:
                    # What the cell does not have is an empty field, as the reader's <NA>: N or
                    # M of 0, a seed of -1, `frozen` without M, NaN.
                    want = t[col].to_numpy(dtype=float)
                    if col in ("N", "M"):
                        want[want == 0] = np.nan
                    if col == "seed":
                        want[want < 0] = np.nan
                    if col == "frozen" and "M" in t:
                        want[t["M"].to_numpy() == 0] = np.nan
                    got = pd.to_numeric(c[col].replace("", np.nan)).to_numpy(dtype=float)
                    assert np.array_equal(got, want, equal_nan=True), (name, col)
    n_groups = pd.read_csv(os.path.join(csv, "fpe.csv"))["N"].dropna().unique()
    assert 0 not in n_groups, n_groups
    print("ok: export --csv writes every table, every column equal (fpe, tpa, timings, training, "
          "vae_latents, tpa_heads), missing values empty")

    # Another engine version wrote the file: refused, and --force starts over.
    # An edited file no longer matches its checksum: refused as changed (exit 1, one line), and
    # --force recomputes it.
    edited = os.path.join(tmp, "edited.h5")
    shutil.copy(one, edited)
    shutil.copy(one + ".sum", edited + ".sum")
    with h5py.File(edited, "r+") as f:
        f.attrs["engine_version"] = "0.0.1"
    p = run("export", edited, "--csv", os.path.join(tmp, "e"), check=False)
    assert p.returncode == 1 and "checksum mismatch" in p.stderr and p.stderr.count("\n") == 1, \
        p.stderr
    print("ok: an edited results file is refused by its checksum:", p.stderr.strip()[:120])
    # A file of another engine version, without checksums as engine 0.1.0 wrote it: no .sum, and
    # no checksum frame (plain HDF5 from byte 0: every object copied into a file without one).
    os.remove(one + ".sum")
    framed = one + ".framed"
    os.replace(one, framed)
    with h5py.File(framed, "r") as a, h5py.File(one, "w") as b:
        for k, v in a.attrs.items():
            if k != "schema_version":  # engine 0.1.0 wrote none (schema 1); a schema-3 file
                b.attrs[k] = v         # without its frame is refused as rewritten
        for name in a:
            a.copy(a[name], b, name=name)
        b.attrs["engine_version"] = "0.0.1"
    os.remove(framed)
    with open(one, "rb") as f:
        assert f.read(8) == b"\x89HDF\r\n\x1a\n"
    p = run("run", SMOKE, "--out", one)
    assert "not reused" in p.stderr and "(%d reused" % n_all in p.stdout, \
        (p.stdout, p.stderr)  # its records not trusted; the cache's are
    same(ref, tables(one), "a file no checksum covers: its records unused, the cache's reused")
    out = run("run", SMOKE, "--out", one, "--force").stdout
    assert "(0 reused" in out, out
    same(ref, tables(one), "a file of another engine version, --force: recomputed, same tables")

    # The cache of an interrupted run of another profile: what the two share is reused.
    fresh = os.path.join(tmp, "fresh.h5")
    child = subprocess.run([SIRL, "run", other, "--out", fresh, "--threads", "1", "--quiet"],
                           stdin=subprocess.DEVNULL, env=dict(os.environ, SIRL_CRASH_AFTER_COMMITS="3"))
    assert child.returncode == 137, child.returncode
    assert os.path.isdir(fresh + ".tasks") and not os.path.exists(fresh)
    out = run("run", SMOKE, "--out", fresh).stdout
    reused = int(re.search(r"\((\d+) reused", out).group(1))
    assert 0 < reused <= 3, out
    same(ref, tables(fresh), f"another profile's interrupted run: {reused} shared tasks reused")

print("PASS")
