#pragma once
// CT volumes in single files: NIfTI-1 (.nii, .nii.gz), NRRD (.nrrd, or .nhdr with a detached
// raw or gzip data file), MetaImage (.mha, or .mhd with a raw data file) and INRIMAGE-4 (.inr,
// .inr.gz; axis-aligned, no orientation). tactus parses these
// formats itself (they are a fixed binary header or a text header before the voxels): every
// field is checked, the voxel bytes are counted against the header before they are read, and a
// compressed stream is inflated with a cap at the declared size. Values become HU through the
// format's scaling (NIfTI scl_slope/scl_inter; NRRD and MetaImage store them directly);
// geometry becomes metres, an origin and an orthonormal direction in the LPS world frame
// (NIfTI's RAS is turned into LPS; NRRD's "space" says which it is; MetaImage is LPS as ITK
// writes it). A sheared or non-orthogonal affine is refused with a clear message.
#include <filesystem>

#include "tactus/segment/stack.hpp"

namespace tactus::segment {

// True when the path names a file of one of these formats (by its extension).
bool is_volume_file(const std::filesystem::path& file);
SliceStack read_volume_file(const std::filesystem::path& file);

}  // namespace tactus::segment
