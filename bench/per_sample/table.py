#!/usr/bin/env python3
"""The per-sample timing table from one bench_per_sample JSON file, beside the NLOS paper's Table 5.

usage: table.py bench_per_sample.json
Median aggregate when the run had --benchmark_repetitions (else the single run), CPU time. A
benchmark that reported an error is printed as such, never as a time.
"""
import json
import sys

# Paper C, Table 5 (i5-7300HQ), us per sample.
PAPER = {"SVM": 189.3, "Consistency": 1.0, "DS": 0.6, "Fusion": 2322.6, "Total": 2513.5}
EPOCH = 4  # ranges per fusion step


def load(path):
    with open(path) as f:
        doc = json.load(f)
    us, errors = {}, {}
    scale = {"ns": 1e-3, "us": 1.0, "ms": 1e3, "s": 1e6}
    for r in doc["benchmarks"]:
        name = r.get("run_name", r["name"])
        if r.get("error_occurred"):
            errors[name] = r.get("error_message", "error")
            continue
        if r.get("run_type") == "aggregate" and r.get("aggregate_name") != "median":
            continue
        us[name] = r["cpu_time"] * scale[r["time_unit"]]
    return doc.get("context", {}), us, errors


def main(path):
    context, us, errors = load(path)
    for name, message in sorted(errors.items()):
        print(f"ERROR {name}: {message}")

    def get(name):
        return us.get("PerSample/" + name)

    per_range = {
        "SVM": get("SVM"),
        "Consistency": get("Consistency"),
        "DS": get("DS"),
        "Fusion": get("Fusion/SameWindow") and get("Fusion/SameWindow") / EPOCH,
        "Total": get("Total/Epoch4") and get("Total/Epoch4") / EPOCH,
    }
    print(f"load average {context.get('load_avg')}")
    print("| per range (sample) | ours, CPU us | paper, us | paper / ours |")
    print("| --- | --- | --- | --- |")
    for key, paper in PAPER.items():
        ours = per_range[key]
        cell = "error" if ours is None else f"{ours:.3f}"
        ratio = "-" if ours is None else f"{paper / ours:.0f}x"
        print(f"| {key} | {cell} | {paper} | {ratio} |")
    parts = [per_range[k] for k in ("SVM", "Consistency", "DS", "Fusion")]
    if None not in parts:
        print(f"sum of the parts per range (fusion step / {EPOCH}): {sum(parts):.3f} us")
        print(f"sum of the parts with the whole fusion step charged to one range: {sum(parts[:3]) + get('Fusion/SameWindow'):.3f} us")
    if get("Total/Epoch4/AllAttached"):
        print(f"Total per range with every epoch attached: {get('Total/Epoch4/AllAttached') / EPOCH:.3f} us")
    print()
    print("| per epoch (4 ranges) | CPU us |")
    print("| --- | --- |")
    for name in ("Fusion/SameWindow", "Fusion/Stream", "Ceres", "TinySolver", "CvFusion/SameWindow", "CvCeres", "Total/Epoch4",
                 "Total/Epoch4/AllAttached"):
        v = get(name)
        print(f"| PerSample/{name} | {'error' if v is None else f'{v:.2f}'} |")
    print()
    svm, lib, fus, cer, tiny, tot = (get("SVM"), get("LibSVM"), get("Fusion/SameWindow"), get("Ceres"), get("TinySolver"),
                                     per_range["Total"])
    if tot is not None:
        print(f"target total <= 5 us per range: {tot:.2f} us, {PAPER['Total'] / tot:.0f}x the paper (target >= 500x): {'met' if tot <= 5 else 'NOT met'}")
    if fus and cer:
        print(f"target fusion (IMU graph) >= 20x faster than Ceres: {cer / fus:.1f}x: {'met' if cer / fus >= 20 else 'NOT met'}")
    if fus and tiny:
        print(f"target fusion (IMU graph) >= 5x faster than TinySolver: {tiny / fus:.1f}x: {'met' if tiny / fus >= 5 else 'NOT met'}")
    if fus:
        print(f"target IMU graph step <= 10 us per epoch: {fus:.2f} us: {'met' if fus <= 10 else 'NOT met'}")
    if svm and lib:
        print(f"target SVM >= 100x libsvm: {lib / svm:.1f}x: {'met' if lib / svm >= 100 else 'NOT met'}")
    if svm:
        print(f"target SVM <= 1 us per sample: {svm:.3f} us: {'met' if svm <= 1 else 'NOT met'}")
    if get("SVM/Exact") and svm:
        print(f"SVM, exact kernel sum: {get('SVM/Exact'):.2f} us ({get('SVM/Exact') / svm:.0f}x the evaluator's time)")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
