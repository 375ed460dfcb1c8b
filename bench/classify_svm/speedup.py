#!/usr/bin/env python3
"""Speed ratios from one bench_classify_svm JSON file: libsvm time / our time per benchmark pair,
and for the fast Gauss transform rows (/Fast: target grid inside the data, source boxes outside;
/FastBoxes: source boxes only) exact / fast and libsvm / fast.

usage: speedup.py results.json [more.json ...]
Uses the median aggregate when the run had --benchmark_repetitions, else the single run; CPU time.
"""
import json
import sys


def main(paths):
    runs = []
    for path in paths:
        with open(path) as f:
            runs += json.load(f)["benchmarks"]
    times = {}
    for r in runs:
        name = r.get("run_name", r["name"])
        if r.get("run_type") == "aggregate" and r.get("aggregate_name") != "median":
            continue
        if r.get("error_occurred"):
            continue
        times[name] = (r["cpu_time"], r["time_unit"])
    for name, (ours, unit) in sorted(times.items()):
        if not name.endswith("/Ours"):
            continue
        base = name[: -len("/Ours")]
        other = times.get(base + "/LibSvm")
        if other and other[1] == unit:
            print(f"{base}: ours {ours:.2f} {unit}, libsvm {other[0]:.2f} {unit}, libsvm/ours = {other[0] / ours:.1f}x")
    for suffix, what in (("/Fast", "fast (target grid + boxes)"), ("/FastBoxes", "fast, source boxes only")):
        for name, (fast, unit) in sorted(times.items()):
            if not name.endswith(suffix) or name.startswith("SvmFastRbfBuild"):
                continue
            base = name[: -len(suffix)]
            ours, other = times.get(base + "/Ours"), times.get(base + "/LibSvm")
            if ours and other and ours[1] == unit == other[1]:
                print(f"{base}: {what} {fast:.3f} {unit}, exact/fast = {ours[0] / fast:.1f}x, libsvm/fast = {other[0] / fast:.0f}x")
    for suffix, what in (("/Fast", "the fast evaluator (target grid + boxes)"), ("/FastBoxes", "the source boxes alone")):
        for name, (t, unit) in sorted(times.items()):
            if name.startswith("SvmFastRbfBuild") and name.endswith(suffix):
                print(f"{name}: {t:.0f} {unit} to build {what}")
    block = {n: t for n, (t, _) in times.items() if n.startswith("RbfKernelBlock/")}
    for n, t in sorted(block.items()):
        print(f"{n}: {t:.1f} ns per 256 support vectors ({t / 256:.2f} ns each)")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
