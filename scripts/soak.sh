#!/usr/bin/env bash
# The soak of issue 18 item 5 (tests/reliability/soak.hpp says what it checks): a simulated
# drive at 100 Hz through the geodetic GNSS/INS filter and the region pipeline's plain IMM.
#   scripts/soak.sh [hours, default 24] [seed, default 1]
# Builds the program in a Release build dir (CTXFUSE_SOAK_BUILD, default build/soak; g++ unless
# CXX says otherwise), runs it under /usr/bin/time when there is one, and exits with its status
# (0 passed, 1 a check failed or an error exceeded its bound). Not part of CI: 24 simulated
# hours take about a minute of CPU (docs/reliability.md).
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
hours="${1:-24}"
seed="${2:-1}"
build="${CTXFUSE_SOAK_BUILD:-$repo/build/soak}"

if [[ ! -f "$build/build.ninja" ]]; then
  cmake -S "$repo" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER="${CXX:-g++}" >/dev/null
fi
cmake --build "$build" -j "${CTXFUSE_SOAK_JOBS:-1}" --target reliability_soak
exe="$build/tests/reliability/reliability_soak"
if [[ -x /usr/bin/time ]]; then
  exec /usr/bin/time -f "wall %e s, user %U s, max RSS %M kB" "$exe" "$hours" "$seed"
fi
exec "$exe" "$hours" "$seed"
