#pragma once
// Filters on image volumes shared by the phantom (partial-volume blur) and segmentation
// (denoising, masks): separable Gaussian blur, 3-D connected components, 3-D hole filling.
#include <cstdint>
#include <vector>

#include "tactus/core/volume.hpp"

namespace tactus {

// In-place separable Gaussian blur, sigma in voxels (clamped at the volume's edges).
void gaussian_blur(Volume<float>& volume, double sigma_voxels);

// Connected components of the non-zero voxels of `mask` with 6-neighbour connectivity.
// Returns component ids per voxel (0 = not in mask, 1..n) and fills `sizes` (index = id).
std::vector<std::int32_t> connected_components(const Volume<std::uint8_t>& mask, std::vector<std::size_t>& sizes);

// Sets to 1 every zero voxel not 6-connected to the volume's border through zero voxels.
void fill_holes(Volume<std::uint8_t>& mask);

}  // namespace tactus
