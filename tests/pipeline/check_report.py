#!/usr/bin/env python3
"""Checks a tactus-post report against values read independently from the solver's files.

    check_report.py <solve folder> <report folder> [--expect-contact | --expect-no-contact]

Oracles: the peak von Mises per material and the peak contact pressure over the output states are
recomputed here from the .vtu files with VTK's own reader (not tactus' code), and so is the
pressure averaged over 25 mm^2 at each output (bench/pressure_sites.py, in numpy); the peak contact
force and largest area from history.csv / run.json; the energy balance error must stay within
2 % of the initial kinetic energy, and the run must have completed (no inverted element).
"""
import csv
import json
import os
import sys

import vtk
from vtk.util.numpy_support import vtk_to_numpy

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "bench"))
from pressure_sites import Field, state_files  # noqa: E402
from tactus_contracts import cell_field, history_column, point_field, run_key  # noqa: E402


def fail(msg):
    print("check_report: FAIL: " + msg)
    sys.exit(1)


def close(a, b, rel=1e-9, what=""):
    if abs(a - b) > rel * max(abs(a), abs(b), 1e-300):
        fail(f"{what}: report {a!r} vs independent {b!r}")
    print(f"  ok {what}: {a:.6g}")


solve, report = sys.argv[1], sys.argv[2]
expect = sys.argv[3] if len(sys.argv) > 3 else ""
summary = json.load(open(os.path.join(report, "summary.json")))
run = json.load(open(os.path.join(solve, "run.json")))
if run[run_key("status")] != "completed":
    fail("run status " + run["status"] + ": " + str(run.get("message")))

materials = run[run_key("materials")]
vm_peak = {m: 0.0 for m in materials}
p_peak = 0.0
states = state_files(solve)
for path in states.values():
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    vm = vtk_to_numpy(g.GetCellData().GetArray(cell_field("von_mises")))
    mat = vtk_to_numpy(g.GetCellData().GetArray(cell_field("material"))).astype(int)
    for k, m in enumerate(materials):
        if (mat == k).any():
            vm_peak[m] = max(vm_peak[m], float(vm[mat == k].max()))
    arr = g.GetPointData().GetArray(point_field("contact_pressure"))
    if arr is not None:
        p_peak = max(p_peak, float(vtk_to_numpy(arr).max()))

for m in materials:
    close(summary["peak_von_mises"][m]["value"], vm_peak[m], what=f"peak von Mises of {m}")

rows = list(csv.DictReader(open(os.path.join(solve, "history.csv"))))
k0 = float(rows[0][history_column("kinetic_energy")])
err = abs(run[run_key("energy")]["balance_error"]) / k0
print(f"  energy balance error {100 * err:.4f} % of the initial kinetic energy")
if err > 0.02:
    fail(f"energy balance error {err:.4f} of the initial kinetic energy (limit 0.02)")
close(summary["energy"]["initial_kinetic_J"], k0, what="initial kinetic energy")

contact = summary["contact"]
if expect == "--expect-no-contact":
    if contact["occurred"] or p_peak > 0:
        fail("contact reported where none occurred")
    text = open(os.path.join(report, "summary.md")).read()
    if "No contact occurred" not in text:
        fail("summary.md does not say that no contact occurred")
    print("  ok no contact, and the report says so")
elif expect == "--expect-contact":
    if not contact["occurred"]:
        fail("no contact reported")
    close(contact["peak_pressure_at_outputs"]["value"], p_peak, what="peak contact pressure at the outputs")
    force = max(float(r[history_column("contact_force")]) for r in rows)
    if contact["peak_force"]["value"] < force * (1 - 1e-9):
        fail(f"peak force {contact['peak_force']['value']} below the history's {force}")
    close(contact["peak_force"]["value"], run[run_key("contact")]["peak_force"]["value"], what="peak contact force (every step)")
    close(contact["largest_area"]["value"], run["contact"]["peak_area"]["value"], what="largest contact area")
    # The 25 mm^2 sensor average at each output: the largest over the pressed skin nodes, and where.
    for o in run["contact"]["at_outputs"]:
        field = Field(states[round(o["time"], 9)], run["contact"]["pressure_average_area"])
        best = field.sites(count=1)
        value = best[0][1] if best else 0.0
        close(o["averaged_peak_pressure"], value, rel=1e-6, what=f"25 mm^2 peak pressure at {1e3 * o['time']:g} ms")
        if best:
            at = field.state["x"][best[0][0]]
            if max(abs(a - b) for a, b in zip(o["averaged_at"], at)) > 1e-9:
                fail(f"25 mm^2 peak at {1e3 * o['time']:g} ms: run.json says {o['averaged_at']}, recomputed {list(at)}")
for pic in summary["pictures"]:
    path = os.path.join(report, pic)
    if not os.path.exists(path) or os.path.getsize(path) < 2000:
        fail("picture missing or empty: " + pic)
print(f"check_report: all good ({len(summary['pictures'])} pictures)")
