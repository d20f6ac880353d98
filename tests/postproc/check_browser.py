#!/usr/bin/env python3
"""The interactive report in a real browser: headless Chromium (software WebGL) opens
report/index.html from the file system.

    check_browser.py <results folder> <report folder> [--timing]

Checks, each against the results folder read independently here (VTK's .vtu reader, run.json):
  1. the page loads every output state (the number in results.pvd), with no script error
     (its own error log, and any console line Chromium prints from the page);
  2. the peak contact pressure it reports equals the largest contact_pressure of the states,
     at the same node (node id = .vtu point + 1) and position;
  3. at each output the nodes it colours by pressure are exactly those pressed in the .vtu with
     contact_status stick or slip (pressure > 0), and run.json's contact.at_outputs has area
     there exactly when it does;
  4. screenshots at the first and the last output are not blank (over 5 % of the viewport
     neither background nor one colour), differ, and show rainbow (saturated) pixels only at an
     output with contact: grey elsewhere, so the pressure colour never appears without contact.
  5. the pressure table of the last output (pressure_<ms>ms.csv): its pressed nodes are the
     .vtu's, and pressure times tributary area, summed, equals the base's reaction (history.csv,
     reaction_base_z: the pad is held at rest under the punch) within 2 %.
With --timing it prints how long the page takes to load and the report's size (no checks).
With --grasp the results folder's run.json carries a grasp (joints.grasp): the page must draw its
grip table, one row per region of run.json, with no script error.
"""
import glob
import html
import json
import os
import re
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

CHROMIUM = "/usr/bin/chromium"
FLAGS = [
    "--headless",
    "--no-sandbox",  # as root
    "--use-angle=swiftshader",  # WebGL in software: no GPU on the test machines
    "--enable-unsafe-swiftshader",
    "--ignore-gpu-blocklist",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--enable-logging=stderr",
    "--v=0",
    "--window-size=1280,800",
    "--virtual-time-budget=60000",
]


def fail(msg):
    print("check_browser: FAIL: " + msg)
    sys.exit(1)


def chromium(url, extra):
    with tempfile.TemporaryDirectory() as profile:
        p = subprocess.run(
            [CHROMIUM, *FLAGS, "--user-data-dir=" + profile, *extra, url],
            capture_output=True,
            text=True,
            timeout=300,
        )
    console = [line for line in p.stderr.splitlines() if ":CONSOLE" in line]
    if console:
        fail("the page wrote to the console:\n" + "\n".join(console))
    return p.stdout


def page_status(url):
    dom = chromium(url, ["--dump-dom"])
    m = re.search(r'<pre id="tactus-status">(.*?)</pre>', dom, re.S)
    if not m:
        fail("no #tactus-status in the page")
    status = json.loads(html.unescape(m.group(1)))
    if status.get("errors"):
        fail("script errors: " + "; ".join(status["errors"]))
    if not status.get("ready"):
        fail("the page did not finish loading: " + json.dumps(status))
    return status


def screenshot(url, file, canvas):
    chromium(url, ["--screenshot=" + file])
    r = vtk.vtkPNGReader()
    r.SetFileName(file)
    r.Update()
    img = r.GetOutput()
    w, h, _ = img.GetDimensions()
    rgb = vtk_to_numpy(img.GetPointData().GetScalars()).reshape(h, w, -1)[::-1, :, :3].astype(int)
    x, y, cw, ch = (int(round(v)) for v in canvas)
    return rgb[y : y + ch, x : x + cw]


def states_of(results):
    root = ET.parse(os.path.join(results, "results.pvd")).getroot()
    return [(float(d.get("timestep")), os.path.join(results, d.get("file"))) for d in root.iter("DataSet")]


def read_vtu(file):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(file)
    r.Update()
    g = r.GetOutput()
    pd = g.GetPointData()
    points = vtk_to_numpy(g.GetPoints().GetData())
    n = g.GetNumberOfPoints()
    p = pd.GetArray("contact_pressure")
    s = pd.GetArray("contact_status")
    pressure = vtk_to_numpy(p) if p else np.zeros(n)
    status = vtk_to_numpy(s) if s else -np.ones(n)
    return points, pressure, status


def saturated(rgb):
    """Pixels of the rainbow: far from grey (the unpressed skin, shaded) and from white."""
    return (rgb.max(axis=2) - rgb.min(axis=2)) > 60


def not_blank(rgb, what):
    flat = rgb.reshape(-1, 3)
    colours, counts = np.unique(flat, axis=0, return_counts=True)
    background = np.all(flat == [255, 255, 255], axis=1).sum()
    mode = counts.max() if colours.size else 0
    other = len(flat) - max(background, mode)
    if other < 0.05 * len(flat):
        fail(f"{what}: only {100 * other / len(flat):.1f} % of the viewport is drawn (blank?)")
    return other / len(flat)


def check_pressure_csv(results, report, states):
    t, f = states[-1]
    table = os.path.join(report, f"pressure_{1e3 * t:.2f}ms.csv")
    if not os.path.isfile(table):
        fail(f"no pressure table {table}")
    rows = np.genfromtxt(table, delimiter=",", names=True, dtype=None, encoding="utf-8")
    _, pressure, _ = read_vtu(f)
    pressed = set(int(i) + 1 for i in np.nonzero(pressure > 0)[0])
    if set(int(i) for i in rows["node_id"]) != pressed:
        fail(f"{table}: its nodes are not the {len(pressed)} pressed in the .vtu")
    force = float(np.sum(rows["pressure_Pa"] * rows["area_m2"]))
    h = np.genfromtxt(os.path.join(results, "history.csv"), delimiter=",", names=True)
    row = int(np.argmin(np.abs(h["time"] - t)))
    reaction = float(h["reaction_base_z"][row])
    if abs(force - reaction) > 0.02 * abs(reaction):
        fail(f"{table}: sum of pressure x area {force:.6g} N, base reaction {reaction:.6g} N (over 2 % apart)")
    print(
        f"check_browser: {os.path.basename(table)}: {len(rows)} pressed nodes, sum p A = {force:.5g} N, "
        f"base reaction {reaction:.5g} N ({100 * abs(force - reaction) / abs(reaction):.2f} % apart)"
    )


def main():
    results, report = sys.argv[1], sys.argv[2]
    page = "file://" + os.path.abspath(os.path.join(report, "index.html"))
    if "--timing" in sys.argv:
        size = sum(os.path.getsize(f) for f in glob.glob(os.path.join(report, "**"), recursive=True) if os.path.isfile(f))
        start = time.time()
        status = page_status(page)
        print(
            f"check_browser: {size / 2**20:.1f} MB, {status['outputs']} outputs; the page loaded and drew in "
            f"{status['load_ms'] / 1e3:.2f} s by its own clock, {time.time() - start:.1f} s with Chromium's start "
            "(headless, software WebGL)"
        )
        return
    if "--grasp" in sys.argv:
        regions = json.load(open(os.path.join(results, "run.json")))["joints"]["grasp"]["regions"]["regions"]
        status = page_status(page)
        if status.get("grasp_regions") != len(regions):
            fail(f"the page's grip table has {status.get('grasp_regions')} rows, run.json {len(regions)} regions")
        print(f"check_browser: grip table with {len(regions)} regions, as run.json has")
        return
    states = states_of(results)
    run = json.load(open(os.path.join(results, "run.json")))
    # run.json's contact rows are the scheduled outputs' (the initial state, t = 0, has none): by time.
    at_outputs = {round(o["time"], 12): o for o in run.get("contact", {}).get("at_outputs", [])}
    last = len(states) - 1
    status = page_status(page + f"?state={last}&field=pressure")
    if status["outputs"] != len(states):
        fail(f"the page shows {status['outputs']} outputs, results.pvd lists {len(states)}")
    print(f"check_browser: {status['outputs']} outputs shown, as results.pvd lists")

    # 2. The peak pressure over the outputs, read here from the .vtu files.
    best = (0.0, -1, -1, None)
    for k, (t, f) in enumerate(states):
        points, pressure, _ = read_vtu(f)
        i = int(np.argmax(pressure))
        if pressure[i] > best[0]:
            best = (float(pressure[i]), k, i, points[i])
    peak = status["peaks"]["pressure"]
    if best[0] <= 0:
        fail("the test run has no contact")
    if abs(peak["value"] - best[0]) > 1e-6 * best[0] or peak["id"] != best[2] + 1 or peak["state"] != best[1]:
        fail(f"peak pressure: page {peak}, .vtu {best[0]} Pa at node {best[2] + 1}, output {best[1]}")
    # The page's position is the node's current one (reference + displacement, in float): within 1 um.
    gap = float(np.linalg.norm(np.array(peak["position"]) - best[3]))
    if gap > 1e-6:
        fail(f"peak pressure position {peak['position']} is {gap} m from node {best[2] + 1} at {list(best[3])}")
    print(
        f"check_browser: peak pressure {peak['value']:.6g} Pa at node {peak['id']}, output {peak['state']} "
        f"(.vtu: {best[0]:.6g} Pa, node {best[2] + 1}; position within {gap:.1e} m)"
    )

    # 3. and 4. Each output: the pressed nodes the page colours, the screenshot's colours.
    shots = {}
    with tempfile.TemporaryDirectory() as tmp:
        for k, (t, f) in enumerate(states):
            s = page_status(page + f"?state={k}&field=pressure")
            _, pressure, contact = read_vtu(f)
            pressed = int(((pressure > 0) & (contact >= 1)).sum())
            if int((pressure > 0).sum()) != pressed:
                fail(f"output {k}: nodes with pressure outside stick or slip status in the .vtu")
            if s["pressed_vertices"] != pressed:
                fail(f"output {k}: the page colours {s['pressed_vertices']} nodes by pressure, the .vtu presses {pressed}")
            row = at_outputs.get(round(t, 12))
            if row is None and t > 0:
                fail(f"output {k} (t = {t} s): no contact row in run.json")
            if row is not None and (row["area"] > 0) != (pressed > 0):
                fail(f"output {k}: run.json contact area {row['area']} but {pressed} pressed nodes")
            if k in (0, last):
                rgb = screenshot(page + f"?state={k}&field=pressure", os.path.join(tmp, f"{k}.png"), s["canvas"])
                drawn = not_blank(rgb, f"output {k}")
                coloured = int(saturated(rgb).sum())
                if (coloured > 0) != (pressed > 0):
                    fail(f"output {k}: {coloured} rainbow pixels with {pressed} pressed nodes")
                shots[k] = rgb
                print(
                    f"check_browser: output {k} (t = {1e3 * t:.2f} ms): {pressed} pressed nodes, page the same; "
                    f"{100 * drawn:.0f} % of the viewport drawn, {coloured} rainbow pixels"
                )
    differ = np.any(shots[0] != shots[last], axis=2).mean()
    if differ < 0.001:
        fail(f"the first and last outputs look the same ({100 * differ:.2f} % of pixels differ)")
    check_pressure_csv(results, report, states)
    print(f"check_browser: first and last outputs differ in {100 * differ:.1f} % of the pixels; all good")


main()
