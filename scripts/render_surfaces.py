"""Renders the segment stage's surfaces (skin translucent, bones opaque) to PNG; run under xvfb-run:
    xvfb-run -a /usr/bin/python3 scripts/render_surfaces.py out/segment/surfaces hand.png
"""
import glob
import os
import sys

import vtk
from render_png import look_from, write_png


def main(folder, png_path):
    renderer = vtk.vtkRenderer()
    renderer.SetBackground(1, 1, 1)
    for path in sorted(glob.glob(os.path.join(folder, "*.stl"))):
        reader = vtk.vtkSTLReader()
        reader.SetFileName(path)
        mapper = vtk.vtkPolyDataMapper()
        mapper.SetInputConnection(reader.GetOutputPort())
        actor = vtk.vtkActor()
        actor.SetMapper(mapper)
        if os.path.basename(path).startswith("skin"):
            actor.GetProperty().SetColor(0.93, 0.72, 0.62)
            actor.GetProperty().SetOpacity(0.25)
        else:
            actor.GetProperty().SetColor(0.95, 0.93, 0.85)
        renderer.AddActor(actor)
    look_from(renderer, (0.15, -0.5, 0.35), (0, 0, 0.12), 1.3)
    write_png(renderer, (700, 900), png_path)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: render_surfaces.py SURFACES_FOLDER OUT.png")
    main(*sys.argv[1:])
