"""Renders one tactus result state (.vtu) to PNG: the deformed bodies coloured by von Mises
stress, with a scalar bar: a quick look at one state without a report (tactus-post draws the
report's pictures); run under xvfb-run:
    xvfb-run -a /usr/bin/python3 scripts/render_state.py out/pad_press/results/state_0003.vtu pad.png
"""
import sys

import vtk
from render_png import look_from, write_png


def main(vtu_path, png_path, field="von_mises"):
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(vtu_path)
    reader.Update()
    grid = reader.GetOutput()
    grid.GetCellData().SetActiveScalars(field)
    lo, hi = grid.GetCellData().GetArray(field).GetRange()

    surface = vtk.vtkDataSetSurfaceFilter()
    surface.SetInputData(grid)
    lut = vtk.vtkLookupTable()
    lut.SetHueRange(0.667, 0.0)
    lut.Build()
    mapper = vtk.vtkDataSetMapper()
    mapper.SetInputConnection(surface.GetOutputPort())
    mapper.SetScalarModeToUseCellData()
    mapper.SetScalarRange(lo, hi)
    mapper.SetLookupTable(lut)
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().EdgeVisibilityOn()
    actor.GetProperty().SetEdgeColor(0.2, 0.2, 0.2)
    actor.GetProperty().SetLineWidth(0.5)

    bar = vtk.vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetTitle("von Mises [Pa]")
    bar.SetNumberOfLabels(5)
    bar.SetLabelFormat("%.2e")

    renderer = vtk.vtkRenderer()
    renderer.SetBackground(1, 1, 1)
    renderer.AddActor(actor)
    renderer.AddActor2D(bar)
    for prop in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty()):
        prop.SetColor(0, 0, 0)
    look_from(renderer, (1, -1.4, 0.9), (0, 0, 0), 1.25)
    write_png(renderer, (900, 650), png_path)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit("usage: render_state.py STATE.vtu OUT.png [cell field]")
    main(*sys.argv[1:])
