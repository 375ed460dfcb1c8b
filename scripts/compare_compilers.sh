#!/usr/bin/env bash
# Runs `ctxfuse demo` from the g++ and the clang release builds on the same seeds and checks
# that every number they print in JSON agrees exactly (scripts/compare_compilers.py says why):
#   scripts/compare_compilers.sh [seed ...]      (default seeds: 1 2)
# Needs build/release and build/clang (scripts/test.sh release, scripts/test.sh clang).
set -uo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="$repo/build/compare-compilers"
mkdir -p "$out"
seeds=("$@")
((${#seeds[@]})) || seeds=(1 2)
status=0
for seed in "${seeds[@]}"; do
  for preset in release clang; do
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
  echo "== seed $seed: g++ vs clang"
  python3 "$repo/scripts/compare_compilers.py" "$out/release-$seed.json" "$out/clang-$seed.json" || status=1
done
exit "$status"
