#!/usr/bin/env python3
"""Compares two regression-set folders (run.sh) bit for bit: every array of every state .vtu,
history.csv, and run.json's figures (not its timings). Prints one line per case.
    compare.py A B [--allow NAME ...]
An array present on one side only passes when all its values are 0 (a field that became optional).
States are paired by their time in results.pvd (so a build that writes the initial t = 0 state
compares with one that did not, the states' numbers shifted by one); a state at a time only one
side has is reported, and passes with --allow initial_state when that time is 0.
--allow names a deliberate change of a file contract that is reported but not failed: an array
("cell:group"), a run.json key ("contact.pairs") or a prefix of history columns added on one side
("history:reaction_").
Bit-identity assumes builds with -ffp-contract=off (cmake -DTACTUS_EXACT_FP=ON): GCC's default
contraction into FMA depends on inlining, so an unchanged formula may round differently after a
refactor; with contraction off the arithmetic is exactly what the source says."""
import json
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np
from vtk.util.numpy_support import vtk_to_numpy
import vtk


def arrays(path):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    out = {"points": vtk_to_numpy(g.GetPoints().GetData())}
    for kind, data in (("point", g.GetPointData()), ("cell", g.GetCellData())):
        for i in range(data.GetNumberOfArrays()):
            out[kind + ":" + data.GetArrayName(i)] = vtk_to_numpy(data.GetArray(i))
    return out


ALLOW = set()


def figures(path):
    j = json.load(open(path))
    for k in ("wall_time_s", "timing_s", "scenario", "tactus_version"):
        j.pop(k, None)
    j.get("time_step", {}).pop("limit", None)
    for key in ALLOW:
        parts = key.split(".")
        node = j
        for p in parts[:-1]:
            node = node.get(p, {}) if isinstance(node, dict) else {}
        if isinstance(node, dict):
            node.pop(parts[-1], None)
    return j


def compare_history(pa, pb):
    """Every column both files have, as text (bit for bit); a column on one side only must be
    allowed by prefix (--allow history:reaction_ admits the reaction columns a change added)."""

    def columns(path):
        lines = open(path).read().splitlines()
        names = lines[0].split(",")
        rows = [line.split(",") for line in lines[1:]]
        return {n: [r[k] for r in rows] for k, n in enumerate(names)}

    A, B = columns(pa), columns(pb)
    out = []
    for name in sorted(set(A) | set(B)):
        if name in A and name in B:
            if A[name] != B[name]:
                out.append(f"history.csv: {name} differs")
        elif not any(x.startswith("history:") and name.startswith(x[len("history:") :]) for x in ALLOW):
            out.append(f"history.csv: {name} only in one")
    return out


def states_by_time(folder):
    """{time: path} of the states results.pvd lists (empty without one)."""
    pvd = os.path.join(folder, "results.pvd")
    if not os.path.exists(pvd):
        return {}
    sets = ET.parse(pvd).getroot().iter("DataSet")
    return {float(d.get("timestep")): os.path.join(folder, d.get("file")) for d in sets}


def pair(a, b, pa):
    """The file of folder b that corresponds to pa of folder a: a state by its time (None when b has
    no state at that time), any other file by name."""
    ta, tb = states_by_time(a), states_by_time(b)
    for t, f in ta.items():
        if os.path.exists(f) and os.path.samefile(f, pa):
            return tb.get(t)  # None: a state only this side has
    return os.path.join(b, os.path.relpath(pa, a))


def compare(a, b):
    diffs = []
    ta, tb = states_by_time(a), states_by_time(b)
    for t in sorted(set(ta) ^ set(tb)):
        if not (t == 0 and "initial_state" in ALLOW):
            diffs.append(f"a state at t = {t} s only in {'the first' if t in ta else 'the second'}")
    for root, _, files in os.walk(a):
        for f in sorted(files):
            pa = os.path.join(root, f)
            pb = pair(a, b, pa)
            if f.endswith(".vtu") and (pb is None or not os.path.exists(pb)):
                continue  # a state only one side has: said above
            if f.endswith(".vtu"):
                A, B = arrays(pa), arrays(pb)
                for k in sorted(set(A) | set(B)):
                    if k in ALLOW:
                        continue
                    if k not in A or k not in B:
                        only = A.get(k, B.get(k))
                        if np.any(only != 0):
                            diffs.append(f"{f}: {k} only in one")
                    elif A[k].shape != B[k].shape or not np.array_equal(A[k], B[k], equal_nan=True):
                        d = np.nanmax(np.abs(A[k].astype(float) - B[k].astype(float))) if A[k].shape == B[k].shape else "shape"
                        diffs.append(f"{f}: {k} differs (max {d})")
            elif f == "history.csv":
                diffs += compare_history(pa, pb)
            elif f == "run.json":
                if figures(pa) != figures(pb):
                    diffs.append("run.json figures differ")
    return diffs


def main():
    a, b = sys.argv[1], sys.argv[2]
    rest = sys.argv[3:]
    while rest:
        if rest[0] == "--allow" and len(rest) > 1:
            ALLOW.add(rest[1])
            rest = rest[2:]
        else:
            sys.exit(f"compare.py: unknown argument {rest[0]}")
    bad = 0
    for case in sorted(os.listdir(a)):
        if not os.path.isdir(os.path.join(a, case)):
            continue
        d = compare(os.path.join(a, case), os.path.join(b, case))
        print(f"{case:18s} {'bit-identical' if not d else 'DIFFERENT: ' + '; '.join(d[:4])}")
        bad += bool(d)
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
