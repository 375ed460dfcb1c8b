#!/usr/bin/env python3
"""When does routing by region pay? FKF, plain IMM and region IMM against indoor GNSS fixes:
    scripts/region_imm_indoor_fixes.py [--cli PATH] [--scenarios default,paper] [--seeds 1-10]
                                       [--errors 2,5,10] [--ratios 1,0.5,0.1] [--out DIR] [--reuse]
Neither simulated scenario has a GNSS fix under the garage roof, so region-aware routing has
nothing to leave out there. This sweep gives the receiver indoor fixes
(`--indoor-fix-error M`: Gauss-Markov error of M metres std per axis; `--indoor-fix-reported-ratio
R`: it reports R * M as its sigma) and runs `ctxfuse region-study` for every scenario, error
and ratio, plus the drive without indoor fixes. It prints, as markdown, the mean over the seeds
of the overall and indoor mean error of FKF, IMM and region IMM, and on how many seeds the
paper's ordering (region IMM < IMM < FKF) holds overall and in the transition region, and on
how many region IMM has the lowest overall error of the three, and how often the UWB integrity
check re-anchored each of the three (summed over the seeds). --reuse reads a grid point's
JSON from DIR when it is there instead of running the study again.
Filters take a fix with R = max(reported sigma, 0.5 m)^2 (region_imm::Settings), so ratios
below 0.5 / M all act as 0.5 m.
Defaults: build/release/tools/ctxfuse, scenarios default and paper, seeds 1-10, errors 2, 5,
10 m, ratios 1, 0.5, 0.1, out build/region-imm-indoor-fixes."""
import json
import os
import subprocess
import sys

from region_imm_seeds import study_parser

METHODS = ("fkf", "imm", "region_imm")


def numbers(text, kind):
    return [kind(v) for v in text.split(",") if v]


def run_study(cli, scenario, seeds, error, ratio, path, reuse):
    if reuse and os.path.exists(path):
        with open(path) as f:
            return json.load(f)
    cmd = [cli, "region-study", "--scenario", scenario, "--seeds", seeds, "--json", path]
    if error is not None:
        cmd += ["--indoor-fix-error", str(error), "--indoor-fix-reported-ratio", str(ratio)]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    with open(path) as f:
        return json.load(f)


def row(scenario, error, ratio, doc):
    per_seed = doc["per_seed"]
    n = len(per_seed)

    def mean(method, region):
        return sum(s["mean_error_m"][method][region] for s in per_seed) / n

    summary = doc["summary"]
    fixes = "none" if error is None else f"{error:g} m, reported x{ratio:g}"
    cells = [scenario, fixes]
    cells += [" / ".join(f"{mean(m, 'overall'):.3f}" for m in METHODS)]
    cells += [" / ".join(f"{mean(m, 'indoor'):.3f}" for m in METHODS)]
    best = sum(1 for s in per_seed
               if s["mean_error_m"]["region_imm"]["overall"] < min(s["mean_error_m"][m]["overall"] for m in ("fkf", "imm")))
    cells += [f"{summary['overall_holds_count']}/{n}", f"{summary['transition_holds_count']}/{n}", f"{best}/{n}"]
    cells += [" / ".join(str(sum(s["integrity_faults"][m] for s in per_seed)) for m in METHODS)]
    return "| " + " | ".join(cells) + " |"


def main():
    ap = study_parser(__doc__, "1-10", "region-imm-indoor-fixes")
    ap.add_argument("--scenarios", default="default,paper")
    ap.add_argument("--errors", default="2,5,10")
    ap.add_argument("--ratios", default="1,0.5,0.1")
    ap.add_argument("--reuse", action="store_true")
    a = ap.parse_args()
    try:
        errors = numbers(a.errors, float)
        ratios = numbers(a.ratios, float)
    except ValueError as e:
        print(f"region_imm_indoor_fixes.py: {e}", file=sys.stderr)
        return 2
    if not os.access(a.cli, os.X_OK):
        print(f"region_imm_indoor_fixes.py: no ctxfuse at {a.cli} (build it, or pass --cli)", file=sys.stderr)
        return 2
    os.makedirs(a.out, exist_ok=True)
    print(f"Seeds {a.seeds}; mean over the seeds of the mean horizontal error (m), FKF / IMM / region IMM; "
          "ordering = region IMM < IMM < FKF")
    print()
    print("| scenario | indoor fixes | overall | indoor | ordering overall | ordering transition | region IMM best overall "
          "| UWB integrity re-anchorings |")
    print("|---|---|---|---|---|---|---|---|")
    for scenario in a.scenarios.split(","):
        grid = [(None, None)] + [(e, r) for e in errors for r in ratios]
        for error, ratio in grid:
            tag = "none" if error is None else f"{error:g}_{ratio:g}"
            path = os.path.join(a.out, f"{scenario}-{tag}.json")
            try:
                doc = run_study(a.cli, scenario, a.seeds, error, ratio, path, a.reuse)
            except subprocess.CalledProcessError as e:
                print(f"region_imm_indoor_fixes.py: {' '.join(e.cmd)} exited with {e.returncode}", file=sys.stderr)
                return 1
            print(row(scenario, error, ratio, doc), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
