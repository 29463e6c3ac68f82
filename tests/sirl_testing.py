"""Helpers shared by the Python tests in tests/ (not a test itself; ctest does not run it).

It holds only what three or more tests repeated with the same behaviour:

- where things are: `sirl_binary()`, `source_dir()`, `build_dir()` read the SIRL,
  SIRL_SOURCE_DIR and SIRL_BUILD_DIR environment variables ctest sets (tests/CMakeLists.txt), a
  missing one raising KeyError as `os.environ[...]` does; `data_path(name)` is tests/data/NAME;
- `make_fail(test_name)`: a test's `fail(msg)`, which prints "TEST_NAME: FAIL: MSG" to stdout
  and exits 1;
- `run_sirl(*args, timeout=...)`: runs the sirl binary with stdout and stderr captured (text by
  default), stdin closed, and the given timeout; it returns the CompletedProcess and checks
  nothing, each test judging the exit code and wording its own failure message;
- `sha256_file(path)`: the SHA-256 hex digest of a file's bytes (to see that a file is
  untouched).

A test imports it from its own folder, run as `/usr/bin/python3 tests/NAME.py` with only the
standard library and the packages the tests already use:

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import sirl_testing  # noqa: E402
"""
import hashlib
import os
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
    """A `fail(msg)` printing "TEST_NAME: FAIL: MSG" and exiting 1."""
    def fail(msg):
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
