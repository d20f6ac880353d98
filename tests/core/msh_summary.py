"""Independent reader for tests: prints counts and physical groups of a .msh via meshio."""
import sys

import meshio

m = meshio.read(sys.argv[1])
print("points", len(m.points))
counts = {}
for block in m.cells:
    counts[block.type] = counts.get(block.type, 0) + len(block.data)
for k, v in counts.items():
    print(k, v)
for name, (tag, dim) in m.field_data.items():
    print("group:" + name, dim)
    # count cells of this physical tag
    n = 0
    for block, phys in zip(m.cells, m.cell_data.get("gmsh:physical", [])):
        n += int((phys == tag).sum()) if block.type in ("tetra", "triangle") and ((dim == 3) == (block.type == "tetra")) else 0
    print("cells_in:" + name, n)
