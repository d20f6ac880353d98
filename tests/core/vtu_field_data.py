"""Prints what VTK's own reader finds in a .vtu's field data and component names, one fact a line
(the test MeshVtu.TimeUnitsAndComponentNamesAsParaViewReadsThem compares them):
    TimeValue <t>
    units <text>
    component <array> <index> <name>
"""
import sys

import vtk

reader = vtk.vtkXMLUnstructuredGridReader()
reader.SetFileName(sys.argv[1])
reader.Update()
grid = reader.GetOutput()
fd = grid.GetFieldData()
time = fd.GetArray("TimeValue")
if time is not None:
    print(f"TimeValue {time.GetValue(0)!r}")
units = fd.GetAbstractArray("units")
if units is not None:
    print(f"units {units.GetValue(0)}")
for data in (grid.GetPointData(), grid.GetCellData()):
    for i in range(data.GetNumberOfArrays()):
        a = data.GetArray(i)
        for c in range(a.GetNumberOfComponents()):
            if a.GetComponentName(c):
                print(f"component {a.GetName()} {c} {a.GetComponentName(c)}")
