#!/usr/bin/env bash
# The meshes of the regression set into DIR: bar.msh, block.msh, sphere.msh (from an icosphere STL
# made here), cube.msh. The hand-block meshes come from the demo pipeline's work folder.
#   make_meshes.sh BUILD_DIR DIR
set -euo pipefail
B=$1
D=$2
mkdir -p "$D"
"$B/data_samples/tactus-sample-mesh" --size 0.1 0.01 0.01 --cells 40 1 1 -o "$D/bar.msh" -q
"$B/data_samples/tactus-sample-mesh" --size 0.02 0.02 0.01 --cells 4 4 2 -o "$D/block.msh" -q
"$B/data_samples/tactus-sample-mesh" --size 0.1 0.1 0.1 --cells 20 20 20 -o "$D/cube.msh" -q
/usr/bin/python3 - "$D/sphere.stl" <<'PY'
# An icosphere of radius 10 mm (4 subdivisions), lowest point 0.1 um above z = 0, in metres.
import math, struct, sys
t = (1 + 5 ** 0.5) / 2
v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
     (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8),
     (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
for _ in range(4):
    mid, nf = {}, []
    def m(a, b):
        k = (min(a, b), max(a, b))
        if k not in mid:
            p = [(v[a][i] + v[b][i]) / 2 for i in range(3)]
            n = math.sqrt(sum(x * x for x in p))
            v.append(tuple(x / n for x in p))
            mid[k] = len(v) - 1
        return mid[k]
    for a, b, c in f:
        ab, bc, ca = m(a, b), m(b, c), m(c, a)
        nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
    f = nf
R, z0 = 0.01, 0.01 + 1e-7
with open(sys.argv[1], "wb") as out:
    out.write(b"icosphere".ljust(80, b" ") + struct.pack("<I", len(f)))
    for tri in f:
        out.write(struct.pack("<3f", 0, 0, 0))
        for i in tri:
            x, y, z = v[i]
            out.write(struct.pack("<3f", R * x, R * y, R * z + z0))
        out.write(b"\0\0")
PY
"$B/mesher/tactus-mesh" stl "$D/sphere.stl" --element-size 0.0015 -o "$D/sphere.msh" -q
