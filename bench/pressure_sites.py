"""Contact pressure averaged over a sensor-sized disc at given sites, from a tactus-solve state .vtu.

The same average as the solver's `averaged_peak_pressure` (run.json contact.at_outputs): the nodal
`contact_pressure` interpolated linearly on the skin triangles, each cut into 64 sub-triangles whose
centroids carry their area and pressure, averaged over the samples within the disc's radius of a
centre (force over sampled area). Computed here independently of the solver, from the state file,
so that two meshes can be compared at the same material points rather than each at its own maximum:
the largest average is a maximum over sites, and when several sites are nearly tied each mesh may
report a different one.
"""
import os
import xml.etree.ElementTree as ET

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

CUTS = 8


def state_files(solve):
    """A solve folder's output states from its results.pvd: {time (s, rounded to 1e-9): .vtu path}, in time order."""
    return {
        round(float(ds.get("timestep")), 9): os.path.join(solve, ds.get("file"))
        for ds in ET.parse(os.path.join(solve, "results.pvd")).getroot().iter("DataSet")
    }


def read_state(path):
    """Current and reference node positions, nodal contact pressure, contact gap, tets and tet bodies."""
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutput()
    points = vtk_to_numpy(grid.GetPoints().GetData()).astype(float)
    pd, cd = grid.GetPointData(), grid.GetCellData()
    displacement = vtk_to_numpy(pd.GetArray("displacement")).astype(float)
    cells = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 4)
    return {
        "x": points,
        "X": points - displacement,
        "p": vtk_to_numpy(pd.GetArray("contact_pressure")).astype(float),
        "gap": vtk_to_numpy(pd.GetArray("contact_gap")).astype(float),
        "tets": cells,
        "body": vtk_to_numpy(cd.GetArray("body")),
    }


def skin_triangles(state):
    """The boundary faces of the body whose nodes carry contact rows (a finite gap): the hand's skin."""
    slave = np.nonzero(~np.isnan(state["gap"]))[0]
    tets = state["tets"]
    owner = np.isin(tets, slave[:1]).any(axis=1)
    tets = tets[state["body"] == state["body"][np.argmax(owner)]]
    faces = np.sort(np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 2, 3]], tets[:, [0, 1, 3]], tets[:, [0, 1, 2]]]), axis=1)
    unique, count = np.unique(faces, axis=0, return_counts=True)
    return unique[count == 1]


def samples(state, triangles):
    """Sub-triangle centroids, their areas and their area-weighted pressures."""
    x, p = state["x"], state["p"]
    bary = []
    for i in range(CUTS):
        for j in range(CUTS - i):
            for up in (0, 1) if i + j + 1 < CUTS else (0,):
                l1, l2 = (i + (2.0 if up else 1.0) / 3.0) / CUTS, (j + (2.0 if up else 1.0) / 3.0) / CUTS
                bary.append((1 - l1 - l2, l1, l2))
    bary = np.array(bary)  # (64, 3)
    a, b, c = x[triangles[:, 0]], x[triangles[:, 1]], x[triangles[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1) / CUTS**2
    points = bary[None, :, 0, None] * a[:, None] + bary[None, :, 1, None] * b[:, None] + bary[None, :, 2, None] * c[:, None]
    pressure = bary @ p[triangles].T  # (64, n)
    return points.reshape(-1, 3), np.repeat(area, len(bary)), (pressure.T * area[:, None]).reshape(-1)


class Field:
    """The disc average of one state's contact pressure about any centre."""

    def __init__(self, path, sensor_area=25e-6):
        self.state = read_state(path)
        self.radius = np.sqrt(sensor_area / np.pi)
        self.triangles = skin_triangles(self.state)
        self.points, self.area, self.force = samples(self.state, self.triangles)
        self.skin_nodes = np.unique(self.triangles)
        # Samples binned in cubes of the disc's radius: a disc reaches the 27 cubes about its centre.
        cell = np.floor(self.points / self.radius).astype(np.int64)
        order = np.lexsort(cell.T[::-1])
        self.points, self.area, self.force, cell = self.points[order], self.area[order], self.force[order], cell[order]
        keys, starts = np.unique(cell, axis=0, return_index=True)
        ends = np.append(starts[1:], len(cell))
        self.bins = {tuple(k): (a, b) for k, a, b in zip(keys.tolist(), starts, ends)}

    def average(self, centre):
        c = np.floor(np.asarray(centre) / self.radius).astype(np.int64)
        spans = [self.bins.get((c[0] + i, c[1] + j, c[2] + k)) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)]
        index = np.concatenate([np.arange(a, b) for a, b in (s for s in spans if s)] or [np.zeros(0, dtype=np.int64)])
        inside = index[((self.points[index] - centre) ** 2).sum(axis=1) <= self.radius**2]
        total = self.area[inside].sum()
        return self.force[inside].sum() / total if total > 0 else 0.0

    def sites(self, count=3, apart=10e-3):
        """The pressed nodes with the largest averages, at least `apart` from each other: (node, average)."""
        pressed = self.skin_nodes[self.state["p"][self.skin_nodes] > 0]
        if len(pressed) == 0:
            return []
        values = np.array([self.average(c) for c in self.state["x"][pressed]])
        chosen = []
        for i in np.argsort(-values):
            if all(np.linalg.norm(self.state["x"][pressed[i]] - self.state["x"][n]) >= apart for n, _ in chosen):
                chosen.append((pressed[i], values[i]))
            if len(chosen) == count:
                break
        return chosen

    def at_material_point(self, X):
        """The average about the skin node nearest to the reference position X (and that node's distance)."""
        d = np.linalg.norm(self.state["X"][self.skin_nodes] - X, axis=1)
        k = self.skin_nodes[np.argmin(d)]
        return self.average(self.state["x"][k]), d.min()
