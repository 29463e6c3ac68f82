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
  TMPDIR="$(mktemp -d /dev/shm/sirl-tests.XXXXXX)"
  chmod 711 "$TMPDIR"  # munged (tests/one_node_slurm.py) wants every folder above its socket searchable
  export TMPDIR
  trap 'rm -rf "$TMPDIR"' EXIT
fi
# One ctest job per core, plus one for the tests that mostly wait (tests/CMakeLists.txt: cores
# are a ctest resource those tests do not take).
jobs=$(($(nproc) + 1))
ctest --preset release -j "$jobs" --resource-spec-file "$PWD/build/release/ctest-cores.json" "$@"
if [ "${SIRL_SANITIZE:-1}" != 0 ]; then
  cmake --preset asan >/dev/null
  cmake --build --preset asan
  ctest --preset asan -j 2 -LE python
  ./scripts/tsan.sh
fi
