#!/usr/bin/env python3
"""Lengths of the C++ functions of the project's own sources, by brace matching.

Usage: scripts/function_lengths.py [--over N] [PATH ...]   (default: every stage's src/ and main files)

A function is a definition that starts at the beginning of a line (a namespace-level function or
a member defined outside its class, as the project writes them) and whose header ends in "{"; its
length is the number of lines from that line to its matching "}", with braces inside strings,
character literals and comments ignored. Lambdas and functions defined inside a class body count
with the function or class around them. Tests and bench/ are left out unless given.
"""
import argparse
import os
import re
import sys

STAGES = ("core", "segment", "mesher", "solver", "postproc", "data_samples")
HEADER = re.compile(r"^(?!\s)(?!namespace\b|class\b|struct\b|enum\b|union\b|extern\b|#|//|}|template\s*<[^>]*>\s*$)[^;=]*\([^;]*$")


def strip(line, state):
    """The line without string/char literals and comments; `state` carries a /* */ across lines."""
    out, i = [], 0
    while i < len(line):
        if state["block"]:
            end = line.find("*/", i)
            if end < 0:
                return "".join(out)
            state["block"], i = False, end + 2
            continue
        c = line[i]
        if line.startswith("//", i):
            break
        if line.startswith("/*", i):
            state["block"], i = True, i + 2
            continue
        if c in "\"'":
            j = i + 1
            while j < len(line) and line[j] != c:
                j += 2 if line[j] == "\\" else 1
            i = j + 1
            continue
        out.append(c)
        i += 1
    return "".join(out)


def functions(path):
    with open(path, encoding="utf-8", errors="replace") as fh:
        lines = fh.read().split("\n")
    state = {"block": False}
    code = [strip(line, state) for line in lines]
    k = 0
    while k < len(code):
        if HEADER.match(code[k]) and not code[k].startswith((" ", "\t")):
            # The header may run over several lines until its "{" (or a ";": a declaration).
            j = k
            while j < len(code) and "{" not in code[j] and ";" not in code[j]:
                j += 1
            if j < len(code) and "{" in code[j] and ";" not in code[j].split("{")[0]:
                depth, end = 0, j
                for m in range(j, len(code)):
                    depth += code[m].count("{") - code[m].count("}")
                    if depth <= 0 and m >= j and "}" in code[m]:
                        end = m
                        break
                name = re.sub(r"\s+", " ", lines[k].split("(")[0]).strip()
                yield name, k + 1, end - k + 1
                k = end + 1
                continue
        k += 1


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--over", type=int, default=80, help="list the functions longer than this many lines")
    ap.add_argument("paths", nargs="*")
    a = ap.parse_args()
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    paths = a.paths or [os.path.join(root, s) for s in STAGES]
    files = []
    for p in paths:
        if os.path.isfile(p):
            files.append(p)
        for d, _, names in os.walk(p):
            files += [os.path.join(d, n) for n in sorted(names) if n.endswith((".cpp", ".hpp"))]
    found = []
    for f in files:
        for name, line, length in functions(f):
            found.append((length, os.path.relpath(f, root), line, name))
    long = sorted((x for x in found if x[0] > a.over), reverse=True)
    for length, f, line, name in long:
        print(f"{length:5d}  {f}:{line}  {name}")
    print(f"{len(found)} functions, {len(long)} over {a.over} lines, {sum(1 for x in found if x[0] > 100)} over 100")
    return 0


if __name__ == "__main__":
    sys.exit(main())
