#!/usr/bin/python3
"""The smoke fixture (ctest `smoke_fixture`, FIXTURES_SETUP smoke_results): one results file and
task cache of each profile the system tests run only to have a finished file, computed once per
binary and shared read-only by them (tests/sirl_testing.py: copy_fixture).

$SIRL_SMOKE_FIXTURE (build/<preset>/test-fixtures/smoke) holds, as the tests made them:
- smoke.h5, smoke.h5.sum, smoke.h5.tasks/: `sirl run smoke --threads 2 --quiet --out smoke.h5`;
- engine-test.h5, .sum, .tasks/: the same on tests/data/engine-test.toml;
- MANIFEST.json: a stamp and the SHA-256 of every file (tests/check_smoke_fixture.py re-hashes).

The stamp is the SHA-256 of the sirl binary, `sirl version`'s lines but the measured roofs (the
CPU class: a task cache holds bits of one class; the libraries' versions), and the SHA-256 of
configs/smoke.toml and tests/data/engine-test.toml.
A folder whose stamp matches and whose files still hash as listed is kept as it is; otherwise
the two runs write a temporary sibling folder, `sirl show --json` must call both files verified
and complete, and that folder replaces the old one in one rename (renameat2 RENAME_EXCHANGE).
Builders take test-fixtures/smoke.lock, so two ctest runs in one build folder build once.
"""
import ctypes
import fcntl
import glob
import json
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

fail = sirl_testing.make_fail("smoke_fixture")

FIXTURES = ("smoke", "engine-test")


def profile_args(src):
    """Each fixture's profile as the tests name it (smoke by name, engine-test by its path)."""
    return {"smoke": "smoke", "engine-test": os.path.join(src, "tests", "data", "engine-test.toml")}


def version_lines():
    """`sirl version` without its roofs (measured each time): the CPU class line, and the
    libraries' versions and kernel paths, which the binary's own hash does not cover."""
    p = sirl_testing.run_sirl("version", timeout=300)
    if p.returncode:
        fail(f"sirl version: rc {p.returncode}\n{p.stderr}")
    lines = [x.rstrip() for x in p.stdout.splitlines() if x.strip() and "measured" not in x]
    if len([x for x in lines if x.startswith("cpu class:")]) != 1:
        fail(f"sirl version prints no single 'cpu class:' line:\n{p.stdout}")
    return lines


def stamp(src):
    parts = [
        "sirl " + sirl_testing.sha256_file(os.path.realpath(sirl_testing.sirl_binary())),
        *version_lines(),
        "configs/smoke.toml "
        + sirl_testing.sha256_file(os.path.join(src, "configs", "smoke.toml")),
        "tests/data/engine-test.toml "
        + sirl_testing.sha256_file(os.path.join(src, "tests", "data", "engine-test.toml")),
    ]
    return "\n".join(parts)


def hash_tree(folder):
    """{relative path: sha256} of every file under FOLDER but MANIFEST.json; a symbolic link or
    other non-regular file is an error (nothing in the fixture is one)."""
    out = {}
    for root, dirs, files in os.walk(folder):
        dirs.sort()
        for name in sorted(files) + [d for d in dirs if os.path.islink(os.path.join(root, d))]:
            path = os.path.join(root, name)
            rel = os.path.relpath(path, folder)
            if rel == "MANIFEST.json":
                continue
            if os.path.islink(path) or not os.path.isfile(path):
                raise ValueError(f"{rel}: not a regular file")
            out[rel] = sirl_testing.sha256_file(path)
    return out


def differences(folder, manifest):
    """What differs between FOLDER and MANIFEST's file list: [sentences], empty if nothing."""
    try:
        now = hash_tree(folder)
    except ValueError as e:
        return [str(e)]
    want = manifest.get("files", {})
    out = [f"{f}: changed" for f in sorted(want) if f in now and now[f] != want[f]]
    out += [f"{f}: removed" for f in sorted(want) if f not in now]
    out += [f"{f}: added" for f in sorted(now) if f not in want]
    return out


def read_manifest(folder):
    try:
        with open(os.path.join(folder, "MANIFEST.json")) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def check_complete(folder, name):
    """`sirl show --json` calls NAME.h5 verified and complete; its cache holds every task."""
    h5 = os.path.join(folder, name + ".h5")
    p = sirl_testing.run_sirl("show", h5, "--json", timeout=300)
    if p.returncode:
        fail(f"sirl show {h5} --json: rc {p.returncode}\n{p.stderr}")
    shown = json.loads(p.stdout)
    tasks = shown.get("tasks", {})
    if not shown.get("verified") or not tasks.get("complete") or \
            tasks.get("done") != tasks.get("total") or not tasks.get("total"):
        fail(f"{h5} is not a verified, complete file: verified {shown.get('verified')}, "
             f"tasks {tasks}")
    if not os.path.isfile(h5 + ".sum"):
        fail(f"{h5}.sum was not written")
    cached = glob.glob(os.path.join(h5 + ".tasks", "**", "*.h5"), recursive=True)
    if len(cached) < tasks["total"]:
        fail(f"{h5}.tasks holds {len(cached)} task files, fewer than the {tasks['total']} tasks")
    return tasks["total"]


def build(into, src):
    for name, profile in profile_args(src).items():
        out = os.path.join(into, name + ".h5")
        # The command line batch_engine, corruption, reader_typed and slurm_submit use.
        p = sirl_testing.run_sirl("run", profile, "--threads", "2", "--quiet", "--out", out,
                                  timeout=3600)
        if p.returncode:
            fail(f"sirl run {profile} --threads 2 --quiet --out {out}: rc {p.returncode}\n"
                 f"{p.stdout[-2000:]}{p.stderr[-2000:]}")
        # The output's lock (and any other leftover beside it) is no part of the fixture.
        for extra in os.listdir(into):
            if extra.startswith(name + ".h5") and extra not in (name + ".h5", name + ".h5.sum",
                                                                name + ".h5.tasks"):
                path = os.path.join(into, extra)
                shutil.rmtree(path) if os.path.isdir(path) else os.remove(path)
        n = check_complete(into, name)
        print(f"built: {name}.h5 ({n} tasks, complete and verified) and its cache")


def exchange(a, b):
    """Swaps two paths in one step (Linux renameat2 RENAME_EXCHANGE); False where unsupported."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    AT_FDCWD, RENAME_EXCHANGE = -100, 2
    rc = renameat2(AT_FDCWD, os.fsencode(a), AT_FDCWD, os.fsencode(b), RENAME_EXCHANGE)
    if rc != 0:
        err = ctypes.get_errno()
        if err in (22, 38, 95):  # EINVAL, ENOSYS, EOPNOTSUPP: the file system cannot
            return False
        raise OSError(err, os.strerror(err), a)
    return True


def put_in_place(new, target):
    if not os.path.lexists(target):
        os.rename(new, target)
        return
    if exchange(new, target):
        shutil.rmtree(new)  # the old folder, now at NEW's name
        return
    old = new + ".old"
    os.rename(target, old)
    os.rename(new, target)
    shutil.rmtree(old)


def main():
    target = os.environ.get("SIRL_SMOKE_FIXTURE")
    if not target:
        fail("SIRL_SMOKE_FIXTURE is not set (tests/CMakeLists.txt sets it)")
    target = os.path.abspath(target)
    src = sirl_testing.source_dir()
    parent = os.path.dirname(target)
    os.makedirs(parent, exist_ok=True)
    with open(target + ".lock", "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # one builder at a time; the others then reuse
        want = stamp(src)
        manifest = read_manifest(target)
        if manifest and manifest.get("stamp") == want:
            diff = differences(target, manifest)
            if not diff:
                print(f"smoke_fixture: OK (reused {target}: stamp matches, "
                      f"{len(manifest['files'])} files as listed)")
                return
            print("the fixture's files changed since it was built, rebuilding:",
                  "; ".join(diff[:5]))
        elif manifest:
            print("the fixture's stamp differs (another binary, CPU class or profile), rebuilding")
        # Folders a killed builder left (only the lock holder builds: none is in use).
        base = os.path.basename(target)
        for stale in glob.glob(os.path.join(parent, base + ".building-*")):
            shutil.rmtree(stale, ignore_errors=True)
        new = tempfile.mkdtemp(prefix=base + ".building-", dir=parent)
        try:
            build(new, src)
            files = hash_tree(new)
            with open(os.path.join(new, "MANIFEST.json.tmp"), "w") as f:
                json.dump({"stamp": want, "files": files}, f, indent=1, sort_keys=True)
                f.write("\n")
            os.rename(os.path.join(new, "MANIFEST.json.tmp"), os.path.join(new, "MANIFEST.json"))
            os.chmod(new, 0o755)
            put_in_place(new, target)
        except BaseException:
            shutil.rmtree(new, ignore_errors=True)
            raise
    print(f"smoke_fixture: OK (built {target}: {len(files)} files)")


if __name__ == "__main__":
    main()
