#!/usr/bin/env python3
"""What including one public header costs, header by header.

    scripts/header_cost.py [--top N] [--jobs J] [--show HEADER] [header ...]

Compiles a source that includes only that header (clang++ -std=c++20 -O0 -ftime-trace) and
prints the front end's seconds and, of those, the seconds spent instantiating function
templates: the cost every source that includes the header pays whether or not it calls
anything. A header whose own inline, non-template code calls heavy templates shows a large
instantiation time here; docs/architecture.md ("Compile time") says how such code is kept
out of its includers. --show HEADER lists the largest top-level instantiations of one header.
Default: every header under include/ctxfuse, the 30 costliest. Needs clang++ (and libsvm's
headers for the headers that train, as the build does).
"""
import argparse
import concurrent.futures
import json
import os
import pathlib
import subprocess
import sys
import tempfile

REPO = pathlib.Path(__file__).resolve().parent.parent
INCLUDES = ["-I", str(REPO / "include"), "-isystem", "/usr/include/eigen3", "-I", "/usr/include/libsvm"]


def trace(header, work):
    src = pathlib.Path(work) / (header.replace("/", "_") + ".cpp")
    src.write_text(f'#include "{header}"\n')
    obj = src.with_suffix(".o")
    cmd = ["clang++", "-std=c++20", "-O0", "-ftime-trace", *INCLUDES, "-c", str(src), "-o", str(obj)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        return header, None, r.stderr.strip().splitlines()[:3]
    events = json.loads(obj.with_suffix(".json").read_text())["traceEvents"]
    return header, [e for e in events if e.get("ph") == "X"], None


def totals(events):
    t = {e["name"]: e["dur"] / 1e6 for e in events if e["name"].startswith("Total ")}
    return t.get("Total Frontend", 0.0), t.get("Total InstantiateFunction", 0.0)


def top_level(events, n):
    inst = sorted((e for e in events if e["name"] == "InstantiateFunction"), key=lambda e: e["ts"])
    out, end = [], -1
    for e in inst:
        if e["ts"] >= end:
            out.append(e)
            end = e["ts"] + e["dur"]
    return sorted(out, key=lambda e: -e["dur"])[:n]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("headers", nargs="*", help="paths under include/, e.g. ctxfuse/filters/ekf.hpp")
    ap.add_argument("--top", type=int, default=30)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--show", metavar="HEADER")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as work:
        if a.show:
            _, events, err = trace(a.show, work)
            if events is None:
                sys.exit(f"{a.show}: does not compile alone: {err}")
            fe, inst = totals(events)
            print(f"{a.show}: front end {fe:.2f} s, instantiating {inst:.2f} s; largest top-level instantiations:")
            for e in top_level(events, a.top):
                print(f"  {e['dur'] / 1e6:6.2f} s  {e['args']['detail'][:150]}")
            return
        headers = a.headers or sorted(str(p.relative_to(REPO / "include")) for p in (REPO / "include" / "ctxfuse").rglob("*.hpp"))
        rows, failed = [], []
        with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
            for header, events, err in pool.map(lambda h: trace(h, work), headers):
                if events is None:
                    failed.append((header, err))
                else:
                    rows.append((*totals(events), header))
    rows.sort(key=lambda r: -r[1])
    print(f"{'front end s':>11} {'instantiating s':>15}  header (clang++ -O0, included alone)")
    for fe, inst, h in rows[: a.top]:
        print(f"{fe:11.2f} {inst:15.2f}  {h}")
    print(f"{len(rows)} headers; front end {sum(r[0] for r in rows):.1f} s, instantiating {sum(r[1] for r in rows):.1f} s in all")
    for h, err in failed:
        print(f"does not compile alone: {h}: {err}")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
