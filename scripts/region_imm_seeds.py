#!/usr/bin/env python3
"""The region_imm tables of docs/results.md over several simulated drives:
    scripts/region_imm_seeds.py [--cli PATH] [--scenario default|paper] [--seeds 1-5] [--out DIR]
Runs `ctxfuse demo --seed N --scenario S --json DIR/S-N.json` for every seed and prints, as
markdown: overall / transition-region mean error of FKF, FKF with static fusion weights, plain
IMM, region IMM, region IMM on the true labels and region IMM + posterior pull; how many seeds the paper's ordering
(region IMM < IMM < FKF) holds on, overall and in the transition region; recognition accuracy
PSO-SVM / HMM / joint; and what routing could exclude (region_imm.routing.* of the JSON).
Defaults: build/release/tools/ctxfuse, scenario default, seeds 1-5, out build/region-imm-seeds."""
import argparse
import json
import os
import subprocess
import sys

METHODS = ("fkf", "fkf_static", "imm", "region_imm", "region_imm_true_labels", "region_imm_posterior")


def seed_list(text):
    seeds = []
    for part in text.split(","):
        if "-" in part:
            lo, hi = part.split("-", 1)
            seeds.extend(range(int(lo), int(hi) + 1))
        else:
            seeds.append(int(part))
    return seeds


def study_parser(doc, seeds, out_name):
    """The arguments the region_imm scripts share: --cli (the built tool), --seeds, and --out
    (a folder under build/ for the JSON documents)."""
    repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cli", default=os.path.join(repo, "build", "release", "tools", "ctxfuse"))
    ap.add_argument("--seeds", default=seeds)
    ap.add_argument("--out", default=os.path.join(repo, "build", out_name))
    return ap


def main():
    ap = study_parser(__doc__, "1-5", "region-imm-seeds")
    ap.add_argument("--scenario", default="default")
    a = ap.parse_args()
    try:
        seeds = seed_list(a.seeds)
    except ValueError:
        print(f"region_imm_seeds: bad --seeds '{a.seeds}' (e.g. 1-5 or 1,3,7)", file=sys.stderr)
        return 2
    os.makedirs(a.out, exist_ok=True)
    docs = {}
    for seed in seeds:
        path = os.path.join(a.out, f"{a.scenario}-{seed}.json")
        cmd = [a.cli, "demo", "--seed", str(seed), "--scenario", a.scenario, "--json", path]
        run = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if run.returncode != 0:
            print(f"region_imm_seeds: {' '.join(cmd)} failed ({run.returncode}): {run.stderr.strip()}", file=sys.stderr)
            return 1
        with open(path) as f:
            docs[seed] = json.load(f)["region_imm"]

    print(f"Scenario `{a.scenario}`. Overall / transition-region mean error (m):\n")
    print("| seed | FKF | FKF static | IMM | region IMM | region IMM, true labels | region IMM + pull |")
    print("|---|---|---|---|---|---|---|")
    holds = {"overall": 0, "transition": 0}
    for seed, d in docs.items():
        e = d["mean_error_m"]
        cells = [f"{e[m]['overall']:.3f} / {e[m]['transition']:.2f}" for m in METHODS]
        print(f"| {seed} | " + " | ".join(cells) + " |")
        for region in holds:
            if e["region_imm"][region] < e["imm"][region] < e["fkf"][region]:
                holds[region] += 1
    n = len(docs)
    print(f"\nregion IMM < IMM < FKF holds overall on {holds['overall']} of {n} seeds, "
          f"in the transition region on {holds['transition']} of {n}.\n")
    print("Recognition accuracy PSO-SVM / HMM / joint (%):\n")
    print("| seed | PSO-SVM | HMM | joint |")
    print("|---|---|---|---|")
    for seed, d in docs.items():
        r = d["recognition_accuracy"]
        print(f"| {seed} | {100 * r['svm']:.2f} | {100 * r['hmm']:.2f} | {100 * r['joint']:.2f} |")
    print("\nWhat routing could exclude (JSON region_imm.routing):\n")
    for seed, d in docs.items():
        print(f"- seed {seed}: " + ", ".join(f"{k} {v:g}" for k, v in sorted(d.get("routing", {}).items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
