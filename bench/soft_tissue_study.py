#!/usr/bin/env python3
"""Soft-tissue sensitivity study of the hand-block case (docs/studies/soft-tissue.md).

Runs pipeline/scenarios/hand_block.toml on the stored reference meshes with the tissue's bulk
modulus k, its formulation (standard / anp) and its fibre field (anatomical: the hand's
`tactus-mesh fibres` file; global: the material's constant +-30 deg to z) varied, and prints one
markdown table row per run:
peak contact pressure and force, peak tissue and bone von Mises at the outputs, the largest fibre
stretch and the element J range in the tissue at the outputs, the step range and the wall time.

  bench/soft_tissue_study.py [--k 1e6 1e7 1e8] [--formulations standard anp] [--fibres anatomical global] [--work DIR]

Needs a built tree (TACTUS_BUILD_DIR, default build/) and Python with numpy and vtk. About a
minute per run on 2 cores; do not time anything else meanwhile.
"""
import argparse
import glob
import json
import lzma
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUILD = os.environ.get("TACTUS_BUILD_DIR", os.path.join(ROOT, "build"))


def stage_meshes(work):
    ref = os.path.join(ROOT, "bench", "references")
    for stored, path in (("hand_block_hand.msh.xz", "mesh/mesh.msh"), ("hand_block_block.msh.xz", "object/block.msh")):
        os.makedirs(os.path.dirname(os.path.join(work, path)), exist_ok=True)
        with lzma.open(os.path.join(ref, stored)) as src, open(os.path.join(work, path), "wb") as dst:
            shutil.copyfileobj(src, dst)
    fibres = os.path.join(work, "mesh", "fibres.vtu")
    if not os.path.exists(fibres):
        subprocess.run(
            [
                os.path.join(BUILD, "mesher", "tactus-mesh"),
                "fibres",
                os.path.join(work, "mesh", "mesh.msh"),
                "--angle",
                "30",
                "--axis",
                "z",
                "-o",
                fibres,
                "-q",
            ],
            check=True,
        )


def scenario_variant(k, formulation, fibres, path, k1=None):
    text = open(os.path.join(ROOT, "pipeline", "scenarios", "hand_block.toml")).read()
    if fibres == "global":  # the material's constant directions: drop the hand's file
        text = re.sub(r'^fibres = "mesh/fibres.vtu".*\n', "", text, flags=re.M)
    section = re.search(r"\[materials\.soft_tissue\]\n(.*?)\n\n", text, re.S)
    body = re.sub(r"^k = .*$", f"k = {k:g}", section.group(1), flags=re.M)
    if k1 is not None:  # 0: no fibre stiffness at all
        body = re.sub(r"^k1 = .*$", f"k1 = {k1:g}", body, flags=re.M)
    body = re.sub(r"^formulation = .*\n?", "", body, flags=re.M) + f'\nformulation = "{formulation}"'
    text = text[: section.start(1)] + body + text[section.end(1) :]
    open(path, "w").write(text)


def tissue_fields(out):
    """Largest isochoric fibre stretch and the element J range of the soft tissue over the output states."""
    stretch, j_lo, j_hi = 0.0, np.inf, -np.inf
    for f in sorted(glob.glob(os.path.join(out, "results", "state_*.vtu")))[1:]:
        r = vtk.vtkXMLUnstructuredGridReader()
        r.SetFileName(f)
        r.Update()
        cd = r.GetOutput().GetCellData()
        material = vtk_to_numpy(cd.GetArray("material"))
        tissue = material == json.load(open(os.path.join(out, "run.json")))["materials"].index("soft_tissue")  # block index
        J = vtk_to_numpy(cd.GetArray("J"))[tissue]
        # the isochoric stretch sqrt(J4bar) = J^(-1/3) |F a|, the one the hgo law acts on
        stretch = max(stretch, float((vtk_to_numpy(cd.GetArray("fibre_stretch"))[tissue] * J[:, None] ** (-1.0 / 3.0)).max()))
        j_lo, j_hi = min(j_lo, float(J.min())), max(j_hi, float(J.max()))
    return stretch, j_lo, j_hi


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--k", type=float, nargs="+", default=[1e6, 1e7, 1e8])
    ap.add_argument("--formulations", nargs="+", default=["standard", "anp"])
    ap.add_argument("--fibres", nargs="+", default=["anatomical"], choices=["anatomical", "global"])
    ap.add_argument("--k1", type=float, default=None, help="replace the fibre stiffness k1 (Pa; 0: no fibres)")
    ap.add_argument("--work", default=None)
    ap.add_argument("--reuse", action="store_true", help="tabulate the runs already in --work instead of running them again")
    a = ap.parse_args()
    work = a.work or tempfile.mkdtemp(prefix="tactus-study-")
    stage_meshes(work)
    if a.k1 is not None:
        print(f"k1 = {a.k1:g} Pa")
    print(
        "| k (Pa) | formulation | fibres | peak contact pressure (MPa) | peak contact force (kN) "
        "| peak tissue von Mises (MPa) | peak bone von Mises (MPa) "
        "| largest isochoric fibre stretch | tissue element J | step (ns) | wall (s) | status |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for k, formulation, fibres in [(k, f, g) for g in a.fibres for k in a.k for f in a.formulations]:
        name = f"k{k:g}_{formulation}" + ("" if fibres == "global" else "_anatomical") + ("" if a.k1 is None else f"_k1_{a.k1:g}")
        scenario = os.path.join(work, name + ".toml")
        out = os.path.join(work, name + ".out")
        if not (a.reuse and os.path.exists(os.path.join(out, "run.json"))):
            shutil.rmtree(out, ignore_errors=True)
            scenario_variant(k, formulation, fibres, scenario, a.k1)
            proc = subprocess.run(
                [os.path.join(BUILD, "solver", "tactus-solve"), scenario, "--meshes", work, "-o", out, "-q"], capture_output=True, text=True
            )
        if not os.path.exists(os.path.join(out, "run.json")):
            print(
                f"| {k:g} | {formulation} | {fibres} | failed: {proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else proc.returncode} |"
            )
            continue
        run = json.load(open(os.path.join(out, "run.json")))
        wall = run["wall_time_s"]
        peaks = run["peak_von_mises_at_outputs"]
        stretch, j_lo, j_hi = tissue_fields(out)
        print(
            f"| {k:g} | {formulation} | {fibres} | {run['contact']['peak_pressure']['value'] / 1e6:.1f} "
            f"| {run['contact']['peak_force']['value'] / 1e3:.2f} "
            f"| {peaks['soft_tissue'] / 1e6:.2f} | {peaks['bone'] / 1e6:.1f} | {stretch:.3f} | {j_lo:.3f}..{j_hi:.3f} "
            f"| {run['time_step']['min'] * 1e9:.0f}..{run['time_step']['max'] * 1e9:.0f} | {wall:.0f} | {run['status']} |",
            flush=True,
        )


if __name__ == "__main__":
    sys.exit(main())
