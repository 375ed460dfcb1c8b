#!/usr/bin/env bash
# Builds the Google Benchmark binaries (Release, no -march=native) and runs them with JSON
# output into out/bench/<binary>.json, then prints the ratios quoted in docs/benchmarks.md.
#   scripts/bench.sh                 # every benchmark binary
#   scripts/bench.sh zero_overhead   # only binaries whose name contains the word
# Times on a shared machine are noisy: the ratios compare variants measured in one run,
# with repetitions interleaved, and the medians of the CPU time are used.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
filter=${1:-}
build="$here/build/bench"
out="$here/out/bench"
mkdir -p "$out"
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCTXFUSE_BUILD_TESTS=OFF -DCTXFUSE_BUILD_TOOLS=OFF -DCTXFUSE_BUILD_EXAMPLES=OFF >/dev/null
cmake --build "$build" -j"$(nproc)"
for exe in $(find "$build/bench" -maxdepth 2 -type f -executable -name 'bench_*' ! -name '*_steps' | sort); do
  name=$(basename "$exe")
  [[ -n "$filter" && "$name" != *"$filter"* ]] && continue
  echo "== $name"
  "$exe" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
    --benchmark_out="$out/$name.json" --benchmark_out_format=json
done
python3 "$here/scripts/bench_ratios.py" "$out"/*.json
