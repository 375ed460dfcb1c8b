#!/usr/bin/env bash
# The table of docs/results.md "gins_platforms": the simulated walk and robot of
# `ctxfuse sim --platform` (seeds 1-3), each run by `ctxfuse run gins` with the outage protocol
# (15 s every 45 s from 40 s, GNSS at 1 Hz) under its own platform's settings, the car's, and
# no constraints, scored against the run's truth (reference/truth.pos).
# Usage: scripts/gins_platforms.sh [BUILD_DIR]   (default build/release; needs python3)
set -euo pipefail
build="${1:-build/release}"
tool="$build/tools/ctxfuse"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
echo "| platform | seed | settings | constraints | outages RMS / max [m] | smoothed RMS / max [m] | whole run RMS [m] | aligned after [s] | heading from |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
for platform in pedestrian robot; do
  for seed in 1 2 3; do
    rec="$work/$platform$seed"
    "$tool" sim --platform "$platform" --seed "$seed" --out "$rec" >/dev/null
    for settings in "$platform" car "$platform none"; do
      set -- $settings
      args=(--platform "$1")
      [[ $# -gt 1 ]] && args+=(--constraints "$2")
      "$tool" run gins --data "$rec" "${args[@]}" --outage 15:45:40 --gnss-rate 1 --smooth \
        --reference "$rec/reference/truth.pos" --json "$work/m.json" >/dev/null
      python3 - "$work/m.json" "$platform" "$seed" "$1" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
f, s, w, a = d["forward"], d["smoothed"], d["whole_run"]["forward"], d["alignment"]
print(f"| {sys.argv[2]} | {sys.argv[3]} | {sys.argv[4]} | {d['constraints']} | {f['rms_m']:.3f} / {f['max_m']:.3f} | "
      f"{s['rms_m']:.3f} / {s['max_m']:.3f} | {w['rms_m']:.3f} | {a['time_after_first_fix_s']:.2f} | {a['heading_source']} |")
EOF
    done
  done
done
