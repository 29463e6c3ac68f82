#!/usr/bin/env bash
# README command 2: install what is missing, build (release), run the whole test suite; then the
# sanitizer builds: clang with AddressSanitizer + UndefinedBehaviorSanitizer (the GoogleTest suite
# and a short run of each libFuzzer target over its seed corpus), then ThreadSanitizer on the
# threaded paths (scripts/tsan.sh). SIRL_SANITIZE=0 skips both.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh --tests
./scripts/build.sh release
# The tests' scratch files on a RAM file system when it has room: the suite writes and fsyncs
# thousands of small files (results, task caches, checkpoints, the nightly history's SQLite), and
# an fsync costs milliseconds on a disk, microseconds there. No test relies on the disk itself
# (disk_full's full disk is a file-size limit, which tmpfs honours). An exported TMPDIR is kept.
if [ -z "${TMPDIR:-}" ] && [ -d /dev/shm ] &&
   [ "$(df -Pk /dev/shm | awk 'NR == 2 { print $4 }')" -ge $((4 * 1024 * 1024)) ]; then
  SIRL_TEST_TMPDIR="$(mktemp -d /dev/shm/sirl-tests.XXXXXX)"
  chmod 711 "$SIRL_TEST_TMPDIR"  # munged (tests/one_node_slurm.py) wants every folder above its socket searchable
  export TMPDIR="$SIRL_TEST_TMPDIR"
  trap 'rm -rf "$SIRL_TEST_TMPDIR"' EXIT
fi
sanitize="${SIRL_SANITIZE:-1}"
if [ "$sanitize" != 0 ]; then
  # The sanitizer builds compile while the release tests run, at the lowest priority: they take
  # only the CPU time the tests leave (a test waiting on Slurm, a browser, a subprocess or a
  # file), and finish at full speed once the tests are done. Each build's log and exit code go to
  # build/sanitizer-builds/; the stage that needs a build waits for its code.
  builds="$PWD/build/sanitizer-builds"
  rm -rf "$builds" && mkdir -p "$builds"
  set -m  # the builds in their own process group, so that an early exit stops all of them
  (
    set +e  # a failed build writes its code; the stage that needs it reports it
    nice -n 19 bash -c 'cmake --preset asan >/dev/null && cmake --build --preset asan' \
      >"$builds/asan.log" 2>&1
    echo $? >"$builds/asan.rc"
    nice -n 19 bash -c 'cmake --preset tsan >/dev/null && cmake --build --preset tsan --target sirl sirl_tests' \
      >"$builds/tsan.log" 2>&1
    echo $? >"$builds/tsan.rc"
  ) &
  builder=$!
  set +m
  trap 'kill -- -"$builder" 2>/dev/null || true; [ -z "${SIRL_TEST_TMPDIR:-}" ] || rm -rf "$SIRL_TEST_TMPDIR"' EXIT
fi
# Waits until the background build NAME has ended; fails with its log if it failed.
await_build() {
  while [ ! -s "$builds/$1.rc" ]; do
    kill -0 "$builder" 2>/dev/null || [ -s "$builds/$1.rc" ] ||
      { echo "test.sh: the $1 build ended without an exit code" >&2; exit 1; }
    sleep 1
  done
  if [ "$(cat "$builds/$1.rc")" != 0 ]; then
    tail -n 200 "$builds/$1.log" >&2
    echo "test.sh: the $1 build failed (whole log: $builds/$1.log)" >&2
    exit 1
  fi
}
# One ctest job per core, plus one for the tests that mostly wait (tests/CMakeLists.txt: cores
# are a ctest resource those tests do not take).
jobs=$(($(nproc) + 1))
ctest --preset release -j "$jobs" --resource-spec-file "$PWD/build/release/ctest-cores.json" "$@"
if [ "$sanitize" != 0 ]; then
  await_build asan
  ctest --preset asan -j 2 -LE python
  await_build tsan
  ./scripts/tsan.sh
fi
