#!/usr/bin/env bash
# End-to-end checks of `ctxfuse classify train|test`: a round trip on simulated data, agreement
# with libsvm's own svm-train/svm-predict tools on a libsvm model (when they are installed),
# and clear errors (never a crash) for malformed CSVs, models and command lines.
# usage: cli_test.sh <path to ctxfuse> <scratch dir>
set -u
cli=$1
work=$2
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 1
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# Three Gaussian classes in two features on different scales (deterministic awk generator).
gen() {  # gen <rows> <seed> <file>
  awk -v n="$1" -v seed="$2" 'BEGIN {
    srand(seed); print "label,snr,count"
    for (i = 0; i < n; ++i) {
      c = i % 3 + 1; m1 = (c == 1 ? 40 : c == 2 ? 32 : 22); m2 = (c == 1 ? 20 : c == 2 ? 12 : 5)
      u1 = rand(); u2 = rand(); z1 = sqrt(-2 * log(u1 + 1e-12)) * cos(6.283185307 * u2)
      z2 = sqrt(-2 * log(u1 + 1e-12)) * sin(6.283185307 * u2)
      printf "%d,%.4f,%.4f\n", c, m1 + 3 * z1, m2 + 3 * z2
    }}' > "$3"
}
gen 600 1 train.csv
gen 300 2 test.csv

# 1. Round trip with our model format.
"$cli" classify train --data train.csv --kernel rbf --multiclass ovr --probability --folds 4 --model ours.model > train.out 2>&1 \
  || fail "train exited $?: $(cat train.out)"
head -1 ours.model | grep -q '^ctxfuse-svm 1$' || fail "model does not start with the ctxfuse-svm header"
grep -q 'cv        4-fold stratified accuracy' train.out || fail "train did not report the cross-validated accuracy"
"$cli" classify test --model ours.model --data test.csv --json r.json --predictions p.csv > test.out 2>&1 \
  || fail "test exited $?: $(cat test.out)"
acc=$(sed -n 's/^  "accuracy": \([0-9.]*\),$/\1/p' r.json)
awk -v a="$acc" 'BEGIN { exit !(a > 0.85) }' || fail "accuracy '$acc' not above 0.85"
[ "$(wc -l < p.csv)" -eq 301 ] || fail "predictions file should have 300 rows plus a header"
awk -F, 'NR > 1 { s = $4 + $5 + $6; if (s < 0.999999 || s > 1.000001) bad++ } END { exit bad > 0 }' p.csv \
  || fail "class probabilities do not sum to one"
grep -q '^confusion matrix' test.out || fail "no confusion matrix printed"

# 2. A libsvm model trained by svm-train: our predictions must equal svm-predict's.
if command -v svm-train > /dev/null && command -v svm-predict > /dev/null; then
  to_libsvm() { awk -F, 'NR > 1 { printf "%s 1:%s 2:%s\n", $1, $2, $3 }' "$1"; }
  to_libsvm train.csv > train.svm
  to_libsvm test.csv > test.svm
  svm-train -q -c 2 -g 0.01 -b 1 train.svm lib.model > /dev/null || fail "svm-train failed"
  svm-predict -b 1 test.svm lib.model lib.pred > /dev/null || fail "svm-predict failed"
  "$cli" classify test --model lib.model --data test.csv --predictions ours.pred > lib.out 2>&1 || fail "test on a libsvm model exited $?"
  # svm-predict -b 1 writes "labels 1 2 3" then "label p1 p2 p3" per row.
  paste -d' ' <(tail -n +2 lib.pred) <(tail -n +2 ours.pred | tr ',' ' ') | awk '
    { if ($1 != $7) lab++; for (k = 2; k <= 4; ++k) { d = $k - $(k + 6); if (d < 0) d = -d; if (d > 1e-6) prob++ } }
    END { if (lab + prob > 0) { print lab " label and " prob " probability mismatches"; exit 1 } }' \
    || fail "our predictions differ from svm-predict on its own model"
else
  echo "note: svm-train/svm-predict not installed; libsvm tool comparison skipped"
fi

# 3. Malformed inputs: status 1 and a message naming file, line and column; never a crash.
expect_error() {  # expect_error <status> <message fragment> <command...>
  local status=$1 fragment=$2
  shift 2
  "$@" > err.out 2>&1
  local got=$?
  [ "$got" -eq "$status" ] || fail "'$*' exited $got, expected $status: $(cat err.out)"
  grep -qF -- "$fragment" err.out || fail "'$*' did not say '$fragment': $(cat err.out)"
}
printf 'label,snr,count\n1,40,20\n2,abc,12\n' > bad_number.csv
expect_error 1 "bad_number.csv:3: column 'snr' (2): expected a number, got 'abc'" "$cli" classify test --model ours.model --data bad_number.csv
printf 'label,snr,count\n1,40\n' > short_row.csv
expect_error 1 "short_row.csv:2: expected 3 fields, got 2" "$cli" classify test --model ours.model --data short_row.csv
printf 'snr,count\n40,20\n' > no_label.csv
expect_error 1 "no_label.csv:1: header has no 'label' column" "$cli" classify train --data no_label.csv --model x.model
printf 'label,snr,count\n1.5,40,20\n' > frac_label.csv
expect_error 1 "frac_label.csv:2: column 'label' (1): label must be an integer" "$cli" classify test --model ours.model --data frac_label.csv
printf 'label,snr,count\n1,nan,20\n' > nan.csv
expect_error 1 "nan.csv:2: column 'snr' (2): value is NaN or Inf" "$cli" classify test --model ours.model --data nan.csv
: > empty.csv
expect_error 1 "empty.csv: file is empty" "$cli" classify train --data empty.csv --model x.model
printf 'label,a,b,c\n1,1,2,3\n' > three.csv
expect_error 1 "model expects 2 features" "$cli" classify test --model ours.model --data three.csv
printf 'label,snr,count\n1,40,20\n1,41,21\n' > one_class.csv
expect_error 1 "1 classes; need 2" "$cli" classify train --data one_class.csv --model x.model
sed 's/^gamma .*/gamma abc/' ours.model > bad.model
expect_error 1 "bad.model:4: gamma: expected a finite number, got 'abc'" "$cli" classify test --model bad.model --data test.csv
head -c 700 ours.model > cut.model
"$cli" classify test --model cut.model --data test.csv > err.out 2>&1
[ $? -eq 1 ] || fail "truncated model: expected status 1: $(cat err.out)"
expect_error 1 "missing.csv: cannot open" "$cli" classify test --model ours.model --data missing.csv
expect_error 2 "unknown option '--bogus'" "$cli" classify train --data train.csv --model x.model --bogus
expect_error 2 "--kernel: expected linear or rbf" "$cli" classify train --data train.csv --model x.model --kernel poly
expect_error 2 "test needs --data and --model" "$cli" classify test --data test.csv

if [ "$failures" -ne 0 ]; then
  echo "$failures check(s) failed"
  exit 1
fi
echo "all classify CLI checks passed"
