#pragma once
// Reading a DICOM CT series (docs/design.md, "DICOM input"). Every file's structure (the Part 10
// preamble and file meta group, then each data element's tag, VR and length, sequences and
// encapsulated pixel data to any depth) is walked by tactus itself before a third-party decoder
// sees it; the header values tactus needs come from that walk and are checked (sizes, spacing,
// orientation, rescale). Only the pixel data is decoded by GDCM (all the transfer syntaxes it
// supports: uncompressed, RLE, JPEG lossless, JPEG-LS, JPEG 2000), in an isolated child
// process. Slices are sorted along the slice normal by ImagePositionPatient, the spacing comes
// from the positions (never SliceThickness), and uneven spacing, a missing slice, gantry tilt and
// mixed sizes are clear errors. The orientation (ImageOrientationPatient) becomes the volume's
// direction, its origin the first slice's position: world coordinates are DICOM's patient frame.
#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "tactus/segment/stack.hpp"

namespace tactus::segment {

// What one file's walk found (only what tactus uses).
struct DicomSlice {
  std::filesystem::path file;
  std::string series_uid, series_description, sop_class_uid, transfer_syntax;
  std::string modality;  // (0008,0060): "CT", "MR", ...
  int rows = 0, columns = 0, bits_allocated = 0, bits_stored = 0, high_bit = -1, pixel_representation = 0, samples_per_pixel = 0;
  std::array<double, 2> pixel_spacing{0, 0};            // mm: between rows, between columns
  std::array<double, 3> position{0, 0, 0};              // ImagePositionPatient, mm
  std::array<double, 6> orientation{0, 0, 0, 0, 0, 0};  // ImageOrientationPatient: row then column cosines
  double slope = 1, intercept = 0;
  bool has_position = false, has_orientation = false, has_pixel_spacing = false, has_pixels = false;
};

// One series of a folder.
struct DicomSeries {
  std::string uid, description;
  std::vector<DicomSlice> slices;
};

// True when `file` starts like a DICOM Part 10 file (128-byte preamble, "DICM").
bool looks_like_dicom(const std::filesystem::path& file);
// Walks one file (InputError naming it and the element when it is malformed or not an image).
DicomSlice scan_dicom_file(const std::filesystem::path& file);
// The DICOM series of a folder (its DICOM files, not its subfolders), by SeriesInstanceUID.
std::vector<DicomSeries> list_dicom_series(const std::filesystem::path& folder);
// True when the folder holds at least one DICOM file and no stack.json.
bool is_dicom_folder(const std::filesystem::path& folder);
// Reads the series `series_uid` of the folder (empty: its only series; several series without a
// choice is an error that lists them) as Hounsfield units in metres.
SliceStack read_dicom_series(const std::filesystem::path& folder, const std::string& series_uid = {});

}  // namespace tactus::segment
