#pragma once
// Storage the master kinds reuse from step to step while they search (no allocation per step once
// grown): a uniform grid over a deformable master's triangles, and per-slave results of the
// parallel narrow phase.
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
  } grid;
  // Per slave node of the pair being searched: closest triangle (-1 none), weights, normal, gap.
  std::vector<std::int32_t> slot_triangle;
  std::vector<double> slot_data;  // 7 per slave: N (3), n (3), h
};

}  // namespace tactus::solver
