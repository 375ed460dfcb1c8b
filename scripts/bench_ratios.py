#!/usr/bin/env python3
"""Prints the ratios quoted in docs/benchmarks.md from Google Benchmark JSON files.

Each ratio is the median CPU time of one benchmark over another measured in the same run.
Usage: bench_ratios.py FILE.json [FILE.json ...]
"""
import json
import sys

# (numerator, denominator, what the ratio says). Names are matched by prefix, so
# ZeroOverhead/Engine matches ZeroOverhead/Engine/repeats:5_median.
RATIOS = [
    ("ZeroOverhead/Engine", "ZeroOverhead/HandWritten", "engine / hand-written (target <= 1.05)"),
    ("ZeroOverhead/Dynamic", "ZeroOverhead/Engine", "dynamic / engine (target >= 3)"),
    ("SvmPredictProbability/LibSvm", "SvmPredictProbability/Ours", "libsvm / ours, RBF predict with probabilities (target >= 8)"),
    ("BM_ImmStep3Eskf15", "BM_ThreeIndependentEskf15", "IMM step / three independent ESKF steps (mixing overhead)"),
]


def medians(paths):
    out = {}
    for path in paths:
        with open(path) as f:
            doc = json.load(f)
        for b in doc.get("benchmarks", []):
            if b.get("aggregate_name") == "median" or ("aggregate_name" not in b and b["name"] not in out):
                name = b.get("run_name", b["name"])
                out[name] = b["cpu_time"] * {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}[b.get("time_unit", "ns")]
    return out


def lookup(table, prefix):
    hits = [v for k, v in table.items() if k == prefix or k.startswith(prefix + "/")]
    return hits[0] if len(hits) == 1 else None


def main(paths):
    table = medians(paths)
    for name, ns in sorted(table.items()):
        print(f"{name:60s} {ns:12.1f} ns (median CPU)")
    print()
    for num, den, what in RATIOS:
        a, b = lookup(table, num), lookup(table, den)
        if a is not None and b is not None:
            print(f"{what}: {a / b:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
