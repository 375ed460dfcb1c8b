#!/usr/bin/env bash
# The opt-in -march=native build (CTXFUSE_NATIVE=ON), kept tested: g++ 12.2 has miscompiled
# small fixed-size Eigen code with it on AVX-512 machines, which is why no preset uses it.
# Builds the core, filter and IMM test binaries and the IMM step driver with it in
# build/native, runs every test of those binaries, and requires bench_imm_steps to agree with
# the default build's (build/release) to a relative 1e-12 (fused multiply-adds round once).
#   scripts/native_smoke.sh     (needs build/release: scripts/test.sh release)
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$repo/scripts/deps.sh"
build="$repo/build/native"
# The areas' test executables (tests/CMakeLists.txt): core, filters and IMM.
tests=(core/core_tests filters/filters_tests imm/imm_tests)
cmake -S "$repo" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCTXFUSE_NATIVE=ON >/dev/null
targets=(bench_imm_steps)
for t in "${tests[@]}"; do targets+=("$(basename "$t")"); done
cmake --build "$build" -j "$(ctxfuse_jobs)" --target "${targets[@]}"
status=0
for t in "${tests[@]}"; do
  if "$build/tests/$t" --gtest_brief=1 >"$build/$(basename "$t").log" 2>&1; then
    echo "native: $(basename "$t") passed ($(grep -o '[0-9]* tests\?' "$build/$(basename "$t").log" | tail -1))"
  else
    echo "native: $(basename "$t") FAILED (log $build/$(basename "$t").log)"
    status=1
  fi
done
for workload in imm three_eskf; do
  a=$("$repo/build/release/bench/imm/bench_imm_steps" "$workload" 2000)
  b=$("$build/bench/imm/bench_imm_steps" "$workload" 2000)
  if python3 -c "import sys; a, b = float(sys.argv[1]), float(sys.argv[2]); sys.exit(0 if abs(a - b) <= 1e-12 * max(abs(a), abs(b)) else 1)" "$a" "$b"; then
    echo "native: bench_imm_steps $workload agrees with the default build ($b vs $a)"
  else
    echo "native: bench_imm_steps $workload: $b, default build $a: DIFFERENT"
    status=1
  fi
done
exit "$status"
