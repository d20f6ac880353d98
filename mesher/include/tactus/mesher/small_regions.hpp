#pragma once
// Regions of a label volume too small to mesh well: a connected set of voxels of one label (or an
// enclosed pocket of background) smaller than a few tets. CGAL would give such a region a
// handful of tiny tets (a 2-voxel label in a real segmentation set L_e min/median to 0.04 and the
// stable step with it) or none at all. Each is given to the label it borders most (6-neighbour
// faces), with a warning, before meshing; the mesh's quality.json lists them.
#include <array>
#include <cstddef>
#include <vector>

#include "tactus/core/volume.hpp"

namespace tactus::mesher {

struct AbsorbedRegion {
  int label = 0;  // its label
  std::size_t voxels = 0;
  int into = 0;                       // the label it now belongs to
  std::array<double, 3> at{0, 0, 0};  // a voxel of it, world position (m)
};

// The smallest region kept, in voxels: `min_volume_mm3` (0: two tets of the bone cell size,
// (bone_cell_size_mm)^3 / 5) over the voxel volume, and at least 1.
std::size_t min_region_voxels(const Volume<std::uint8_t>& labels, double min_volume_mm3, double bone_cell_size_mm);

// Absorbs every 6-connected region of fewer than `min_voxels` voxels into the label it shares
// the most voxel faces with (repeated until none is left, at most 4 sweeps); returns them in
// the order absorbed. The background region touching the volume's border is never absorbed.
std::vector<AbsorbedRegion> absorb_small_regions(Volume<std::uint8_t>& labels, std::size_t min_voxels);

}  // namespace tactus::mesher
