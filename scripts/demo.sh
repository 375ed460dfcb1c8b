#!/usr/bin/env bash
# Builds the ctxfuse command-line tool and runs its main job:  scripts/demo.sh [demo options]
# i.e. `ctxfuse demo [options]` from the release build (build/release). Should the tool have no
# `demo` command, builds and runs every example in examples/ instead. Exit status: the demo's.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$repo/scripts/deps.sh"
preset=release
build_dir="$repo/build/$preset"
jobs="$(ctxfuse_jobs)"

ctxfuse_ensure_deps

cd "$repo"
echo "== configure ($preset)" >&2
ctxfuse_configure "$preset" >/dev/null
echo "== build the ctxfuse tool" >&2
cmake --build --preset "$preset" -j "$jobs" --target ctxfuse_cli

cli="$build_dir/tools/ctxfuse"
if "$cli" --help 2>/dev/null | grep -Eq '^  demo( |$)'; then
  args=("$@")
  # The JSON document is part of the main job: written to out/demo.json unless asked elsewhere.
  if [[ " $* " != *" --json "* ]]; then
    mkdir -p "$repo/out"
    args+=(--json "$repo/out/demo.json")
  fi
  echo "== $cli demo ${args[*]}" >&2
  exec "$cli" demo "${args[@]}"
fi

echo "== '$cli' has no demo command yet; running the examples instead" >&2
mapfile -t examples < <(cd "$repo/examples" && ls -1 -- *.cpp 2>/dev/null | sed 's/\.cpp$//')
if ((${#examples[@]} == 0)); then
  echo "error: no demo command and no examples/*.cpp to run" >&2
  exit 1
fi
targets=()
for name in "${examples[@]}"; do targets+=("example_$name"); done
cmake --build --preset "$preset" -j "$jobs" --target "${targets[@]}"
for name in "${examples[@]}"; do
  echo "== example $name" >&2
  "$build_dir/examples/example_$name"
done
