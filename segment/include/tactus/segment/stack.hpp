#pragma once
// Reading a CT slice stack (docs/design.md): a folder of slice_NNNN.png|tif (8 or 16 bit, one
// channel) and stack.json {spacing_mm, origin_mm (optional), rescale_slope, rescale_intercept,
// slices}. Converted once here to Hounsfield units and metres. Every field is checked (finite, in
// range, the slice count against the files); PNG containers are validated before decoding and the
// decoders run in an isolated child process, so a corrupt slice is an InputError, never a crash.
#include <filesystem>
#include <string>

#include "tactus/core/volume.hpp"

namespace tactus::segment {

struct SliceStack {
  Volume<float> hu;   // Hounsfield units; spacing/origin in metres
  int bit_depth = 0;  // 8 or 16
  std::size_t files = 0;
  std::string source = "slice stack";  // or "DICOM series <uid>"
};

SliceStack read_slice_stack(const std::filesystem::path& folder);

}  // namespace tactus::segment
