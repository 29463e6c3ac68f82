#!/usr/bin/env bash
# README command 2: install what is missing, build (release), run the whole test suite; then the
# sanitizer builds: clang with AddressSanitizer + UndefinedBehaviorSanitizer (the GoogleTest suite
# and a short run of each libFuzzer target over its seed corpus), then ThreadSanitizer on the
# threaded paths (scripts/tsan.sh). SIRL_SANITIZE=0 skips both.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh --tests
./scripts/build.sh release
ctest --preset release -j 2 "$@"
if [ "${SIRL_SANITIZE:-1}" != 0 ]; then
  cmake --preset asan >/dev/null
  cmake --build --preset asan
  ctest --preset asan -j 2 -LE python
  ./scripts/tsan.sh
fi
