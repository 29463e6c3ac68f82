#!/usr/bin/python3
"""No write destroys a good file (ctest; issue: reliability):

- `sirl merge SHARD0 SHARD1` (the output's name forgotten) is refused and SHARD0 is unchanged;
  an output that is one of the inputs is refused even with --force;
- `merge --force`, `dataset --force` and `study simulate --force` honour the output's lock:
  while another process holds it, each is refused naming the lock's holder, and nothing is
  written;
- files of an older engine (the schema-1 fixture, engine 0.1.0) still merge and export.
"""
import fcntl
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile

SIRL = os.environ["SIRL"]
SRC = os.environ["SIRL_SOURCE_DIR"]
FIXTURE = os.path.join(SRC, "tests", "data", "results_v1.h5")


def sirl(*args):
    return subprocess.run([SIRL, *args], capture_output=True, text=True, stdin=subprocess.DEVNULL,
                          timeout=120)


def digest(path):
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


def fail(msg):
    print("output_guards: FAIL:", msg)
    sys.exit(1)


def main():
    with tempfile.TemporaryDirectory() as tmp:
        a, b, m = (os.path.join(tmp, n) for n in ("a.h5", "b.h5", "m.h5"))
        shutil.copy(FIXTURE, a)
        shutil.copy(FIXTURE, b)
        before = digest(a)
        p = sirl("merge", a, b)
        if p.returncode != 2 or "already exists" not in p.stderr or digest(a) != before:
            fail(f"merge over an existing file: rc {p.returncode}, {p.stderr!r}")
        p = sirl("merge", "--force", a, a, b)
        if p.returncode != 2 or "one of the inputs" not in p.stderr or digest(a) != before:
            fail(f"merge into one of its inputs: rc {p.returncode}, {p.stderr!r}")
        print("ok: merge refuses to replace an existing file or an input")

        # An older engine's files merge (their records lack fields the tables now carry); their
        # plans lacked the cells added since (linear evaluation, the references): --partial.
        p = sirl("merge", "--partial", m, a, b)
        if p.returncode != 0:
            fail(f"merging the schema-1 fixture: {p.stderr}")
        p = sirl("export", m, "--csv", os.path.join(tmp, "csv"))
        if p.returncode != 0 or "best_mode" not in open(os.path.join(tmp, "csv", "tpa.csv")).readline():
            fail(f"export of the merged fixture: {p.stderr}")
        print("ok: the schema-1 fixture merges and exports")

        # Another process holds m.h5's lock (as `sirl run --out m.h5` would).
        held = digest(m)
        # The refusal names the holder the lock file records, not the refused command.
        with open(m + ".lock", "a+") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            lock.truncate(0)
            lock.write("4242 sirl run")
            lock.flush()
            for args in (["merge", "--force", m, a, b],
                         ["dataset", "--env", "grid", "--force", "--out", m],
                         ["study", "simulate", "--force", "--out", m, "--users", "2"]):
                p = sirl(*args)
                if p.returncode == 0 or "in use by sirl run (pid 4242)" not in p.stderr:
                    fail(f"sirl {' '.join(args[:2])} wrote while the lock was held: rc "
                         f"{p.returncode}, {p.stderr!r}")
                if digest(m) != held or os.path.exists(m + ".partial"):
                    fail(f"sirl {' '.join(args[:2])} changed {m} while the lock was held")
        print("ok: merge, dataset and study simulate honour the output's lock, --force or not")
    # An empty or folder output path: one line, exit 2, nothing written where we stand.
    with tempfile.TemporaryDirectory() as cwd:
        for args in (["dataset", "--out", ""], ["dataset", "--out", cwd + "/"],
                     ["run", "smoke", "--out", ""], ["merge", "", FIXTURE],
                     ["study", "simulate", "--out", ""], ["export", FIXTURE, "--csv", ""]):
            p = subprocess.run([SIRL, *args], capture_output=True, text=True, cwd=cwd,
                               stdin=subprocess.DEVNULL, timeout=60)
            if p.returncode != 2 or "must name a" not in p.stderr or p.stderr.count("\n") != 1:
                fail(f"sirl {' '.join(args)}: rc {p.returncode}, {p.stderr!r}")
            if os.listdir(cwd):
                fail(f"sirl {' '.join(args)} left {os.listdir(cwd)}")
        # A file that exists but is not HDF5: the reason is its content, not a stale OS error.
        text = os.path.join(cwd, "notes.h5")
        open(text, "w").write("not hdf5\n")
        p = subprocess.run([SIRL, "inspect", text], capture_output=True, text=True, timeout=60)
        if p.returncode == 0 or "not an HDF5 file" not in p.stderr or "No such file" in p.stderr:
            fail(f"inspect on a text file: {p.stderr!r}")
    print("ok: empty and folder output paths refused in one line; no stale OS reason")
    # A FIFO as an input or an output would block forever (no writer, or no reader, ever comes):
    # refused in one line, within the timeout.
    with tempfile.TemporaryDirectory() as cwd:
        fifo = os.path.join(cwd, "pipe.h5")
        os.mkfifo(fifo)
        for args in (["inspect", fifo], ["export", fifo, "--csv", os.path.join(cwd, "c")],
                     ["run", "smoke", "--out", fifo], ["merge", fifo, FIXTURE],
                     ["dataset", "--env", "grid", "--out", fifo]):
            try:
                p = subprocess.run([SIRL, *args], capture_output=True, text=True, cwd=cwd,
                                   stdin=subprocess.DEVNULL, timeout=30)
            except subprocess.TimeoutExpired:
                fail(f"sirl {' '.join(args[:2])} blocked on a FIFO")
            if p.returncode == 0 or "regular file" not in p.stderr or p.stderr.count("\n") != 1:
                fail(f"sirl {' '.join(args[:2])} on a FIFO: rc {p.returncode}, {p.stderr!r}")
        # submit's --out is a folder: an existing file is refused before anything is calibrated.
        plain = os.path.join(cwd, "notes")
        open(plain, "w").write("mine\n")
        p = subprocess.run([SIRL, "submit", "smoke", "--shards", "2", "--out", plain],
                           capture_output=True, text=True, cwd=cwd, stdin=subprocess.DEVNULL,
                           timeout=60)
        if p.returncode != 2 or "must name a folder" not in p.stderr or \
                open(plain).read() != "mine\n" or "filesystem error" in p.stderr:
            fail(f"submit --out FILE: rc {p.returncode}, {p.stderr!r}")
    print("ok: FIFOs as inputs and outputs refused in one line; submit --out FILE refused")
    print("output_guards: OK")


if __name__ == "__main__":
    main()
