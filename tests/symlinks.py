#!/usr/bin/python3
"""Files sirl creates beside an output never follow a planted symbolic link (ctest):

for `sirl dataset`, `run`, `merge` and `study simulate`, a link planted at each file the command
creates beside OUT (OUT.partial or a study's OUT.tmp, OUT.lock, OUT.sum.tmp, and for `run` the
folder OUT.tasks), pointing at a victim file or folder, makes the command stop with one line
naming the link, and the victim is untouched.
"""
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

MICRO = sirl_testing.data_path("micro.toml")
fail = sirl_testing.make_fail("symlinks")


def sirl(*args):
    return sirl_testing.run_sirl(*args, timeout=300)


def state(path):
    """The victim's content: a file's digest, or a folder's names and digests."""
    if os.path.isdir(path):
        return {n: state(os.path.join(path, n)) for n in sorted(os.listdir(path))}
    return sirl_testing.sha256_file(path)


def main():
    checked = 0
    with tempfile.TemporaryDirectory() as tmp:
        shards = [os.path.join(tmp, f"s{i}.h5") for i in range(2)]
        for i, s in enumerate(shards):
            p = sirl("run", MICRO, "--out", s, "--shard", f"{i}/2", "--quiet")
            if p.returncode:
                fail(p.stderr)
        commands = {
            "dataset": (lambda out: ["dataset", "--env", "grid", "--out", out],
                        [".partial", ".lock"]),
            "run": (lambda out: ["run", MICRO, "--out", out, "--quiet"],
                    [".partial", ".lock", ".sum.tmp", ".tasks"]),
            "merge": (lambda out: ["merge", out, *shards], [".partial", ".lock", ".sum.tmp"]),
            "study simulate": (lambda out: ["study", "simulate", "--env", "grid", "--users", "2",
                                            "--out", out], [".tmp", ".lock"]),
        }
        for name, (args, besides) in commands.items():
            for beside in besides:
                work = os.path.join(tmp, "w")
                shutil.rmtree(work, ignore_errors=True)
                os.makedirs(work)
                victim = os.path.join(work, "victim")
                if beside == ".tasks":
                    os.makedirs(victim)
                    open(os.path.join(victim, "keep.h5"), "w").write("the user's data\n")
                else:
                    open(victim, "w").write("the user's data\n")
                before = state(victim)
                out = os.path.join(work, "out.h5")
                os.symlink(victim, out + beside)
                p = sirl(*args(out))
                err = p.stderr.strip()
                if p.returncode == 0 or "symbolic link" not in err or "\n" in err:
                    fail(f"{name} with a link at OUT{beside}: rc {p.returncode}, {err[:300]!r}")
                if state(victim) != before:
                    fail(f"{name} changed what OUT{beside} pointed to")
                checked += 1
    print(f"ok: {checked} planted links refused, their targets untouched")
    print("symlinks: OK")


if __name__ == "__main__":
    main()
