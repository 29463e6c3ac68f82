#!/usr/bin/python3
"""The crash-point walk: `sirl run` on the micro profile ends as kill -9 would at its k-th crash
point (SIRL_CRASH_AT=k: before and after every fsync of every durable write — task commits, the
staging manifest, the results file and its checksum — and before the staging folder is removed),
for every k; each rerun must resume to exactly the file an uninterrupted run writes (every table,
and every dataset and attribute under /runs, timing fields excepted), with its checksum in place
and no staging folder, temporary or partial file left behind.
"""
import os
import sys
import tempfile

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

MICRO = sirl_testing.data_path("micro.toml")
TIMING = {"seconds", "threads", "wall_seconds", "started", "finished", "roof_fp32_gflops_per_core",
          "roof_bf16_gflops_per_core", "stream_gbs_per_core"}
TIMING_COLUMNS = {"seconds", "gflops", "roof_percent", "threads", "memory_roof_gflops",
                  "attainable_percent", "compute_roof_gflops"}
# Every STRIDE-th crash point (default 1: all). scripts/tsan.sh walks a fifth of them: under
# ThreadSanitizer each point costs a 10x slower run and rerun, and the release suite walks them all.
STRIDE = int(os.environ.get("SIRL_CRASH_WALK_STRIDE", "1"))
assert STRIDE >= 1, STRIDE
EVERY = "all" if STRIDE == 1 else f"every {STRIDE}th"


def run(out, crash_at=None, threads="1", after_commits=None, checkpoints="5"):
    env = dict(os.environ)
    env.pop("SIRL_CRASH_AT", None)
    env.pop("SIRL_CRASH_AFTER_COMMITS", None)
    if crash_at is not None:
        env["SIRL_CRASH_AT"] = str(crash_at)
    if after_commits is not None:
        env["SIRL_CRASH_AFTER_COMMITS"] = str(after_commits)
    return sirl_testing.run_sirl("run", MICRO, "--out", out, "--threads", threads, "--quiet",
                                 "--checkpoint-minutes", checkpoints, env=env)


def content(path):
    """Every table column and every dataset and attribute under /runs (timing excepted)."""
    out = {}
    with h5py.File(path, "r") as f:
        assert f.attrs["complete"] == 1, f"{path} is not complete"
        for name in f["tables"]:
            t = f["tables/" + name][:]
            order = np.argsort(f["tables/" + name]["key"][:]) if "key" in t.dtype.names else None
            for c in t.dtype.names:
                if c not in TIMING_COLUMNS:
                    col = t[c] if order is None else t[c][order]
                    out[f"tables/{name}/{c}"] = col

        def visit(name, obj):
            for a, v in obj.attrs.items():
                if a not in TIMING:
                    out[f"runs/{name}@{a}"] = v.tolist() if hasattr(v, "tolist") else v
            if isinstance(obj, h5py.Dataset):
                out[f"runs/{name}"] = obj[:]
        f["runs"].visititems(visit)
    return out


def differences(a, b):
    if a.keys() != b.keys():
        return [f"objects only in one: {sorted(a.keys() ^ b.keys())[:5]}"]
    bad = []
    for k in a:
        x, y = a[k], b[k]
        if not (np.array_equal(x, y) if isinstance(x, np.ndarray) else x == y):
            bad.append(k)
    return bad


with tempfile.TemporaryDirectory() as tmp:
    ref = os.path.join(tmp, "ref.h5")
    p = run(ref)
    assert p.returncode == 0, p.stderr
    expected = content(ref)
    k, walked = 1, 0
    while True:
        out = os.path.join(tmp, f"k{k}.h5")
        p = run(out, crash_at=k)
        if p.returncode == 0:  # k is past the last crash point: the walk is complete
            break
        assert p.returncode == 137, f"crash point {k}: exit {p.returncode}\n{p.stderr}"
        r = run(out, threads="2")  # resumed (with another thread count: it must not matter)
        assert r.returncode == 0, f"crash point {k}: the rerun failed ({r.returncode}):\n{r.stderr}"
        bad = differences(expected, content(out))
        assert not bad, f"crash point {k}: the resumed file differs from a fresh run's: {bad[:5]}"
        assert os.path.exists(out + ".sum"), f"crash point {k}: no checksum beside the file"
        left = [n for n in os.listdir(tmp) if n.startswith(f"k{k}.h5.") and n != f"k{k}.h5.sum"
                and not n.endswith((".lock", ".tasks"))]  # the task cache stays for later runs
        assert not left, f"crash point {k}: left behind {left}"
        walked += 1
        k += STRIDE
    assert k > 30, f"only {k - 1} crash points: the walk no longer covers every write"
    print(f"ok: crashed at {walked} crash points ({EVERY} of the first {k - 1}), every rerun resumed "
          f"to the fresh run's file ({len(expected)} columns, datasets and attributes compared)")

    # Training checkpoints after every epoch: a crash right after each durable commit (a task or
    # a checkpoint) and a rerun that continues the interrupted trainings end in the fresh run's
    # file, and the crashes did land mid-training (a checkpoint was on disk).
    k, resumed_mid_training, walked = 1, 0, 0
    while True:
        out = os.path.join(tmp, f"c{k}.h5")
        p = run(out, after_commits=k, checkpoints="0")
        if p.returncode == 0:
            break
        assert p.returncode == 137, f"commit {k}: exit {p.returncode}\n{p.stderr}"
        ckpt = out + ".tasks/checkpoints"
        resumed_mid_training += os.path.isdir(ckpt) and any(n.endswith(".h5") for n in os.listdir(ckpt))
        r = run(out, threads="2", checkpoints="0")
        assert r.returncode == 0, f"commit {k}: the rerun failed ({r.returncode}):\n{r.stderr}"
        bad = differences(expected, content(out))
        assert not bad, f"commit {k}: continuing from the checkpoints differs from a fresh run: {bad[:5]}"
        ckpt_left = [n for n in os.listdir(ckpt) if n.endswith(".h5")] if os.path.isdir(ckpt) else []
        assert not ckpt_left, f"commit {k}: checkpoints of committed trainings left behind: {ckpt_left}"
        walked += 1
        k += STRIDE
    assert resumed_mid_training >= max(1, 5 // STRIDE), resumed_mid_training
    print(f"ok: with a checkpoint after every epoch, a crash after {walked} commits "
          f"({EVERY} of the first {k - 1}) resumed to the fresh run's file ({resumed_mid_training} of them with "
          f"a training checkpoint on disk)")
