#!/usr/bin/python3
"""A full disk for every command that writes (ctest; `sirl run`'s case is in batch_engine.py).

The disk is filled by a file-size limit (RLIMIT_FSIZE: a write past it fails with EFBIG, as one
would with ENOSPC). Each of `sirl dataset`, `sirl merge`, `sirl study simulate` and `sirl study
import` must then end with one line naming the cause and exit 1, never a crash; leave no
temporary or partial file behind; leave the good file already at --out untouched; and succeed
once there is room again.
"""
import hashlib
import os
import resource
import signal
import subprocess
import tempfile

SIRL = os.environ["SIRL"]
SRC = os.environ["SIRL_SOURCE_DIR"]
MICRO = os.path.join(SRC, "tests", "data", "micro.toml")
LIMIT = 8_192  # bytes: below every output here (the smallest, an imported study, is ~14 KB)


def limited(n=LIMIT):
    def set_limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (n, n))
    return set_limit


def sirl(args, limit=False, size=LIMIT):
    return subprocess.run([SIRL, *args], capture_output=True, text=True, stdin=subprocess.DEVNULL,
                          preexec_fn=limited(size) if limit else None)


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


with tempfile.TemporaryDirectory() as tmp:
    shards = [os.path.join(tmp, f"s{i}.h5") for i in range(2)]
    for i, s in enumerate(shards):
        p = sirl(["run", MICRO, "--out", s, "--shard", f"{i}/2", "--quiet"])
        assert p.returncode == 0, p.stderr
    answers = os.path.join(tmp, "answers.csv")
    with open(answers, "w") as f:
        f.write("participant,kind,t1,t2,t3,answer,response_ms,timestamp,scenario,scenario_features\n"
                "ann,similarity,1,2,3,2,1500,1700000000.5,Stay away,laptop_distance\n"
                "ann,preference,7,8,,1,700,1700000002,,\n")
    cases = [
        ("dataset", lambda out: ["dataset", "--env", "grid", "--out", out, "--force"]),
        ("merge", lambda out: ["merge", "--force", out, *shards]),
        ("study simulate", lambda out: ["study", "simulate", "--env", "grid", "--users", "2",
                                        "--out", out, "--force"]),
        ("study import", lambda out: ["study", "import", answers, "--env", "grid", "--out", out]),
    ]
    for name, args in cases:
        out = os.path.join(tmp, name.replace(" ", "_") + ".h5")
        # A good file of the same kind is at --out: a failed write must not replace or damage it.
        first = sirl(args(out))
        assert first.returncode == 0, (name, first.stderr)
        before = digest(out)
        p = sirl(args(out), limit=True)
        assert p.returncode == 1, (name, p.returncode, p.stderr[-800:])
        assert p.stderr.count("\n") == 1 and "File too large" in p.stderr, (name, p.stderr[-800:])
        assert digest(out) == before, f"{name}: the good file at --out changed"
        left = [n for n in os.listdir(tmp) if n.endswith((".partial", ".tmp"))]
        assert not left, (name, left)
        again = sirl(args(out))
        assert again.returncode == 0, (name, again.stderr)
        print(f"ok: {name} on a full disk: {p.stderr.strip()[:110]}...; the file at --out kept; "
              "succeeds with room again")

    # `sirl export` on a full disk: the CSVs already in the folder stay as they were (every CSV is
    # written in full before any replaces its old copy), nothing of the attempt is left behind,
    # and the line says why.
    merged = os.path.join(tmp, "merge.h5")
    csv = os.path.join(tmp, "csv")
    assert sirl(["export", merged, "--csv", csv]).returncode == 0
    open(os.path.join(csv, "notes.txt"), "w").write("the user's own file\n")
    before = {n: digest(os.path.join(csv, n)) for n in os.listdir(csv)}
    # below the largest CSV, above the smallest: some tables fit, one does not
    sizes = sorted(os.path.getsize(os.path.join(csv, n)) for n in before if n.endswith(".csv"))
    p = sirl(["export", merged, "--csv", csv], limit=True, size=sizes[-1] - 1)
    assert p.returncode == 1, (p.returncode, p.stderr[-800:])
    assert p.stderr.count("\n") == 1 and "File too large" in p.stderr, p.stderr[-800:]
    after = {n: digest(os.path.join(csv, n)) for n in os.listdir(csv)}
    assert after == before, "export on a full disk changed the folder's files"
    assert sirl(["export", merged, "--csv", csv]).returncode == 0
    assert open(os.path.join(csv, "notes.txt")).read() == "the user's own file\n"
    print(f"ok: export on a full disk: {p.stderr.strip()[:110]}...; the old CSVs kept")
