#!/usr/bin/env python3
"""Compares two `ctxfuse demo --json` documents number by number:
    scripts/compare_compilers.py A.json B.json
Both come from the same sources built by two compilers (g++ and clang in .ci/run). IEEE
arithmetic in the same order gives the same bits, and the library's code has no compiler-
dependent branches, so any difference beyond wall-clock timings is a miscompilation or
undefined behaviour on one side (this found a g++ 12.2 one: core/numerics.hpp, symmetrize).
Keys naming wall-clock time (containing "elapsed" or ending in "_ns"/"_us"/"per_second") are
skipped. Exit status 1 on any difference, with every differing key printed."""
import json
import sys

TIMING_MARKERS = ("elapsed", "per_second")
TIMING_SUFFIXES = ("_ns", "_us")


def is_timing(key):
    return any(m in key for m in TIMING_MARKERS) or key.endswith(TIMING_SUFFIXES)


def walk(a, b, path, out):
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if is_timing(k):
                continue
            p = f"{path}.{k}" if path else k
            if k not in a or k not in b:
                out.append(f"{p}: present in only one document")
            else:
                walk(a[k], b[k], p, out)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            out.append(f"{path}: lists of {len(a)} and {len(b)} entries")
        for i, (x, y) in enumerate(zip(a, b)):
            walk(x, y, f"{path}[{i}]", out)
    elif a != b and not (isinstance(a, float) and isinstance(b, float) and a != a and b != b):
        out.append(f"{path}: {a!r} vs {b!r}")


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    docs = []
    for name in sys.argv[1:]:
        try:
            with open(name) as f:
                docs.append(json.load(f))
        except (OSError, ValueError) as e:
            print(f"compare_compilers: {name}: {e}", file=sys.stderr)
            return 2
    diffs = []
    walk(docs[0], docs[1], "", diffs)
    for d in diffs:
        print("differs:", d)
    print(f"compare_compilers: {len(diffs)} differing values")
    return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main())
