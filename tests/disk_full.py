#!/usr/bin/python3
"""A full disk for every command that writes (ctest; `sirl run`'s case is in batch_engine.py).

The disk is filled by a file-size limit (RLIMIT_FSIZE: a write past it fails with EFBIG, as one
would with ENOSPC). Each of `sirl dataset`, `sirl merge`, `sirl study simulate` and `sirl study
import` must then end with one line naming the cause and exit 1, never a crash; leave no
temporary or partial file behind; leave the good file already at --out untouched; and succeed
once there is room again.
"""
import os
import resource
import signal
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402
from sirl_testing import sha256_file as digest  # noqa: E402

MICRO = sirl_testing.data_path("micro.toml")
LIMIT = 8_192  # bytes: below every output here (the smallest, an imported study, is ~14 KB)


def limited(n=LIMIT):
    def set_limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (n, n))
    return set_limit


def sirl(args, limit=False, size=LIMIT):
    return sirl_testing.run_sirl(*args, preexec_fn=limited(size) if limit else None)


with tempfile.TemporaryDirectory() as tmp:
    shards = [os.path.join(tmp, f"s{i}.h5") for i in range(2)]
    for i, s in enumerate(shards):
        p = sirl(["run", MICRO, "--out", s, "--shard", f"{i}/2", "--quiet"])
        assert p.returncode == 0, p.stderr
    answered = []

    def new_answers():
        """An answers file whose records no earlier one has (other timestamps)."""
        answers = os.path.join(tmp, f"answers{len(answered)}.csv")
        t = 1700000000 + 10 * len(answered)
        with open(answers, "w") as f:
            f.write("participant,kind,t1,t2,t3,answer,response_ms,timestamp,scenario,"
                    "scenario_features\n"
                    f"ann,similarity,1,2,3,2,1500,{t}.5,Stay away,laptop_distance\n"
                    f"ann,preference,7,8,,1,700,{t + 2},,\n")
        answered.append(answers)
        return answers
    cases = [
        ("dataset", lambda out: ["dataset", "--env", "grid", "--out", out, "--force"]),
        ("merge", lambda out: ["merge", "--force", out, *shards]),
        ("study simulate", lambda out: ["study", "simulate", "--env", "grid", "--users", "2",
                                        "--out", out, "--force"]),
        # each attempt imports new answers (the same answers twice are refused before any write)
        ("study import", lambda out: ["study", "import", new_answers(), "--env", "grid", "--out",
                                      out]),
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
