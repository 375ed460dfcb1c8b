#!/usr/bin/env python3
"""What one source costs to compile: user + sys CPU seconds of its command in a build tree.

  scripts/compile_cost.py [--build build/release] [--against TREE] SOURCE...

SOURCE is the end of a source path in the build tree's compile_commands.json (for example
tests/pipelines/nlos_uwb_eval_test.cpp, or Unity/unity_uwb_cxx.cxx for a unity source of the
tool). The command is the build's own, less the precompiled header (its cost is paid once, and
a comparison should not depend on whether it was fresh) and the dependency file, writing its
object to a temporary folder. With --against TREE (another checkout of the repository, for
example a `git worktree` of an earlier commit), the same source of TREE is compiled at the same
time, one compilation per core, so that both see the same machine; a unity source of TREE is
the build tree's unity source with its paths moved to TREE. Prints one line per source:
`<source> <seconds>` or `<source> <seconds here> <seconds in TREE>`.
"""
import argparse
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def find_entry(entries, suffix):
    hits = [e for e in entries if e["file"].endswith(suffix)]
    if len(hits) != 1:
        sys.exit(f"compile_cost: {len(hits)} sources of the build end in {suffix!r}; give more of the path")
    return hits[0]


def command_of(entry, out):
    args = shlex.split(entry["command"])
    keep = []
    skip = 0
    for i, a in enumerate(args):
        if skip:
            skip -= 1
            continue
        if a == "-include" and i + 1 < len(args) and args[i + 1].endswith("cmake_pch.hxx"):
            skip = 1
        elif a in ("-Xclang",) and i + 3 < len(args) and args[i + 1] in ("-include-pch", "-include") and "cmake_pch" in args[i + 2] + args[i + 3]:
            skip = 3
        elif a in ("-MF", "-MT", "-o"):
            skip = 1
        elif a in ("-MD", "-Winvalid-pch"):
            continue
        else:
            keep.append(a)
    return keep + ["-o", out]


def moved(args, repo, tree, tmp):
    """The command for the same source in `tree`: paths under the repository moved there."""
    out = []
    for a in args:
        a = a.replace(str(repo) + "/", str(tree) + "/")
        if a.endswith(".cxx") and "/Unity/" in a and Path(a.replace(str(tree) + "/", str(repo) + "/")).exists():
            # A unity source lives in the build tree: its includes name the repository's files.
            text = Path(a.replace(str(tree) + "/", str(repo) + "/")).read_text().replace(str(repo) + "/", str(tree) + "/")
            unity = Path(tmp) / ("against_" + Path(a).name)
            unity.write_text(text)
            a = str(unity)
        out.append(a)
    return out


def start(args, cwd):
    # /usr/bin/time writes user and system seconds to a file of its own, apart from the
    # compiler's diagnostics.
    fd, timing = tempfile.mkstemp(suffix=".time")
    os.close(fd)
    proc = subprocess.Popen(["/usr/bin/time", "-f", "%U %S", "-o", timing] + args, cwd=cwd,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    return proc, timing


def finish(proc, timing, what):
    _, err = proc.communicate()
    if proc.returncode != 0:
        sys.exit(f"compile_cost: {what} did not compile:\n{err}")
    user, system = Path(timing).read_text().split()[-2:]
    os.unlink(timing)
    return float(user) + float(system)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", default=str(REPO / "build" / "release"), help="build tree with compile_commands.json")
    ap.add_argument("--against", help="another checkout: compile its same source side by side")
    ap.add_argument("sources", nargs="+")
    a = ap.parse_args()
    build = Path(a.build).resolve()
    entries = json.loads((build / "compile_commands.json").read_text())
    with tempfile.TemporaryDirectory() as tmp:
        for suffix in a.sources:
            e = find_entry(entries, suffix)
            here = command_of(e, str(Path(tmp) / "here.o"))
            proc, timing = start(here, e["directory"])
            other = None
            if a.against:
                there = moved(command_of(e, str(Path(tmp) / "there.o")), REPO, Path(a.against).resolve(), tmp)
                other = start(there, tmp)
            t = finish(proc, timing, e["file"])
            if other:
                u = finish(*other, f"{e['file']} in {a.against}")
                print(f"{suffix} {t:.1f} {u:.1f}", flush=True)
            else:
                print(f"{suffix} {t:.1f}", flush=True)


if __name__ == "__main__":
    main()
