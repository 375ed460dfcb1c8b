#!/usr/bin/env bash
# Runs `ctxfuse demo` from the g++ and the clang release builds on the same seeds and checks
# that every number they print in JSON agrees exactly (scripts/compare_compilers.py says why),
# then the same for the error-state path the demo does not use yet: 2000 IMM steps with three
# 15-state ESKF modes and 2000 steps of three independent ESKFs (bench_imm_steps prints the
# final position to 17 digits). With --v3, also the g++ x86-64-v3 build's demo (the speed build
# of docs/benchmarks.md) against the default g++ build: equal to a relative 1e-9, since fused
# multiply-adds round differently (seeds 1-5 differ by at most 4e-13); a fault of the kind
# that -march=native triggers in g++ 12.2 would show as far more. (CI checks the v3 build with
# scripts/v3_smoke.sh instead, which does not build the tool.)
#   scripts/compare_compilers.sh [--v3] [seed ...]      (default seeds: 1 2)
# Needs build/release and build/clang (the tool and bench_imm_steps), and build/release-v3's
# tool for --v3. CTXFUSE_CLANG_TOOL_PRESET=clang-asan takes clang's demo from the sanitized
# build instead (CI does: it builds that tool anyway, and its demo prints the same numbers;
# bench_imm_steps still comes from build/clang, clang's -O3).
set -uo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="$repo/build/compare-compilers"
mkdir -p "$out"
clang_tool="${CTXFUSE_CLANG_TOOL_PRESET:-clang}"
presets=(release "$clang_tool")
if [[ "${1:-}" == --v3 ]]; then
  presets+=(release-v3)
  shift
fi
seeds=("$@")
((${#seeds[@]})) || seeds=(1 2)
status=0
for seed in "${seeds[@]}"; do
  for preset in "${presets[@]}"; do
    cli="$repo/build/$preset/tools/ctxfuse"
    if [[ ! -x "$cli" ]]; then
      echo "compare_compilers: $cli is missing; build it with scripts/test.sh $preset"
      exit 2
    fi
    if ! "$cli" demo --seed "$seed" --json "$out/$preset-$seed.json" >"$out/$preset-$seed.txt" 2>&1; then
      echo "compare_compilers: the $preset demo failed on seed $seed (log $out/$preset-$seed.txt)"
      status=1
    fi
  done
  echo "== seed $seed: g++ vs clang ($clang_tool)"
  python3 "$repo/scripts/compare_compilers.py" "$out/release-$seed.json" "$out/$clang_tool-$seed.json" || status=1
  if [[ " ${presets[*]} " == *" release-v3 "* ]]; then
    echo "== seed $seed: g++ x86-64 vs g++ x86-64-v3 (relative 1e-9)"
    python3 "$repo/scripts/compare_compilers.py" --rel-tol 1e-9 "$out/release-$seed.json" "$out/release-v3-$seed.json" || status=1
  fi
done
for workload in imm three_eskf; do
  a=$("$repo/build/release/bench/imm/bench_imm_steps" "$workload" 2000 2>&1) || status=1
  b=$("$repo/build/clang/bench/imm/bench_imm_steps" "$workload" 2000 2>&1) || status=1
  if [[ "$a" == "$b" ]]; then
    echo "== bench_imm_steps $workload 2000: g++ and clang agree ($a)"
  else
    echo "== bench_imm_steps $workload 2000: g++ $a, clang $b: DIFFERENT"
    status=1
  fi
done
exit "$status"
