"""Helpers shared by the Python tests in tests/ (not a test itself; ctest does not run it).

It holds only what three or more tests repeated with the same behaviour:

- where things are: `sirl_binary()`, `source_dir()`, `build_dir()` read the SIRL,
  SIRL_SOURCE_DIR and SIRL_BUILD_DIR environment variables ctest sets (tests/CMakeLists.txt), a
  missing one raising KeyError as `os.environ[...]` does; `data_path(name)` is tests/data/NAME;
- `make_fail(test_name)`: a test's `fail(msg, p=None)`, which prints "TEST_NAME: FAIL: MSG" to
  stdout (with the exit code and the tails of stdout and stderr of `p`, a CompletedProcess, when
  given) and exits 1;
- `run_sirl(*args, timeout=...)`: runs the sirl binary with stdout and stderr captured (text by
  default), stdin closed, and the given timeout; it returns the CompletedProcess and checks
  nothing, each test judging the exit code and wording its own failure message;
- `sha256_file(path)`: the SHA-256 hex digest of a file's bytes (to see that a file is
  untouched);
- `copy_fixture(name, dest_h5, ...)`: a private copy of the smoke fixture's results file and/or
  task cache ("smoke" or "engine-test", built once per binary by tests/make_smoke_fixture.py in
  $SIRL_SMOKE_FIXTURE); False when that variable is unset (a test run by hand), the caller then
  running sirl as before.

A test imports it from its own folder, run as `/usr/bin/python3 tests/NAME.py` with only the
standard library and the packages the tests already use:

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import sirl_testing  # noqa: E402
"""
import hashlib
import os
import shutil
import subprocess
import sys


def sirl_binary():
    """The sirl executable under test ($SIRL)."""
    return os.environ["SIRL"]


def source_dir():
    """The project's source folder ($SIRL_SOURCE_DIR)."""
    return os.environ["SIRL_SOURCE_DIR"]


def build_dir():
    """The CMake build folder ($SIRL_BUILD_DIR)."""
    return os.environ["SIRL_BUILD_DIR"]


def data_path(name):
    """tests/data/NAME in the source folder."""
    return os.path.join(source_dir(), "tests", "data", name)


def make_fail(test_name):
    """A `fail(msg, p=None)` printing "TEST_NAME: FAIL: MSG" and exiting 1; with `p` (a
    CompletedProcess) the message ends with its exit code and the tails of its output."""
    def fail(msg, p=None):
        if p is not None:
            out, err = p.stdout or "", p.stderr or ""
            if isinstance(out, bytes):
                out, err = out.decode(errors="replace"), err.decode(errors="replace")
            msg += f"\n--- exit {p.returncode}; stdout:\n{out[-4000:]}\n--- stderr:\n{err[-3000:]}"
        print(f"{test_name}: FAIL:", msg)
        sys.exit(1)
    return fail


def run_sirl(*args, timeout=None, text=True, stdin=subprocess.DEVNULL, **kwargs):
    """`sirl ARGS...` with its output captured and stdin closed (unless `stdin` says otherwise);
    other keywords (cwd, env, preexec_fn, ...) go to subprocess.run. No exit code is checked."""
    return subprocess.run([sirl_binary(), *args], capture_output=True, text=text, stdin=stdin,
                          timeout=timeout, **kwargs)


def sha256_file(path):
    """The SHA-256 hex digest of the file's bytes."""
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


FIXTURE_NAMES = ("smoke", "engine-test")


def copy_fixture(name, dest_h5=None, with_file=True, with_cache=True, cache_dest=None):
    """Copies the smoke fixture's NAME ("smoke": `sirl run smoke --threads 2 --quiet`;
    "engine-test": the same on tests/data/engine-test.toml) for a test to use as its own:
    - with_file: NAME.h5 to DEST_H5 and its .sum beside it (the file name inside the .sum line
      made DEST_H5's, as sirl writes it: `DIGEST  BASENAME`);
    - with_cache: the task cache NAME.h5.tasks/ to CACHE_DEST (default DEST_H5 + ".tasks"), a
      real copy (shutil.copytree: a run writes lock files in a cache in place, so never links).
    The fixture itself is never written (smoke_fixture_unchanged checks). Returns True when
    copied; False when $SIRL_SMOKE_FIXTURE is unset (a script run by hand): the caller then
    computes what it needs as it would without the fixture. A destination that exists, or a
    fixture folder without NAME's files, raises."""
    if name not in FIXTURE_NAMES:
        raise ValueError(f"copy_fixture: {name!r} is not one of {FIXTURE_NAMES}")
    if not (with_file or with_cache):
        raise ValueError("copy_fixture: nothing to copy")
    if with_file and not dest_h5:
        raise ValueError("copy_fixture: with_file needs dest_h5")
    if with_cache and cache_dest is None:
        if not dest_h5:
            raise ValueError("copy_fixture: with_cache needs dest_h5 or cache_dest")
        cache_dest = dest_h5 + ".tasks"
    folder = os.environ.get("SIRL_SMOKE_FIXTURE")
    if not folder:
        return False
    src = os.path.join(folder, name + ".h5")
    if not os.path.isfile(src) or not os.path.isfile(os.path.join(folder, "MANIFEST.json")):
        raise FileNotFoundError(f"SIRL_SMOKE_FIXTURE={folder} holds no finished {name}.h5 "
                                "(the smoke_fixture test builds it)")
    if with_file:
        for path in (dest_h5, dest_h5 + ".sum"):
            if os.path.lexists(path):
                raise FileExistsError(f"copy_fixture: {path} exists")
        shutil.copyfile(src, dest_h5)
        with open(src + ".sum") as f:
            digest, _ = f.read().rstrip("\n").split("  ", 1)
        with open(dest_h5 + ".sum", "w") as f:
            f.write(f"{digest}  {os.path.basename(dest_h5)}\n")
    if with_cache:
        shutil.copytree(src + ".tasks", cache_dest, symlinks=False)  # raises if it exists
    return True
