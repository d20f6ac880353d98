#!/usr/bin/env python3
"""Checks that a tactus-post report's pictures show what its numbers say.

    check_pictures.py <report folder> [--pressure-body NAME]

Read back with VTK's PNG reader: every picture listed in summary.json exists; each von Mises
picture has the model in it (coloured pixels over at least 5 % of the model area, left of the
colour bar and between the captions, outside the view keys' corner); the pressure map has its red (shaded) peak where its black
dot marks the peak node; with --pressure-body, the summary maps the pressure on that body.
"""
import json
import os
import sys

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy


def fail(msg):
    print("check_pictures: FAIL: " + msg)
    sys.exit(1)


def model_area(file):
    r = vtk.vtkPNGReader()
    r.SetFileName(file)
    r.Update()
    img = r.GetOutput()
    w, h, _ = img.GetDimensions()
    rgb = vtk_to_numpy(img.GetPointData().GetScalars()).reshape(h, w, -1)[:, :, :3].astype(int)
    # VTK's rows start at the bottom: the view keys (triad, "seen from", scale bar) hold the
    # lower-left corner, painted white here so their red x axis and black bar are not the model's.
    rgb[: int(0.28 * h), : int(0.4 * w)] = 255
    return rgb[60 : h - 60, : int(0.86 * w)]  # without the captions and the colour bar


report = sys.argv[1]
body = sys.argv[sys.argv.index("--pressure-body") + 1] if "--pressure-body" in sys.argv else None
summary = json.load(open(os.path.join(report, "summary.json")))
for pic in summary["pictures"]:
    if not os.path.isfile(os.path.join(report, pic)):
        fail(f"{pic} is listed but missing")
for pic in (p for p in summary["pictures"] if p.startswith("von_mises_")):
    a = model_area(os.path.join(report, pic))
    frac = float(((a.max(axis=2) - a.min(axis=2)) > 60).mean())
    print(f"  ok {pic}: model covers {100 * frac:.1f} % of the picture")
    if frac < 0.05:
        fail(f"{pic}: the model is missing or tiny ({100 * frac:.2f} % coloured)")
if body is not None:
    found = summary["contact"]["peak_pressure_at_outputs"].get("body")
    if found != body:
        fail(f"pressure mapped on {found!r}, expected {body!r}")
    print(f"  ok pressure mapped on {body}")
if "pressure.png" in summary["pictures"]:
    a = model_area(os.path.join(report, "pressure.png"))
    # Reds of the top of the scale, shaded by the lighting: red well above green and blue.
    red = np.argwhere(a[:, :, 0] - np.maximum(a[:, :, 1], a[:, :, 2]) > 50)
    if len(red) == 0:
        fail("pressure.png: no red (peak) pixels")
    # The black dot marks the peak node: a disc of black pixels right at the red peak.
    centre = red.mean(axis=0)
    ys, xs = np.mgrid[0 : a.shape[0], 0 : a.shape[1]]
    near = np.hypot(ys - centre[0], xs - centre[1]) < 0.05 * a.shape[1]
    dot = int(((a.max(axis=2) < 30) & near).sum())
    print(f"  ok pressure.png: {len(red)} red pixels, {dot} black dot pixels within {0.05 * a.shape[1]:.0f} px of them")
    if dot < 100:
        fail(f"pressure.png: the black dot is not at the red peak ({dot} dot pixels near it)")
print(f"check_pictures: all good ({len(summary['pictures'])} pictures)")
