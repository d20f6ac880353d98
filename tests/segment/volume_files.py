#!/usr/bin/env python3
"""CT volumes in NIfTI, NRRD and MetaImage written by independent writers, for tactus's readers.

Usage: volume_files.py FOLDER

NIfTI by nibabel (an sform, and a qform-only .nii.gz), MetaImage by VTK's vtkMetaImageWriter
(raw and compressed .mhd) and by hand (.mha with a TransformMatrix, ITK's layout: one axis
direction per triple), NRRD by hand (gzip .nrrd in RAS, detached big-endian .nhdr in LPS). All
hold 9 x 7 x 6 voxels with stored value v(i, j, k) = (7 i + 13 j + 29 k) % 500 - 250 at column i,
row j, slice k. expected.json gives, per file, what a reader must find in the LPS world frame:
HU = slope * v + intercept, spacing (m), origin (m), direction (row by row; column a = axis a).
"""
import gzip
import json
import sys
from pathlib import Path

import numpy as np

NX, NY, NZ = 9, 7, 6


def stored():
    i, j, k = np.meshgrid(np.arange(NX), np.arange(NY), np.arange(NZ), indexing="ij")
    return ((7 * i + 13 * j + 29 * k) % 500 - 250).astype(np.int16)  # indexed [i, j, k]


def rotation(ax, ay, az):
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def expected(direction_lps, spacing_mm, origin_lps_mm, slope=1.0, intercept=0.0):
    return {
        "direction": [float(x) for x in np.asarray(direction_lps).reshape(9)],
        "spacing": [float(x) * 1e-3 for x in spacing_mm],
        "origin": [float(x) * 1e-3 for x in origin_lps_mm],
        "slope": slope,
        "intercept": intercept,
    }


RAS_TO_LPS = np.diag([-1.0, -1.0, 1.0])


def nifti(folder, out):
    import nibabel as nib

    v = stored()
    spacing = np.array([0.6, 0.8, 1.25])
    R = rotation(0.3, -0.2, 0.5)
    origin = np.array([10.0, -20.0, 30.0])
    affine = np.eye(4)
    affine[:3, :3] = R @ np.diag(spacing)
    affine[:3, 3] = origin
    img = nib.Nifti1Image(v, affine)
    img.header.set_slope_inter(2.0, -1000.0)
    img.set_sform(affine, code=1)
    img.set_qform(affine, code=1)
    nib.save(img, str(folder / "sform.nii"))
    out["sform.nii"] = expected(RAS_TO_LPS @ R, spacing, RAS_TO_LPS @ origin, 2.0, -1000.0)
    # qform only, with a reflection (qfac = -1), gzip-compressed
    Rq = rotation(-0.1, 0.4, 1.2) @ np.diag([1.0, 1.0, -1.0])
    affine_q = np.eye(4)
    affine_q[:3, :3] = Rq @ np.diag(spacing)
    affine_q[:3, 3] = origin
    img = nib.Nifti1Image(v, None)
    img.set_qform(affine_q, code=1)
    img.set_sform(None, code=0)
    img.header.set_slope_inter(1.0, 0.0)
    nib.save(img, str(folder / "qform.nii.gz"))
    out["qform.nii.gz"] = expected(RAS_TO_LPS @ Rq, spacing, RAS_TO_LPS @ origin)


def metaimage(folder, out):
    import vtk
    from vtk.util.numpy_support import numpy_to_vtk

    v = stored()
    for name, compress in (("vtk_raw.mhd", False), ("vtk_zlib.mhd", True)):
        image = vtk.vtkImageData()
        image.SetDimensions(NX, NY, NZ)
        image.SetSpacing(0.5, 0.7, 2.0)
        image.SetOrigin(-5.0, 6.0, 7.0)
        arr = numpy_to_vtk(v.transpose(2, 1, 0).ravel().copy(), deep=True, array_type=vtk.VTK_SHORT)  # x fastest
        image.GetPointData().SetScalars(arr)
        w = vtk.vtkMetaImageWriter()
        w.SetFileName(str(folder / name))
        w.SetCompression(compress)
        w.SetInputData(image)
        w.Write()
        out[name] = expected(np.eye(3), [0.5, 0.7, 2.0], [-5.0, 6.0, 7.0])
    R = rotation(0.2, 0.1, -0.7)
    header = (
        "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\nCompressedData = False\n"
        f"TransformMatrix = {' '.join(repr(float(x)) for x in R.T.reshape(9))}\n"
        "Offset = 1.5 -2.5 3.5\nCenterOfRotation = 0 0 0\nAnatomicalOrientation = RAI\n"
        "ElementSpacing = 0.9 0.9 1.1\nDimSize = 9 7 6\nElementType = MET_SHORT\nElementDataFile = LOCAL\n"
    )
    (folder / "rotated.mha").write_bytes(header.encode() + v.transpose(2, 1, 0).astype("<i2").tobytes())
    out["rotated.mha"] = expected(R, [0.9, 0.9, 1.1], [1.5, -2.5, 3.5])


def nrrd(folder, out):
    v = stored()
    R = rotation(0.0, 0.5, 0.25)
    steps = R @ np.diag([0.6, 0.6, 1.5])  # column a: axis a's step in RAS
    dirs = " ".join("(" + ",".join(repr(float(x)) for x in steps[:, a]) + ")" for a in range(3))
    header = (
        "NRRD0004\n# written by tactus's test (independent of its reader)\ntype: short\ndimension: 3\n"
        f"space: right-anterior-superior\nsizes: {NX} {NY} {NZ}\nspace directions: {dirs}\n"
        "kinds: domain domain domain\nendian: little\nencoding: gzip\nspace origin: (4,5,6)\n\n"
    )
    (folder / "ras.nrrd").write_bytes(header.encode() + gzip.compress(v.transpose(2, 1, 0).astype("<i2").tobytes()))
    out["ras.nrrd"] = expected(RAS_TO_LPS @ R, [0.6, 0.6, 1.5], RAS_TO_LPS @ np.array([4.0, 5.0, 6.0]))
    header = (
        "NRRD0004\ntype: float\ndimension: 3\nspace: left-posterior-superior\nsizes: 9 7 6\n"
        "space directions: (0,0.75,0) (-0.75,0,0) (0,0,2)\nendian: big\nencoding: raw\nspace origin: (1,2,3)\n"
        "data file: lps.raw\n\n"
    )
    (folder / "lps.nhdr").write_text(header)
    (folder / "lps.raw").write_bytes(v.transpose(2, 1, 0).astype(">f4").tobytes())
    out["lps.nhdr"] = expected(np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]]), [0.75, 0.75, 2.0], [1.0, 2.0, 3.0])


def main(folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    out = {}
    nifti(folder, out)
    metaimage(folder, out)
    nrrd(folder, out)
    (folder / "expected.json").write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main(Path(sys.argv[1]))
