#!/usr/bin/env python3
"""Compares two `ctxfuse demo --json` documents number by number:
    scripts/compare_compilers.py [--rel-tol X] A.json B.json
Both come from the same sources built by two compilers (g++ and clang in .ci/run). IEEE
arithmetic in the same order gives the same bits, and the library's code has no compiler-
dependent branches, so any difference beyond wall-clock timings is a miscompilation or
undefined behaviour on one side (this found a g++ 12.2 one: core/numerics.hpp, symmetrize).
--rel-tol X accepts numbers within a relative difference X instead: for two instruction-set
levels (x86-64 against x86-64-v3, whose fused multiply-adds round once instead of twice).
Keys naming wall-clock time (containing "elapsed" or ending in "_ns"/"_us"/"per_second") are
skipped. Exit status 1 on any difference, with every differing key printed."""
import json
import sys

TIMING_MARKERS = ("elapsed", "per_second")
TIMING_SUFFIXES = ("_ns", "_us")


def is_timing(key):
    return any(m in key for m in TIMING_MARKERS) or key.endswith(TIMING_SUFFIXES)


def walk(a, b, path, out, rel_tol=0.0):
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if is_timing(k):
                continue
            p = f"{path}.{k}" if path else k
            if k not in a or k not in b:
                out.append(f"{p}: present in only one document")
            else:
                walk(a[k], b[k], p, out, rel_tol)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            out.append(f"{path}: lists of {len(a)} and {len(b)} entries")
        for i, (x, y) in enumerate(zip(a, b)):
            walk(x, y, f"{path}[{i}]", out, rel_tol)
    elif a != b and not (isinstance(a, float) and isinstance(b, float) and a != a and b != b):
        numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (a, b))
        if numbers and rel_tol > 0.0 and abs(a - b) <= rel_tol * max(abs(a), abs(b)):
            return
        out.append(f"{path}: {a!r} vs {b!r}")


def main():
    args = sys.argv[1:]
    rel_tol = 0.0
    if len(args) == 4 and args[0] == "--rel-tol":
        try:
            rel_tol = float(args[1])
        except ValueError:
            rel_tol = -1.0
        args = args[2:]
    if len(args) != 2 or not rel_tol >= 0.0:
        print(__doc__, file=sys.stderr)
        return 2
    docs = []
    for name in args:
        try:
            with open(name) as f:
                docs.append(json.load(f))
        except (OSError, ValueError) as e:
            print(f"compare_compilers: {name}: {e}", file=sys.stderr)
            return 2
    diffs = []
    walk(docs[0], docs[1], "", diffs, rel_tol)
    for d in diffs:
        print("differs:", d)
    print(f"compare_compilers: {len(diffs)} differing values")
    return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main())
