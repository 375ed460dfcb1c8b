#!/usr/bin/env python3
"""The include direction of include/ctxfuse/ (docs/architecture.md, "Layers").

    scripts/check_layers.py [--root DIR]

Every header under DIR/include/ctxfuse/ (default: this repository) may include headers of its
own folder and of the folders of lower layers, never of a higher layer or of a folder on its
own layer; the pipelines' folders (pipelines/<name>/) never include one another, apart from
the exceptions listed below with their reason. SVM training (the headers that include
libsvm's svm.h) is included only by training headers (*/training.hpp), by studies/ and by the
training headers of classify/ themselves, so that inference never needs libsvm. Prints each
offending include as file:line: and exits 1 when there is one, 0 otherwise.
"""
import argparse
import pathlib
import re
import sys

# Lowest first. Folders on one line are peers: neither includes the other.
LAYERS = [
    ["core"],
    ["messages"],
    ["io", "models"],
    ["policies"],
    ["filters"],
    ["classify"],
    ["features"],
    ["pipelines"],
    ["sim"],
    ["eval"],
    ["studies"],
    ["instances"],
    ["testing"],
]

# Includes between pipelines that are still to be removed, each with its reason (none now: what
# two pipelines share lives in a lower layer). The check fails on any other one.
PIPELINE_EXCEPTIONS: dict = {}

# The headers that include libsvm, and who may include them: a pipeline's training header,
# the studies (they train on other recordings), each other, and a pipeline's umbrella header
# (pipelines/<name>.hpp, which gathers training too).
LIBSVM_HEADERS = {"classify/svm_train.hpp", "classify/svm_tune.hpp"}


def may_include_libsvm(rel):
    return (rel.name == "training.hpp" or rel.parts[0] == "studies" or str(rel) in LIBSVM_HEADERS
            or (rel.parts[0] == "pipelines" and len(rel.parts) == 2))


# ctxfuse.hpp, the umbrella header, sits above the engine it gathers.
TOP_LEVEL_ALLOWED = {"core", "messages", "models", "policies", "filters"}

INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]ctxfuse/([^>"]+)[>"]')


def rank_of(folder):
    for rank, peers in enumerate(LAYERS):
        if folder in peers:
            return rank
    return None


def check(root):
    base = root / "include" / "ctxfuse"
    if not base.is_dir():
        return [f"{base}: no such folder"]
    problems = []
    for path in sorted(base.rglob("*.hpp")):
        rel = path.relative_to(base)
        parts = rel.parts
        folder = parts[0] if len(parts) > 1 else None
        if folder is not None and rank_of(folder) is None:
            problems.append(f"include/ctxfuse/{rel}: folder '{folder}' has no layer (add it to LAYERS)")
            continue
        for number, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            target = pathlib.PurePosixPath(m.group(1)).parts
            where = f"include/ctxfuse/{rel}:{number}"
            if len(target) < 2:
                problems.append(f"{where}: includes the umbrella header ctxfuse/{m.group(1)}")
                continue
            to = target[0]
            if m.group(1) in LIBSVM_HEADERS and not may_include_libsvm(rel):
                problems.append(f"{where}: includes ctxfuse/{m.group(1)} (libsvm) outside a training header")
            if rank_of(to) is None:
                problems.append(f"{where}: includes ctxfuse/{m.group(1)}, a folder with no layer")
                continue
            if folder is None:
                if to not in TOP_LEVEL_ALLOWED:
                    problems.append(f"{where}: ctxfuse.hpp includes '{to}', outside {sorted(TOP_LEVEL_ALLOWED)}")
                continue
            if to == folder:
                if folder == "pipelines" and len(parts) > 2 and len(target) > 2 and parts[1] != target[1]:
                    pair = (parts[1], target[1])
                    if pair not in PIPELINE_EXCEPTIONS:
                        problems.append(f"{where}: pipelines/{parts[1]} includes pipelines/{target[1]} "
                                        f"(pipelines never include one another)")
                continue
            if rank_of(to) >= rank_of(folder):
                kind = "a peer" if rank_of(to) == rank_of(folder) else "a higher layer"
                problems.append(f"{where}: '{folder}' includes '{to}', {kind} (ctxfuse/{m.group(1)})")
    return problems


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=pathlib.Path, default=pathlib.Path(__file__).resolve().parent.parent)
    args = parser.parse_args()
    problems = check(args.root)
    for p in problems:
        print(p)
    if problems:
        print(f"check_layers: {len(problems)} include(s) against the layers")
        return 1
    headers = len(list((args.root / "include" / "ctxfuse").rglob("*.hpp")))
    print(f"check_layers: {headers} headers, every include points down")
    return 0


if __name__ == "__main__":
    sys.exit(main())
