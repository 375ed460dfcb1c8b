#!/usr/bin/env bash
# The x86-64-v3 (AVX2, FMA) release build, smoke-tested. Builds in build/release-v3 the core,
# filter and IMM test binaries, the IMM benchmark quoted by docs/benchmarks.md and the IMM step
# driver; runs every test of those binaries and the benchmark briefly; and requires
# bench_imm_steps to agree with the default build's (build/release) to a relative 1e-9 (fused
# multiply-adds round differently; the -march=native fault of g++ 12.2 would show as far more).
# The whole demo on v3: build its tool and run scripts/compare_compilers.sh --v3.
#   scripts/v3_smoke.sh     (needs build/release: scripts/test.sh release)
set -uo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$repo/scripts/deps.sh"
build="$repo/build/release-v3"
# The areas' test executables (tests/CMakeLists.txt): core, filters (EKF, ESKF, bad input,
# multilateration, fixed-lag RTS) and IMM (cycle, API, mixing, planar Jacobians).
tests=(core/core_tests filters/filters_tests imm/imm_tests)
targets=(bench_imm bench_imm_steps)
for t in "${tests[@]}"; do targets+=("$(basename "$t")"); done
(cd "$repo" && ctxfuse_configure release-v3 >/dev/null) || exit 1
cmake --build "$build" -j "$(ctxfuse_jobs)" --target "${targets[@]}" || exit 1
status=0
for t in "${tests[@]}"; do
  log="$build/$(basename "$t").log"
  if "$build/tests/$t" --gtest_brief=1 >"$log" 2>&1; then
    echo "v3: $(basename "$t") passed ($(grep -o '[0-9]* tests\?' "$log" | tail -1))"
  else
    echo "v3: $(basename "$t") FAILED; its output:"
    sed 's/^/    /' "$log"
    status=1
  fi
done
if ! "$build/bench/imm/bench_imm" --benchmark_min_time=0.001 >"$build/bench_imm.log" 2>&1; then
  echo "v3: bench_imm FAILED; its output:"
  sed 's/^/    /' "$build/bench_imm.log"
  status=1
fi
for workload in imm three_eskf; do
  if ! a=$("$repo/build/release/bench/imm/bench_imm_steps" "$workload" 2000); then
    echo "v3: the default build's bench_imm_steps $workload failed (build/release missing?)"
    status=1
    continue
  fi
  if ! b=$("$build/bench/imm/bench_imm_steps" "$workload" 2000); then
    echo "v3: bench_imm_steps $workload FAILED"
    status=1
    continue
  fi
  if python3 -c "import sys; a, b = float(sys.argv[1]), float(sys.argv[2]); sys.exit(0 if abs(a - b) <= 1e-9 * max(abs(a), abs(b)) else 1)" "$a" "$b"; then
    echo "v3: bench_imm_steps $workload agrees with the default build to 1e-9 ($b vs $a)"
  else
    echo "v3: bench_imm_steps $workload: $b, default build $a: DIFFERENT"
    status=1
  fi
done
exit "$status"
