#!/usr/bin/python3
"""Stopping a run by signal keeps its work (jobs/stop_request.h): SIGTERM or a first Ctrl-C makes
each training save at its next epoch end, the run exit 75 naming the signal, and a rerun
continue from the saved epoch to the bits of an uninterrupted run; a second Ctrl-C ends the
process at once, and the rerun still gives the same bits."""
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py
import pandas as pd

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

SIRL = sirl_testing.sirl_binary()
SLOW = sirl_testing.data_path("slow-training.toml")


fail = sirl_testing.make_fail("stop_signals")


def tables(path):
    with h5py.File(path, "r") as f:
        return {k: pd.DataFrame(f["tables/" + k][:]) for k in ("fpe", "tpa", "training")}


def run(out, *extra):
    p = sirl_testing.run_sirl("run", SLOW, "--out", str(out), "--threads", "1", *extra, timeout=300)
    if p.returncode != 0:
        fail(f"sirl run exited {p.returncode}\n{p.stderr}")
    return p


def interrupted(out, signals):
    """Starts a run saving after every epoch, sends `signals` once a checkpoint exists."""
    p = subprocess.Popen([SIRL, "run", SLOW, "--out", str(out), "--threads", "1",
                          "--checkpoint-minutes", "0"], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    checkpoints = Path(str(out) + ".tasks") / "checkpoints"
    deadline = time.time() + 60
    while not (checkpoints.is_dir() and any(checkpoints.glob("*.h5"))):
        if time.time() > deadline or p.poll() is not None:
            p.kill()
            fail("no checkpoint appeared\n" + p.communicate()[1])
        time.sleep(0.05)
    for sig in signals:
        p.send_signal(sig)
        time.sleep(0.01)
    _, err = p.communicate(timeout=120)
    return p.returncode, err


with tempfile.TemporaryDirectory() as tmp:
    tmp = Path(tmp)
    run(tmp / "ref.h5", "--checkpoint-minutes", "-1")
    ref = tables(tmp / "ref.h5")

    for sig, name in ((signal.SIGTERM, "SIGTERM"), (signal.SIGINT, "SIGINT")):
        out = tmp / f"{name}.h5"
        rc, err = interrupted(out, [sig])
        m = re.search(r"saved at epoch (\d+); stopping \(" + name + r"\)", err)
        if rc != 75 or not m or f"stopped on {name}" not in err:
            fail(f"{name}: expected exit 75 after a save, got {rc}\n{err}")
        again = run(out, "--checkpoint-minutes", "5")
        if f"continues from its checkpoint at epoch {m.group(1)}" not in again.stderr:
            fail(f"{name}: the rerun should continue from epoch {m.group(1)}\n{again.stderr}")
        got = tables(out)
        for k in ref:
            if not ref[k].equals(got[k]):
                fail(f"{name}: table {k} differs from the uninterrupted run's")
        print(f"ok: {name} at epoch {m.group(1)}: exit 75, the rerun continued to the same bits")

    out = tmp / "twice.h5"
    rc, err = interrupted(out, [signal.SIGINT, signal.SIGINT])
    if rc not in (-signal.SIGINT, 75):  # 75 only if the save finished between the two
        fail(f"a second Ctrl-C should end the run at once, it exited {rc}\n{err}")
    run(out, "--checkpoint-minutes", "5")
    got = tables(out)
    if not all(ref[k].equals(got[k]) for k in ref):
        fail("after two Ctrl-C the rerun should give the uninterrupted run's bits")
    print(f"ok: a second Ctrl-C ended the run (exit {rc}); the rerun gave the same bits")
