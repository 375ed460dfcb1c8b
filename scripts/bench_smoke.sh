#!/usr/bin/env bash
# Runs every benchmark binary of a build once, briefly, to show that it starts, runs and
# writes its JSON:  scripts/bench_smoke.sh [build dir, default build/release]
# The figures are meaningless (tiny repetitions on a busy machine); benchmarks for the docs
# are run by hand as docs/benchmarks.md describes. Exit status 1 if any binary fails.
set -uo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${1:-$repo/build/release}"
out_dir="$build_dir/bench-smoke"
mkdir -p "$out_dir"

# *_steps binaries are instruction-count drivers that take arguments, not benchmarks.
mapfile -t binaries < <(find "$build_dir/bench" -mindepth 2 -maxdepth 2 -type f -perm -u+x ! -name '*_steps' 2>/dev/null | sort)
# Benchmarks with an expensive set-up (the SVM one trains a model with libsvm) use a small one.
export CTXFUSE_BENCH_SMOKE=1
if ((${#binaries[@]} == 0)); then
  echo "bench smoke: no benchmark binaries under $build_dir/bench"
  exit 0
fi

failed=0
for bin in "${binaries[@]}"; do
  name="$(basename "$bin")"
  json="$out_dir/$name.json"
  rm -f "$json"
  if "$bin" --benchmark_min_time=0.001 --benchmark_out="$json" --benchmark_out_format=json \
       >"$out_dir/$name.log" 2>&1 && [[ -s "$json" ]]; then
    echo "bench smoke: $name ok ($(grep -c '"run_name"' "$json") runs)"
  else
    echo "bench smoke: $name FAILED, log follows"
    sed 's/^/    /' "$out_dir/$name.log" | tail -20
    failed=1
  fi
done
exit "$failed"
