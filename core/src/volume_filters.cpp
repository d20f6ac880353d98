#include "tactus/core/volume_filters.hpp"

#include <algorithm>
#include <cmath>
#include <deque>

namespace tactus {

void gaussian_blur(Volume<float>& volume, double sigma) {
  if (sigma <= 0 || volume.size() == 0) return;
  const int radius = static_cast<int>(std::ceil(3 * sigma));
  std::vector<float> k(static_cast<std::size_t>(2 * radius + 1));
  double sum = 0;
  for (int i = -radius; i <= radius; ++i)
    sum += k[static_cast<std::size_t>(i + radius)] = static_cast<float>(std::exp(-0.5 * i * i / (sigma * sigma)));
  for (auto& w : k) w = static_cast<float>(w / sum);
  const long n[3] = {volume.dims[0], volume.dims[1], volume.dims[2]};
  const long stride[3] = {1, n[0], n[0] * n[1]};
  std::vector<float> out(volume.size());
  std::vector<float>& v = volume.data;
  const long total = static_cast<long>(v.size());
  for (int axis = 0; axis < 3; ++axis) {
#pragma omp parallel for schedule(static)
    for (long idx = 0; idx < total; ++idx) {
      const long coord = (idx / stride[axis]) % n[axis];
      double acc = 0;
      for (int i = -radius; i <= radius; ++i) {
        const long c = std::clamp(coord + i, 0L, n[axis] - 1);
        acc += k[static_cast<std::size_t>(i + radius)] * v[static_cast<std::size_t>(idx + (c - coord) * stride[axis])];
      }
      out[static_cast<std::size_t>(idx)] = static_cast<float>(acc);
    }
    v.swap(out);
  }
}

namespace {
// Visits the 6 neighbours of voxel idx that lie inside the volume.
template <class F>
void for_neighbours(const std::array<int, 3>& d, std::size_t idx, F&& f) {
  const std::size_t nx = static_cast<std::size_t>(d[0]), nxy = nx * static_cast<std::size_t>(d[1]);
  const std::size_t x = idx % nx, y = (idx / nx) % static_cast<std::size_t>(d[1]), z = idx / nxy;
  if (x > 0) f(idx - 1);
  if (x + 1 < nx) f(idx + 1);
  if (y > 0) f(idx - nx);
  if (y + 1 < static_cast<std::size_t>(d[1])) f(idx + nx);
  if (z > 0) f(idx - nxy);
  if (z + 1 < static_cast<std::size_t>(d[2])) f(idx + nxy);
}
}  // namespace

std::vector<std::int32_t> connected_components(const Volume<std::uint8_t>& mask, std::vector<std::size_t>& sizes) {
  std::vector<std::int32_t> id(mask.size(), 0);
  sizes.assign(1, 0);
  std::vector<std::size_t> stack;
  for (std::size_t seed = 0; seed < mask.size(); ++seed) {
    if (!mask.data[seed] || id[seed]) continue;
    const std::int32_t label = static_cast<std::int32_t>(sizes.size());
    std::size_t count = 0;
    stack.push_back(seed);
    id[seed] = label;
    while (!stack.empty()) {
      const std::size_t v = stack.back();
      stack.pop_back();
      ++count;
      for_neighbours(mask.dims, v, [&](std::size_t w) {
        if (mask.data[w] && !id[w]) id[w] = label, stack.push_back(w);
      });
    }
    sizes.push_back(count);
  }
  return id;
}

// A scanline flood fill of the background from the border: each seed grows into its whole run
// along x (contiguous in memory), and each run seeds the runs of the four rows beside it
// (y +- 1, z +- 1). Several times faster than a voxel-by-voxel fill on CT-sized volumes (100 M
// voxels of mostly air): memory is walked along rows and the coordinates come with the seed.
void fill_holes(Volume<std::uint8_t>& mask) {
  std::vector<std::uint8_t> outside(mask.size(), 0);
  const int nx = mask.dims[0], ny = mask.dims[1], nz = mask.dims[2];
  if (mask.size() == 0) return;
  struct Seed {
    int x, y, z;
  };
  std::vector<Seed> stack;
  auto open = [&](int x, int y, int z) {
    const std::size_t i = mask.index(x, y, z);
    return !mask.data[i] && !outside[i];
  };
  // Pushes one seed per run of open voxels in row (y, z) between x0 and x1.
  auto seed_row = [&](int x0, int x1, int y, int z) {
    if (y < 0 || y >= ny || z < 0 || z >= nz) return;
    bool in_run = false;
    for (int x = x0; x <= x1; ++x) {
      const bool o = open(x, y, z);
      if (o && !in_run) stack.push_back({x, y, z});
      in_run = o;
    }
  };
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y) {
      if (z == 0 || y == 0 || z == nz - 1 || y == ny - 1)
        seed_row(0, nx - 1, y, z);
      else {
        if (open(0, y, z)) stack.push_back({0, y, z});
        if (open(nx - 1, y, z)) stack.push_back({nx - 1, y, z});
      }
    }
  while (!stack.empty()) {
    const Seed s = stack.back();
    stack.pop_back();
    if (!open(s.x, s.y, s.z)) continue;
    int x0 = s.x, x1 = s.x;
    while (x0 > 0 && open(x0 - 1, s.y, s.z)) --x0;
    while (x1 + 1 < nx && open(x1 + 1, s.y, s.z)) ++x1;
    std::fill(outside.begin() + static_cast<std::ptrdiff_t>(mask.index(x0, s.y, s.z)),
              outside.begin() + static_cast<std::ptrdiff_t>(mask.index(x1, s.y, s.z)) + 1, std::uint8_t{1});
    seed_row(x0, x1, s.y - 1, s.z);
    seed_row(x0, x1, s.y + 1, s.z);
    seed_row(x0, x1, s.y, s.z - 1);
    seed_row(x0, x1, s.y, s.z + 1);
  }
  for (std::size_t i = 0; i < mask.size(); ++i)
    if (!outside[i]) mask.data[i] = 1;
}

}  // namespace tactus
