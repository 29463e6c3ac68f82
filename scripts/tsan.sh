#!/usr/bin/env bash
# ThreadSanitizer on the engine's threaded paths (part of ./scripts/test.sh; tests/CMakeLists.txt
# lists the tests): the scheduler (a oneTBB task DAG), the threaded kernels (OpenMP; LLVM's Archer
# tells TSan about OpenMP's synchronisation), the MPI dispatcher and the study server's thread
# pool. The end-to-end tests run the micro profile (instrumented code is ~10x slower). Any report
# fails the stage, including one from a process a test killed: reports go to files, not to the
# killed process's exit code.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset tsan >/dev/null
cmake --build --preset tsan --target sirl sirl_tests
reports="$PWD/build/tsan/reports"
rm -rf "$reports" && mkdir -p "$reports"
archer="$(dirname "$(readlink -f "$(command -v clang)")")/../lib/libarcher.so"
[ -f "$archer" ] || { echo "tsan.sh: $archer missing (Debian: libomp-dev)" >&2; exit 1; }
export OMP_TOOL_LIBRARIES="$archer"
# Uninstrumented libraries (oneTBB, libomp, Open MPI, cpp-httplib) synchronise in code TSan cannot
# see; ignore_noninstrumented_modules keeps their internals out of the reports, ours stay in.
export TSAN_OPTIONS="ignore_noninstrumented_modules=1 halt_on_error=0 log_path=$reports/tsan suppressions=$PWD/tests/tsan.supp"
export SIRL_TEST_PROFILE="$PWD/tests/data/micro.toml"
export SIRL_CRASH_WALK_STRIDE=5  # every fifth crash point (the release suite walks them all)
# The threaded tests, as tests/CMakeLists.txt names them (the preset builds sirl_tests from their
# files only).
threaded="$(cat build/tsan/threaded-tests.regex)"
status=0
ctest --preset tsan -j $(($(nproc) + 1)) --resource-spec-file "$PWD/build/tsan/ctest-cores.json" -R "$threaded" ||
  status=$?
if compgen -G "$reports/tsan.*" >/dev/null; then
  echo "ThreadSanitizer reported data races (full reports in $reports):" >&2
  head -c 20000 "$reports"/tsan.* >&2
  exit 1
fi
exit "$status"
