#!/usr/bin/env python3
"""Writes a closed cylinder (a tool handle) as a binary STL, in millimetres.

    make_cylinder_stl.py OUT.stl [--radius 15] [--length 120] [--segments 48] [--axis z]
                                 [--centre X Y Z]

The side is split into `segments` facets around and closed by two fan caps; the facets are
oriented outward. Uses only the Python standard library."""
import argparse
import math
import struct


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("--radius", type=float, default=15.0, help="mm")
    ap.add_argument("--length", type=float, default=120.0, help="mm")
    ap.add_argument("--segments", type=int, default=48)
    ap.add_argument("--axis", choices="xyz", default="z")
    ap.add_argument("--centre", type=float, nargs=3, default=[0.0, 0.0, 0.0], help="mm")
    a = ap.parse_args()
    if not (a.radius > 0 and a.length > 0 and a.segments >= 3):
        ap.error("radius and length must be > 0 and segments >= 3")
    n, r, h = a.segments, a.radius, a.length / 2
    ring = [(r * math.cos(2 * math.pi * k / n), r * math.sin(2 * math.pi * k / n)) for k in range(n)]
    tris = []
    for k in range(n):
        (x0, y0), (x1, y1) = ring[k], ring[(k + 1) % n]
        tris += [((x0, y0, -h), (x1, y1, -h), (x1, y1, h)), ((x0, y0, -h), (x1, y1, h), (x0, y0, h))]  # side, outward
        tris += [((0, 0, h), (x0, y0, h), (x1, y1, h)), ((0, 0, -h), (x1, y1, -h), (x0, y0, -h))]  # caps
    # local (u, v, along) -> world indices, a cyclic permutation (keeps the facets outward)
    order = {"x": (1, 2, 0), "y": (2, 0, 1), "z": (0, 1, 2)}[a.axis]

    def place(p):
        q = [0.0, 0.0, 0.0]
        for local, world in enumerate(order):
            q[world] = p[local]
        return [q[i] + a.centre[i] for i in range(3)]

    with open(a.out, "wb") as fh:
        fh.write(b"tactus cylinder handle (mm)".ljust(80, b" ") + struct.pack("<I", len(tris)))
        for t in tris:
            fh.write(struct.pack("<3f", 0, 0, 0))
            for p in t:
                fh.write(struct.pack("<3f", *place(p)))
            fh.write(b"\0\0")


if __name__ == "__main__":
    main()
