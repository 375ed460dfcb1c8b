#!/usr/bin/env bash
# Builds the libFuzzer targets of fuzz/ (clang, -fsanitize=fuzzer,address,undefined) in
# build/fuzz and runs each for a bounded time:
#   scripts/fuzz.sh [seconds per target, default 60] [target ...]   (default: every target)
# Targets run two at a time (CTXFUSE_FUZZ_JOBS, default: the number of cores). Each starts
# from a corpus in build/fuzz/corpus/<target> seeded with fuzz/seeds, the heads of the shared
# recordings when ../shared/data is there, and the inputs of tests/fuzz_regressions/<target>,
# so that a run never forgets a past finding. A crash, sanitizer report or broken invariant
# stops that target and leaves its input in build/fuzz/artifacts/<target>/; the script then
# prints how to replay it and exits 1. Every finding becomes a regression input: copy it to
# tests/fuzz_regressions/<target>/, where ctest replays it in every build.
set -uo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${1:-60}"
shift || true
build="$repo/build/fuzz"
data="${CTXFUSE_DATA_DIR:-$repo/../shared/data}"
jobs="${CTXFUSE_FUZZ_JOBS:-$(nproc 2>/dev/null || echo 2)}"
all=(text_fuzz rtklib_pos_fuzz imu_tag_fuzz hanyang_uwb_fuzz nmea_fuzz uwb_static_fuzz sim_logs_fuzz
     svm_io_fuzz recogniser_io_fuzz ekf_update_fuzz)
targets=("$@")
((${#targets[@]})) || targets=("${all[@]}")

echo "== configure and build (clang, $build)"
cmake -S "$repo/fuzz" -B "$build" -G Ninja -DCMAKE_CXX_COMPILER=clang++ >/dev/null || exit 1
cmake --build "$build" -j "$jobs" --target "${targets[@]}" || exit 1

echo "== seed corpora"
# Seeds in the shape each target decodes: a selector byte, a 2-byte length prefix
# (fuzz_support.hpp, split2), or the file as it is.
python3 - "$repo" "$build/corpus" "$data" <<'PY' || exit 1
import pathlib, struct, sys
repo, out, data = (pathlib.Path(a) for a in sys.argv[1:4])
seeds = repo / "fuzz" / "seeds"
def head(p, n=3000):
    try:
        b = p.read_bytes()[:n]
    except OSError:
        return None
    return b if len(b) < n else b[: b.rfind(b"\n") + 1]  # whole lines, as a real file has
def two(a, b):
    return struct.pack("<H", len(a)) + a + b
def put(target, name, content):
    if content is None:
        return
    d = out / target
    d.mkdir(parents=True, exist_ok=True)
    (d / name).write_bytes(content)
drive = data / "gnss-imu-drive"
case = data / "uwb-outdoor-hanyang/Dynamic_measurements/LOS/Trajectory_A/Case_2"
static = data / "uwb-outdoor-hanyang/Static_measurements/LOS/height_50.0cm/58m.csv"
put("text_fuzz", "text.csv", (seeds / "text.csv").read_bytes())
put("text_fuzz", "imu.csv", head(drive / "imu_1934.csv", 400))
put("rtklib_pos_fuzz", "drive.pos", head(drive / "gnss_1934_sf.pos"))
imu, tag = head(drive / "imu_1934.csv", 1500), head(drive / "imu_1934.csv.tag", 200)
if imu is not None and tag is not None:
    put("imu_tag_fuzz", "drive", two(imu, tag[: 76 + 8 * ((len(tag) - 76) // 8)]))
a3, traj = head(case / "A3.csv"), head(case / "trajectory.csv")
if a3 is not None and traj is not None:
    put("hanyang_uwb_fuzz", "case2", two(a3, traj))
put("nmea_fuzz", "f9k.nmea", head(data / "gnss-nmea-mtv/mtv_f9k.nmea", 4000))
put("uwb_static_fuzz", "58m", None if head(static) is None else two(b"height_50.0cm", head(static)))
sim = {0: b"t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z\n0,0.01,0,0,0.1,0,9.81\n0.01,0.01,0,0,0.1,0,9.8\n",
       3: b"t,anchor_id,anchor_x,anchor_y,anchor_z,range,rssi,rssi_fp,nlos\n1,2,0,0,3,5.5,-80,-82,0\n1,3,10,0,3,6.1,-81,-90,1\n",
       4: b"t,speed\n0,1.5\n0.1,1.6\n",
       5: b"t,mag_x,mag_y,mag_z\n0,20,0,-40\n"}
for sel, content in sim.items():
    put("sim_logs_fuzz", f"sel{sel}", bytes([sel]) + content)
put("sim_logs_fuzz", "gnss_sats", bytes([7]) + two(
    b"t,fix,east,north,up,std_h,std_v,num_sats,pdop,hdop,mean_cn0\n1,1,0,0,0,2,3,4,1.5,1,40\n",
    b"t,sat_id,elevation_deg,azimuth_deg,cn0_dbhz,los\n" + b"".join(b"1,%d,30,%d,40,1\n" % (s, 40 * s) for s in range(1, 5))))
svm, libsvm = (seeds / "svm_ctxfuse.txt").read_bytes(), (seeds / "svm_libsvm.txt").read_bytes()
put("svm_io_fuzz", "ours", b"\x00" + svm)
put("svm_io_fuzz", "libsvm", b"\x01" + libsvm)
put("recogniser_io_fuzz", "recogniser", (seeds / "recogniser.txt").read_bytes())
# A well-conditioned tame-number case (bit 0 clear) and a raw-double one.
put("ekf_update_fuzz", "tame", b"\x00" + bytes(range(1, 200)))
put("ekf_update_fuzz", "raw", b"\x01" + struct.pack("<40d", *([1.0, 0.5, 2.0, -1.0] + [0.1 * k for k in range(36)])))
PY

status=0
run_one() {
  local t="$1" corpus="$build/corpus/$1" artifacts="$build/artifacts/$1/"
  mkdir -p "$corpus" "$artifacts"
  local regressions="$repo/tests/fuzz_regressions/$t"
  [[ -d "$regressions" ]] && cp -n "$regressions"/* "$corpus"/ 2>/dev/null
  # -rss_limit_mb / -malloc_limit_mb: a reader that allocates gigabytes on a short input is a
  # finding too; -timeout: one input taking 10 s is a hang.
  if "$build/$t" "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 \
       -artifact_prefix="$artifacts" -print_final_stats=1 >"$build/$t.log" 2>&1; then
    echo "fuzz: $t ok: $(grep -m1 -o 'stat::number_of_executed_units: *[0-9]*' "$build/$t.log" | grep -o '[0-9]*$') runs in ${seconds} s, corpus $(ls "$corpus" | wc -l) inputs"
  else
    echo "fuzz: $t FAILED (log $build/$t.log); the input is in $artifacts:"
    ls "$artifacts" | sed 's/^/    /'
    grep -m3 -E 'ERROR|runtime error|invariant broken|SUMMARY' "$build/$t.log" | sed 's/^/    /'
    echo "    replay: $build/$t <input>; keep it: copy it to tests/fuzz_regressions/$t/"
    return 1
  fi
}
export -f run_one
export build seconds repo
echo "== run: ${#targets[@]} targets, $seconds s each, $jobs at a time"
printf '%s\n' "${targets[@]}" | xargs -P "$jobs" -I{} bash -c 'run_one {}' || status=1
exit "$status"
