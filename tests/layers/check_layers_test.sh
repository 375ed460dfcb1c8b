#!/usr/bin/env bash
# check_layers_test.sh PYTHON REPO WORK: the layer check passes on REPO and fails, naming the
# file and line, on copies of REPO's headers with one wrong include planted each.
set -uo pipefail
python="$1"
repo="$2"
work="$3"
check="$repo/scripts/check_layers.py"
failures=0

expect() {  # expect <0|1> <pattern or -> <root>
  local want="$1" pattern="$2" root="$3" out status
  out="$("$python" "$check" --root "$root" 2>&1)"
  status=$?
  if [[ "$status" != "$want" ]]; then
    echo "FAIL: check_layers on $root exited $status, expected $want"; echo "$out"; failures=$((failures + 1)); return
  fi
  if [[ "$pattern" != "-" ]] && ! grep -qF -- "$pattern" <<<"$out"; then
    echo "FAIL: check_layers on $root did not print '$pattern'"; echo "$out"; failures=$((failures + 1)); return
  fi
  echo "ok: exit $want${pattern:+, '$pattern'}"
}

fresh_copy() {
  rm -rf "$work/$1"
  mkdir -p "$work/$1/include"
  cp -r "$repo/include/ctxfuse" "$work/$1/include/"
  echo "$work/$1"
}

# The tree as it is.
expect 0 "every include points down" "$repo"

# An upward include: core includes a pipeline.
root="$(fresh_copy upward)"
printf '#include "ctxfuse/pipelines/gins/run.hpp"\n' >>"$root/include/ctxfuse/core/types.hpp"
n=$(wc -l <"$root/include/ctxfuse/core/types.hpp")
expect 1 "include/ctxfuse/core/types.hpp:$n: 'core' includes 'pipelines', a higher layer" "$root"

# A peer include: models includes io.
root="$(fresh_copy peer)"
printf '#include <ctxfuse/io/text.hpp>\n' >>"$root/include/ctxfuse/models/planar.hpp"
expect 1 "'models' includes 'io', a peer" "$root"

# One pipeline includes another.
root="$(fresh_copy sibling)"
printf '#include "ctxfuse/pipelines/nlos_uwb/run.hpp"\n' >>"$root/include/ctxfuse/pipelines/gins/run.hpp"
expect 1 "pipelines/gins includes pipelines/nlos_uwb" "$root"

# An inference header that pulls in libsvm (SVM training).
root="$(fresh_copy libsvm)"
printf '#include "ctxfuse/classify/svm_train.hpp"\n' >>"$root/include/ctxfuse/pipelines/nlos_uwb/classifier.hpp"
expect 1 "includes ctxfuse/classify/svm_train.hpp (libsvm) outside a training header" "$root"

# A new folder that is not in the layer table.
root="$(fresh_copy unknown)"
mkdir -p "$root/include/ctxfuse/extras"
printf '#pragma once\n' >"$root/include/ctxfuse/extras/x.hpp"
expect 1 "folder 'extras' has no layer" "$root"

if ((failures > 0)); then
  echo "$failures failure(s)"
  exit 1
fi
echo "all layer-check cases passed"
