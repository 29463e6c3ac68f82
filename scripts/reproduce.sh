#!/usr/bin/env bash
# README command 1: install what is missing, build the engine (only the `sirl` command: the test
# command builds the tests and benchmarks), run the main job.
#   ./scripts/reproduce.sh                 smoke first (a first look in about a minute), then quick
#   ./scripts/reproduce.sh [PROFILE] [sirl reproduce options...]   that reproduction only
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/build.sh release sirl
if [ "$#" -eq 0 ]; then
  echo "reproduce.sh: first the whole pipeline at toy scale (smoke, about a minute; its numbers" \
       "mean nothing), then the main job (quick)" >&2
  ./build/release/app/sirl reproduce smoke
  echo "reproduce.sh: smoke's report: out/smoke-figures/report.md (report.html for a browser);" \
       "now quick" >&2
  exec ./build/release/app/sirl reproduce quick
fi
exec ./build/release/app/sirl reproduce "$@"
