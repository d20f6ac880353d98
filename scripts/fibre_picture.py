#!/usr/bin/env python3
"""Picture of a rule-based fibre field (tactus-mesh fibres): the reference direction of the
soft-tissue tets as short lines at their centroids, over a translucent skin, coloured by how much
each direction deviates from the hand's long axis.

  scripts/fibre_picture.py FIBRES.vtu OUT.png [--every N] [--axis z]

Needs Python with VTK (Debian: python3-vtk9); renders off screen.
"""
import argparse
import sys

import numpy as np
import vtk
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("fibres")
    ap.add_argument("png")
    ap.add_argument("--every", type=int, default=6, help="draw one tet in N")
    ap.add_argument("--axis", default="z", help="the hand's long axis (drawn upwards)")
    ap.add_argument("--view", default="y", help="the axis the camera looks along (the palm's normal)")
    ap.add_argument("--group", type=int, default=1, help="the physical volume tag of the soft tissue (tactus-mesh: 1)")
    a = ap.parse_args()
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(a.fibres)
    r.Update()
    g = r.GetOutput()
    cd = g.GetCellData()
    if cd.GetArray("fibre_direction") is None:
        sys.exit(f"{a.fibres}: expected cell data fibre_direction (a tactus-mesh fibres output)")
    direction = vtk_to_numpy(cd.GetArray("fibre_direction"))
    normal = vtk_to_numpy(cd.GetArray("skin_normal"))
    cc = vtk.vtkCellCenters()
    cc.SetInputData(g)
    cc.Update()
    centres = vtk_to_numpy(cc.GetOutput().GetPoints().GetData())
    pick = np.arange(0, len(centres), a.every)
    group = vtk_to_numpy(cd.GetArray("group")) if cd.GetArray("group") is not None else np.full(len(centres), a.group)
    pick = pick[(np.linalg.norm(normal[pick], axis=1) > 0) & (group[pick] == a.group)]  # soft tissue with a skin normal
    extent = np.ptp(centres, axis=0).max()
    half = 0.012 * extent
    pts = vtk.vtkPoints()
    lines = vtk.vtkCellArray()
    colour = []
    axis = np.eye(3)["xyz".index(a.axis)]
    for k, e in enumerate(pick):
        p0, p1 = centres[e] - half * direction[e], centres[e] + half * direction[e]
        pts.InsertNextPoint(*p0)
        pts.InsertNextPoint(*p1)
        lines.InsertNextCell(2)
        lines.InsertCellPoint(2 * k)
        lines.InsertCellPoint(2 * k + 1)
        colour.append(np.degrees(np.arccos(min(1.0, abs(direction[e] @ axis)))))
    poly = vtk.vtkPolyData()
    poly.SetPoints(pts)
    poly.SetLines(lines)
    poly.GetCellData().SetScalars(numpy_to_vtk(np.array(colour)))
    lut = vtk.vtkLookupTable()
    lut.SetHueRange(0.66, 0.0)
    lut.SetTableRange(0, 90)
    lut.Build()
    m = vtk.vtkPolyDataMapper()
    m.SetInputData(poly)
    m.SetLookupTable(lut)
    m.SetScalarRange(0, 90)
    m.SetScalarModeToUseCellData()
    lines_actor = vtk.vtkActor()
    lines_actor.SetMapper(m)
    lines_actor.GetProperty().SetLineWidth(2)
    skin = vtk.vtkDataSetSurfaceFilter()
    skin.SetInputData(g)
    sm = vtk.vtkPolyDataMapper()
    sm.SetInputConnection(skin.GetOutputPort())
    sm.ScalarVisibilityOff()
    skin_actor = vtk.vtkActor()
    skin_actor.SetMapper(sm)
    skin_actor.GetProperty().SetOpacity(0.12)
    skin_actor.GetProperty().SetColor(0.8, 0.7, 0.6)
    bar = vtk.vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetTitle(f"angle to {a.axis} (deg)")
    bar.SetNumberOfLabels(4)
    bar.SetPosition(0.86, 0.1)
    bar.SetWidth(0.1)
    ren = vtk.vtkRenderer()
    ren.SetBackground(1, 1, 1)
    ren.AddActor(skin_actor)
    ren.AddActor(lines_actor)
    ren.AddActor2D(bar)
    bar.GetTitleTextProperty().SetColor(0, 0, 0)
    bar.GetLabelTextProperty().SetColor(0, 0, 0)
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.AddRenderer(ren)
    win.SetSize(1100, 1100)
    cam = ren.GetActiveCamera()
    view = np.eye(3)["xyz".index(a.view)]
    cam.SetFocalPoint(0, 0, 0)
    cam.SetPosition(*(-view))
    cam.SetViewUp(*axis)
    ren.ResetCamera()
    cam.Zoom(1.1)
    win.Render()
    w2i = vtk.vtkWindowToImageFilter()
    w2i.SetInput(win)
    w2i.Update()
    out = vtk.vtkPNGWriter()
    out.SetFileName(a.png)
    out.SetInputConnection(w2i.GetOutputPort())
    out.Write()
    print(f"wrote {a.png}: {len(pick)} tets drawn")


if __name__ == "__main__":
    main()
