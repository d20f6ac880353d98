#!/usr/bin/env python3
"""An independently written DICOM CT series (pydicom, not GDCM) for tactus's DICOM reader tests.

Usage: pydicom_series.py FOLDER

Writes 6 slices of 9 columns x 7 rows in implicit VR little endian, signed 12 of 16 bits (the
upper 4 bits set, as overlay planes once were), RescaleSlope 2,
RescaleIntercept -1000, PixelSpacing 0.8 (rows) \\ 0.6 (columns) mm, slices 1.25 mm apart from
(10, -20, 30) mm, under random file names written in random order, each with a nested sequence of
undefined length; plus a text file and a DICOMDIR-like file without pixels. Stored value
v(i, j, k) = (7 i + 13 j + 29 k) % 500 - 250 at column i, row j, slice k: HU = 2 v - 1000.
"""
import random
import struct
import sys
from pathlib import Path

from pydicom.dataset import Dataset, FileDataset, FileMetaDataset
from pydicom.sequence import Sequence
from pydicom.uid import ImplicitVRLittleEndian, generate_uid

CT = "1.2.840.10008.5.1.4.1.1.2"


def main(folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    rng = random.Random(7)
    series, study, frame = generate_uid(), generate_uid(), generate_uid()
    nx, ny, nz = 9, 7, 6
    order = list(range(nz))
    rng.shuffle(order)
    for k in order:
        meta = FileMetaDataset()
        meta.MediaStorageSOPClassUID = CT
        meta.MediaStorageSOPInstanceUID = generate_uid()
        meta.TransferSyntaxUID = ImplicitVRLittleEndian
        name = folder / f"{rng.getrandbits(40):010x}"
        ds = FileDataset(str(name), {}, file_meta=meta, preamble=b"\0" * 128)
        ds.is_little_endian, ds.is_implicit_VR = True, True
        ds.SOPClassUID, ds.SOPInstanceUID = CT, meta.MediaStorageSOPInstanceUID
        ds.Modality, ds.PatientName, ds.PatientID = "CT", "Independent^Writer", "PYDICOM"
        ds.StudyInstanceUID, ds.SeriesInstanceUID, ds.FrameOfReferenceUID = study, series, frame
        ds.SeriesDescription = "pydicom series"
        ds.InstanceNumber = k + 1
        ds.ImagePositionPatient = [10.0, -20.0, 30.0 + 1.25 * k]
        ds.ImageOrientationPatient = [1, 0, 0, 0, 1, 0]
        ds.PixelSpacing = [0.8, 0.6]
        ds.SliceThickness = 3.0  # deliberately not the spacing: the reader must use the positions
        ds.RescaleSlope, ds.RescaleIntercept = 2, -1000
        ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
        ds.Rows, ds.Columns = ny, nx
        ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 12, 11, 1
        item = Dataset()
        item.ReferencedSOPClassUID, item.ReferencedSOPInstanceUID = CT, generate_uid()
        inner = Dataset()
        inner.CodeValue, inner.CodingSchemeDesignator, inner.CodeMeaning = "T-D8800", "SRT", "Hand"
        item.PurposeOfReferenceCodeSequence = Sequence([inner])
        ds.ReferencedImageSequence = Sequence([item])
        v = [(7 * i + 13 * j + 29 * k) % 500 - 250 for j in range(ny) for i in range(nx)]
        # 12-bit two's complement in 16-bit words, the 4 bits above them set (as old overlay planes
        # did): a reader must use BitsStored, not the whole word.
        ds.PixelData = struct.pack(f"<{nx * ny}H", *[0xA000 | (x & 0x0FFF) for x in v])
        ds.save_as(str(name), write_like_original=False)
    (folder / "notes.txt").write_text("not a DICOM file\n")
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = "1.2.840.10008.1.3.10"  # Media Storage Directory Storage
    meta.MediaStorageSOPInstanceUID = generate_uid()
    meta.TransferSyntaxUID = ImplicitVRLittleEndian
    d = FileDataset(str(folder / "DIRFILE"), {}, file_meta=meta, preamble=b"\0" * 128)
    d.is_little_endian, d.is_implicit_VR = True, True
    d.FileSetID = "TACTUS"
    d.save_as(str(folder / "DIRFILE"), write_like_original=False)


if __name__ == "__main__":
    main(Path(sys.argv[1]))
