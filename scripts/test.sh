#!/usr/bin/env bash
# Configures, builds and runs the whole test suite:  scripts/test.sh [preset]
# preset: release (default, g++), clang, release-v3, clang-v3, debug-asan or clang-asan (see
# CMakePresets.json); build tree build/<preset>. Prints ctest's summary; the exit status is
# ctest's (or the build's, when the build fails). Honours CTXFUSE_DATA_DIR (the shared/data
# folder; default ../shared/data next to the repository) and CI=true (missing data fails
# instead of skipping).
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$repo/scripts/deps.sh"
preset="${1:-release}"
jobs="$(ctxfuse_jobs)"

ctxfuse_ensure_deps

cd "$repo"
echo "== configure ($preset)"
ctxfuse_configure "$preset"
echo "== build ($preset, $jobs jobs)"
cmake --build --preset "$preset" -j "$jobs"
echo "== test ($preset, $jobs jobs)"
status=0
ctest --preset "$preset" -j "$jobs" || status=$?
exit "$status"
