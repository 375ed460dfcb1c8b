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
grep -q '^cv        accuracy .* (4 contiguous blocks (row order))' train.out || fail "train did not report the blocked cross-validated accuracy"
grep -q '^cv: fold 4/4, 600 samples scored' train.out || fail "no per-fold progress on stderr"
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
expect_error 1 "bad_number.csv:3:2: column 'snr': 'abc' is not a number" "$cli" classify test --model ours.model --data bad_number.csv
printf 'label,snr,count\n1,40\n' > short_row.csv
expect_error 1 "short_row.csv:2: 2 fields, expected 3 (as in the header)" "$cli" classify test --model ours.model --data short_row.csv
printf 'snr,count\n40,20\n' > no_label.csv
expect_error 1 "no_label.csv:1: header has no 'label' column" "$cli" classify train --data no_label.csv --model x.model
printf 'label,snr,count\n1.5,40,20\n' > frac_label.csv
expect_error 1 "frac_label.csv:2:1: column 'label': '1.5' is not a whole number" "$cli" classify test --model ours.model --data frac_label.csv
printf 'label,snr,count\n1,nan,20\n' > nan.csv
expect_error 1 "nan.csv:2:2: column 'snr': 'nan' is not finite" "$cli" classify test --model ours.model --data nan.csv
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
expect_error 2 "--bogus" "$cli" classify train --data train.csv --model x.model --bogus
expect_error 2 "--kernel: poly not in {linear,rbf}" "$cli" classify train --data train.csv --model x.model --kernel poly
expect_error 2 "--model is required" "$cli" classify test --data test.csv
expect_error 2 "--class-weight" "$cli" classify train --data train.csv --model x.model --class-weight 1:x
expect_error 1 "--cv groups needs --groups COL" "$cli" classify train --data train.csv --model x.model --cv groups

# 4. --help of every sub-command exits 0 and lists every option with its default.
help_has() {  # help_has <fragment...> -- <command...>
  local fragments=()
  while [ "$1" != "--" ]; do fragments+=("$1"); shift; done
  shift
  "$@" > help.out 2>&1 || fail "'$* ' exited $?"
  for f in "${fragments[@]}"; do grep -qF -- "$f" help.out || fail "'$*' does not list '$f'"; done
}
help_has "--pso-samples UINT=2000" "--score" "=accuracy" "--cv" "=auto" "--folds INT" "=5" "--class-weight" "--groups" "--ignore TEXT=[time_s]" -- "$cli" classify train --help
help_has "--predictions" "--label TEXT=label" "--features" -- "$cli" classify test --help
help_has "--window FLOAT" "=4" "--cn0-window" "--fill FLOAT=-1" "--labels" "--label-tolerance FLOAT:NONNEGATIVE=0.05" -- "$cli" features gnss --help
help_has "--open-max-error FLOAT" "=0.6" "--window" "--train-fraction" -- "$cli" features nmea --help
help_has "--window INT" "=1" "--height-column" -- "$cli" features uwb-static --help
help_has "--static" "--data" "--out" -- "$cli" features dw1000 --help
help_has "--validation-fraction FLOAT" "=0.25" "--decoder" "=viterbi" "--covariance" "=diagonal" -- "$cli" context joint --help
expect_error 2 "--train is required" "$cli" context joint --test test.csv

# 5. Column selection: named label, chosen features, text columns left alone; classes sorted.
awk -F, 'BEGIN { OFS = "," } NR == 1 { print "time_s,note,count,cls,snr"; next } { print NR, "x" NR, $3, $1, $2 }' train.csv > cols.csv
"$cli" classify train --data cols.csv --label cls --features snr,count --model cols.model > cols.out 2>&1 || fail "column selection: $(cat cols.out)"
grep -q 'features (snr,count)' cols.out || fail "train did not use --features snr,count in order: $(cat cols.out)"
"$cli" classify train --data train.csv --model plain.model > /dev/null 2>&1
cmp -s <(tail -n +2 cols.model) <(tail -n +2 plain.model) || fail "--label/--features model differs from the same columns in label,snr,count order"
expect_error 1 "cols.csv:2:2: column 'note': 'x2' is not a number" "$cli" classify train --data cols.csv --label cls --ignore time_s --model x.model
awk -F, 'NR == 1 || $1 != 1' train.csv | awk -F, 'BEGIN { OFS = "," } NR == 1 { print; next } { $1 = ($1 == 2 ? 9 : 4); print }' > relabel.csv
"$cli" classify train --data relabel.csv --model relabel.model > /dev/null 2>&1 || fail "train on labels 9/4 failed"
"$cli" classify test --data relabel.csv --model relabel.model > relabel.out 2>&1
grep -q '^true\\pred       4       9$' relabel.out || fail "confusion matrix not labelled in ascending order: $(cat relabel.out)"

# 6. Grouped validation and class weights.
awk -F, 'BEGIN { OFS = "," } NR == 1 { print $0, "run"; next } { print $0, int((NR - 2) / 100) }' train.csv > groups.csv
"$cli" classify train --data groups.csv --groups run --folds 0 --pso --pso-swarm 2 --pso-iterations 1 --class-weight auto --score macro-f1 \
  --model g.model > g.out 2>&1 || fail "grouped PSO: $(cat g.out)"
grep -q 'folds     leave-one-group-out over 6 groups' g.out || fail "not leave-one-group-out over the 6 runs: $(cat g.out)"
grep -q '^pso: iteration 1/1, 4 cross-validations, best macro-f1' g.out || fail "no PSO progress: $(cat g.out)"
grep -q '^weights   1:1 2:1 3:1' g.out || fail "auto weights of three equal classes are not 1: $(cat g.out)"

# 7. features gnss: receiver conventions (rows of one epoch in any order and mix of
# constellations, -91 / empty / out-of-range geometry) and the label join by time.
cat > sats.csv <<'CSV'
time_s,sat_id,elevation_deg,azimuth_deg,cn0_dbhz
1,G01,20,10,40
1,R05,-91,,48
2,E11,60,300,36
1,E11,60,300,36
2,G01,20,10,42
1,G07,40,100,44
2,R05,-91,0,50
2,G07,40,400,44
CSV
printf 'time_s,label\n1.01,3\n2,5\n7,4\n' > scene_labels.csv
"$cli" features gnss --sats sats.csv --labels scene_labels.csv --out feat.csv 2> feat.err || fail "features gnss: $(cat feat.err)"
grep -q '2 epochs .* 3 tracked satellite rows without geometry .* 2 labelled, 0 without a label' feat.err \
  || fail "features gnss did not report the rows without geometry / the join: $(cat feat.err)"
# t = 1: 4 satellites, mean C/N0 42, mean elevation of G01/G07/E11 = 40, vacancy of azimuths 10, 100, 300 = 200.
# t = 2: G07's azimuth 400 is out of range: geometry only for G01 and E11.
head -1 feat.csv | grep -q '^time_s,label,satellite_count,pdop,mean_cn0_dbhz' || fail "feature header: $(head -1 feat.csv)"
awk -F, 'NR == 2 && !($2 == 3 && $3 == 4 && $5 == 42 && $9 == 40 && $10 == 200) { exit 1 }
         NR == 3 && !($2 == 5 && $3 == 4 && $9 == 40) { exit 1 }' feat.csv || fail "features of the hand-computed epochs: $(cat feat.csv)"
"$cli" classify train --data feat.csv --features satellite_count,mean_cn0_dbhz --model f.model > /dev/null 2>&1 \
  || fail "features gnss output does not feed classify"

# 8. features dw1000: the manual's formulas, checked with awk.
printf 'label,range_m,fp_amp1,fp_amp2,fp_amp3,cir_power,rxpacc,std_noise,prf_mhz,other\n1,10.5,14305,15276,14270,6491,230,52,64,x\n0,3,9000,8000,7000,3000,1000,40,16,y\n' > dw.csv
"$cli" features dw1000 --data dw.csv --out dw_feat.csv > dw.out 2>&1 || fail "features dw1000: $(cat dw.out)"
head -1 dw_feat.csv | grep -qx 'label,rx_power_dbm,fp_power_dbm,rx_minus_fp_db,noise_dbm,range_m' || fail "dw1000 header: $(head -1 dw_feat.csv)"
paste -d, <(tail -n +2 dw.csv) <(tail -n +2 dw_feat.csv) | awk -F, '
  function db(x) { return 10 * log(x) / log(10) }
  { a = ($9 == 16 ? 113.77 : 121.74); n2 = $7 * $7
    e[1] = db($6 * 131072 / n2) - a; e[2] = db(($3 * $3 + $4 * $4 + $5 * $5) / n2) - a; e[3] = e[1] - e[2]
    e[4] = db($8 * $8 / n2) - a; e[5] = $2
    if ($11 != $1) bad++
    for (k = 1; k <= 5; ++k) { d = e[k] - $(11 + k); if (d < 0) d = -d; if (d > 1e-6) bad++ } }
  END { exit bad > 0 }' || fail "dw1000 features differ from the manual's formulas: $(cat dw_feat.csv)"
expect_error 2 "give --data CSV or --static DIR" "$cli" features dw1000 --out x.csv

# 9. The CSV readers of features gnss / dw1000 and context joint (io/text.hpp): CRLF, blank
# lines and a leading '+' change nothing; bad input names file, line and column.
same_as() {  # same_as <reference> <output> <command...>: succeeds and writes what the reference holds
  local reference=$1 output=$2
  shift 2
  "$@" > cmd.out 2>&1 || fail "'$*' exited $?: $(cat cmd.out)"
  cmp -s "$reference" "$output" || fail "'$*' wrote other output than $reference"
}
cat > r_sats.csv <<'CSV'
time_s,sat_id,elevation_deg,azimuth_deg,cn0_dbhz,pdop
1,G01,20,10,40,2.5
1,G07,40,100,44,2.5
1,E11,60,300,36,
1,R05,-91,,48,
CSV
"$cli" features gnss --sats r_sats.csv --out r_feat.csv 2> /dev/null || fail "features gnss on r_sats.csv"
sed 's/$/\r/' r_sats.csv > r_crlf.csv
same_as r_feat.csv r_out.csv "$cli" features gnss --sats r_crlf.csv --out r_out.csv
awk 'NR == 3 { print "" } { print }' r_sats.csv > r_blank.csv
same_as r_feat.csv r_out.csv "$cli" features gnss --sats r_blank.csv --out r_out.csv
sed 's/,40,/,+40,/' r_sats.csv > r_plus.csv
same_as r_feat.csv r_out.csv "$cli" features gnss --sats r_plus.csv --out r_out.csv
sed 's/^1,G07,40,100/1,G07,1e300,nan/' r_sats.csv > r_nogeo.csv
"$cli" features gnss --sats r_nogeo.csv --out r_out.csv 2> cmd.out || fail "features gnss on r_nogeo.csv: $(cat cmd.out)"
grep -q '2 tracked satellite rows without geometry' cmd.out || fail "1e300 / nan geometry not counted as unknown: $(cat cmd.out)"
printf 'time_s,label\n1,2.0\n' > r_labels.csv
"$cli" features gnss --sats r_sats.csv --labels r_labels.csv --out r_out.csv 2> cmd.out || fail "label 2.0 refused: $(cat cmd.out)"
awk -F, 'NR == 2 && $2 != 2 { exit 1 }' r_out.csv || fail "label 2.0 not read as 2: $(cat r_out.csv)"
printf 'label,range_m,fp_amp1,fp_amp2,fp_amp3,cir_power,rxpacc,std_noise,prf_mhz,other\n1,10.5,14305,15276,14270,6491,230,52,64,x\n' > r_dw.csv
"$cli" features dw1000 --data r_dw.csv --out r_dw_feat.csv > /dev/null 2>&1 || fail "features dw1000 on r_dw.csv"
sed 's/$/\r/' r_dw.csv > r_dw_crlf.csv
same_as r_dw_feat.csv r_out.csv "$cli" features dw1000 --data r_dw_crlf.csv --out r_out.csv
awk 'BEGIN { srand(3); print "label,snr,count"  # rows in time order, regions 0, 1, 2 in turn
  for (i = 0; i < 300; ++i) { c = int(i / 20) % 3; printf "%d,%.3f,%.3f\n", c, 40 - 9 * c + 4 * rand(), 20 - 7 * c + 4 * rand() } }' > r_joint.csv
"$cli" context joint --train r_joint.csv --test r_joint.csv > r_joint.out 2>&1 || fail "context joint: $(cat r_joint.out)"
sed 's/$/\r/' r_joint.csv > r_joint_crlf.csv
same_as r_joint.out cmd.out "$cli" context joint --train r_joint.csv --test r_joint_crlf.csv
expect_error 1 "absent.csv: cannot open file" "$cli" features gnss --sats absent.csv
# Each case: the command, the file it reads as bad.csv, the sed edit that makes it bad, the message.
while IFS='|' read -r command source edit fragment <&3; do
  sed "$edit" "$source" > bad.csv
  case $command in
    gnss) expect_error 1 "$fragment" "$cli" features gnss --sats bad.csv ;;
    labels) expect_error 1 "$fragment" "$cli" features gnss --sats r_sats.csv --labels bad.csv --out r_out.csv ;;
    dw1000) expect_error 1 "$fragment" "$cli" features dw1000 --data bad.csv --out r_out.csv ;;
    joint) expect_error 1 "$fragment" "$cli" context joint --train r_joint.csv --test bad.csv ;;
  esac
done 3<<'CASES'
gnss|r_sats.csv|3s/,44,/,150,/|bad.csv:3:5: column 'cn0_dbhz': '150' outside [0, 100]
gnss|r_sats.csv|3s/,44,/,abc,/|bad.csv:3:5: column 'cn0_dbhz': 'abc' is not a number
gnss|r_sats.csv|3s/,40,/,4x,/|bad.csv:3:3: column 'elevation_deg': '4x' has characters after the number
gnss|r_sats.csv|3s/^1,/inf,/|bad.csv:3:1: column 'time_s': 'inf' is not finite
gnss|r_sats.csv|3s/,2.5$/,0/|bad.csv:3:6: column 'pdop': '0' is not a positive number
gnss|r_sats.csv|3s/,2.5$/,3/|bad.csv:3:6: column 'pdop': '3' differs from the epoch's other pdop (line 2)
gnss|r_sats.csv|3s/G07/G01/|bad.csv:3:2: column 'sat_id': 'G01' appears twice in the epoch at time_s 1 (also line 2)
gnss|r_sats.csv|3s/,100,44,2.5$//|bad.csv:3: 3 fields, expected 6 (as in the header)
gnss|r_sats.csv|1s/^time_s/time/|bad.csv:1: header has no column 'time_s'
gnss|r_sats.csv|d|bad.csv: empty file (no header)
labels|r_labels.csv|2s/2.0/1.5/|bad.csv:2:2: column 'label': '1.5' is not a whole number
labels|r_labels.csv|1s/label/lbl/|bad.csv:1: header has no column 'label'
dw1000|r_dw.csv|2s/^1,/1.5,/|bad.csv:2:1: column 'label': '1.5' is not a whole number
dw1000|r_dw.csv|2s/,14305,/,abc,/|bad.csv:2:3: column 'fp_amp1': 'abc' is not a number
dw1000|r_dw.csv|2s/,10.5,/,inf,/|bad.csv:2:2: column 'range_m': 'inf' is not finite
dw1000|r_dw.csv|2s/,64,x$//|bad.csv:2: 8 fields, expected 10 (as in the header)
dw1000|r_dw.csv|1s/std_noise/noise/|bad.csv:1: header has no column 'std_noise'
joint|r_joint.csv|3s/^0,/3,/|bad.csv:3:1: column 'label': '3' is outside the allowed range [0, 2]
joint|r_joint.csv|3s/^0,/0.5,/|bad.csv:3:1: column 'label': '0.5' is not a whole number
joint|r_joint.csv|4s/,[0-9.]*$/,nan/|bad.csv:4:3: column 'count': 'nan' is not finite
joint|r_joint.csv|4s/,[0-9.]*$//|bad.csv:4: 2 fields, expected 3 (as in the header)
joint|r_joint.csv|1s/label/region/|bad.csv:1: header has no column 'label'
joint|r_joint.csv|2,$d|bad.csv: no data rows
CASES

if [ "$failures" -ne 0 ]; then
  echo "$failures check(s) failed"
  exit 1
fi
echo "all classify CLI checks passed"
