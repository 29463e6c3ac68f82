#!/usr/bin/env bash
# README command 1: install what is missing, build (release), run the main job.
#   ./scripts/reproduce.sh [sirl reproduce options...]
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/build.sh release
exec ./build/release/app/sirl reproduce "$@"
