#pragma once
// Storage the master kinds reuse from step to step while they search (no allocation per step once
// grown): a uniform grid over a deformable master's triangles, and per-slave results of the
// parallel narrow phase.
#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace tactus::solver {

struct DetectionScratch {
  struct Grid {
    double lo[3]{}, cell = 1;
    int n[3]{1, 1, 1};
    std::vector<std::int32_t> start, items, count;
    std::vector<std::array<int, 6>> box;  // cell range of each triangle
    std::vector<double> normal;           // 4 per triangle: unit outward normal, 1 / (2 area); 0 if degenerate
    // The cell index along axis c of coordinate v, clamped to the grid.
    int cell_of(double v, int c) const { return std::clamp(static_cast<int>((v - lo[c]) / cell), 0, n[c] - 1); }
  } grid;
  // Per slave node of the pair being searched: closest triangle (-1 none), weights, normal, gap.
  std::vector<std::int32_t> slot_triangle;
  std::vector<double> slot_data;  // 7 per slave: N (3), n (3), h
};

// A uniform grid over the triangles (3 node ids each, outward) at positions x, each triangle in
// the cells its box grown by `margin` touches; cells about `scale` wide (at most ~8 per triangle).
// Also each triangle's unit outward normal and 1 / (2 area). (detection.cpp)
void build_triangle_grid(const std::vector<std::int32_t>& triangles, double scale, const double* x, double margin, DetectionScratch::Grid& g);

}  // namespace tactus::solver
