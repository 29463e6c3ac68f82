#!/usr/bin/env bash
# README command 2: install what is missing, build (release), run the whole test suite; then the
# sanitizer builds: clang with AddressSanitizer + UndefinedBehaviorSanitizer (the GoogleTest suite
# and a short run of each libFuzzer target over its seed corpus), then ThreadSanitizer on the
# threaded paths (scripts/tsan.sh). SIRL_SANITIZE=0 skips both.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh --tests
./scripts/build.sh release
sanitize="${SIRL_SANITIZE:-1}"
scratch="" background=""
cleanup() {
  if [ -n "$background" ]; then kill -- -"$background" 2>/dev/null || true; fi
  if [ -n "$scratch" ]; then rm -rf "$scratch"; fi
}
trap cleanup EXIT
# The tests' scratch files on a RAM file system when it has room: the suite writes and fsyncs
# thousands of small files (results, task caches, checkpoints, the nightly history's SQLite), and
# an fsync costs milliseconds on a disk, microseconds there. No test relies on the disk itself
# (disk_full's full disk is a file-size limit, which tmpfs honours). An exported TMPDIR is kept.
if [ -z "${TMPDIR:-}" ] && [ -d /dev/shm ] &&
   [ "$(df -Pk /dev/shm | awk 'NR == 2 { print $4 }')" -ge $((4 * 1024 * 1024)) ]; then
  scratch="$(mktemp -d /dev/shm/sirl-tests.XXXXXX)"
  chmod 711 "$scratch"  # munged (tests/one_node_slurm.py) wants every folder above its socket searchable
  export TMPDIR="$scratch"
fi

# Each sanitizer build runs beside the test stage before it, at the lowest CPU priority, so it
# takes only the cores those tests leave idle (the release suite's tests wait on Slurm, a browser,
# sockets and their own subprocesses: about a sixth of its core-seconds); the stage that needs the
# build then waits for the rest of it. Its own session (setsid) lets cleanup stop every compiler
# it started; in a session of its own it is also its own scheduling group where the kernel groups
# by session (autogroup), so its group's nice value is lowered too, or nice alone would not rank it
# below the tests.
start_build() {  # start_build PRESET [TARGET...]: in the background, output to build/PRESET.log
  local preset="$1"
  shift
  mkdir -p build
  echo "test.sh: building the $preset preset beside the tests, at the lowest priority (build/$preset.log)"
  # shellcheck disable=SC2016  # $0 and $@ belong to the inner shell
  (exec setsid bash -c 'echo 19 > /proc/self/autogroup 2>/dev/null || true
    p="$0"; cmake --preset "$p" >/dev/null && exec nice -n 19 cmake --build --preset "$p" "$@"' \
    "$preset" "$@") >"build/$preset.log" 2>&1 </dev/null &
  background=$!
}
finish_build() {  # finish_build PRESET: waits for start_build's build; its output either way
  local preset="$1" status=0
  wait "$background" || status=$?
  background=""
  if [ "$status" != 0 ]; then
    cat "build/$preset.log" >&2
    echo "test.sh: the $preset build failed (exit $status; its output above, in build/$preset.log)" >&2
    exit 1
  fi
  tail -n 1 "build/$preset.log"
}

if [ "$sanitize" != 0 ]; then start_build asan; fi
# One ctest job per core, plus one for the tests that mostly wait (tests/CMakeLists.txt: cores
# are a ctest resource those tests do not take).
jobs=$(($(nproc) + 1))
ctest --preset release -j "$jobs" --resource-spec-file "$PWD/build/release/ctest-cores.json" "$@"
if [ "$sanitize" != 0 ]; then
  finish_build asan
  start_build tsan --target sirl sirl_tests
  ctest --preset asan -j 2 -LE python
  finish_build tsan
  ./scripts/tsan.sh
fi
