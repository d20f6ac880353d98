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

void fill_holes(Volume<std::uint8_t>& mask) {
  std::vector<std::uint8_t> outside(mask.size(), 0);
  std::vector<std::size_t> stack;
  const auto& d = mask.dims;
  for (int z = 0; z < d[2]; ++z)
    for (int y = 0; y < d[1]; ++y)
      for (int x = 0; x < d[0]; ++x) {
        const bool border = x == 0 || y == 0 || z == 0 || x == d[0] - 1 || y == d[1] - 1 || z == d[2] - 1;
        const std::size_t i = mask.index(x, y, z);
        if (border && !mask.data[i] && !outside[i]) outside[i] = 1, stack.push_back(i);
      }
  while (!stack.empty()) {
    const std::size_t v = stack.back();
    stack.pop_back();
    for_neighbours(d, v, [&](std::size_t w) {
      if (!mask.data[w] && !outside[w]) outside[w] = 1, stack.push_back(w);
    });
  }
  for (std::size_t i = 0; i < mask.size(); ++i)
    if (!outside[i]) mask.data[i] = 1;
}

}  // namespace tactus
