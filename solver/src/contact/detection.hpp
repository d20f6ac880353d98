#pragma once
// Storage the master kinds reuse from step to step while they search (no allocation per step once
// grown), one per contact pair: a uniform grid over a deformable master's triangles, the Verlet
// candidate lists of the node-to-surface search, and per-slave results of the parallel narrow
// phase.
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

namespace tactus::solver {

struct ContactPair;

// Where a pair's nodes were when its search was last built, to tell when it must be built again:
// the node-to-surface Verlet lists and the mortar segments' integration both hold while no node of
// the pair has moved more than a reach since, and the band is the one they were built for.
//
// Most steps move every node far less than the reach, so a check first adds the farthest any
// contact node moved since the last check (ContactSolver measures it while it copies the
// positions) to a bound on how far any node has moved since the build: while the bound is within
// the reach the lists hold without a scan over the pair's nodes. When it is not, the check scans,
// gives the scan's answer and resets the bound to the distance the scan found. Since the bound is
// never below the distance a scan would find (the triangle inequality; its relative rounding, a
// few ulps per term, is covered by kBoundSlack and a scan at least every kMaxUnscanned checks),
// the answer is always the scan's, and the lists are rebuilt at the same steps as with a scan at
// every check.
struct BuildSnapshot {
  double band = -1;
  std::vector<std::int32_t> nodes;  // the pair's slave nodes and master vertices, sorted, unique
  std::vector<double> x;            // their positions at the build, 3 each
  // At least the farthest any node has moved since the build; infinite when not known (before the
  // first check after a restart). Checks since the last scan, and scans over all checks.
  double moved_bound = std::numeric_limits<double>::infinity();
  std::size_t unscanned = 0, scans = 0;
  static constexpr double kBoundSlack = 1 - 1e-8;
  static constexpr std::size_t kMaxUnscanned = std::size_t{1} << 20;
  // Records the positions x of the pair's nodes (its slave nodes and master_triangles' vertices).
  void record(const ContactPair& p, const std::vector<std::int32_t>& master_triangles, const double* x, double band);
  // True when a build was recorded for this band and no node has moved more than `reach` since.
  // moved: at least the farthest any node moved since the last check (infinite: not known).
  bool holds(const double* x, double band, double reach, double moved, int threads);
};

// A mortar row as integrated (contact/mortar.cpp), kept until the next integration.
struct MortarRow {
  std::int32_t slave_index, slave_node;
  std::size_t begin, end;  // its masters and weights
  std::array<double, 3> n;
  double gap, along_normal, area;  // h and n . (x_j - sum_k w_k x_k) when integrated
};

struct DetectionScratch {
  struct Grid {
    double lo[3]{}, cell = 1;
    int n[3]{1, 1, 1};
    std::vector<std::int32_t> start, items, count;
    std::vector<std::array<int, 6>> box;  // cell range of each triangle
    std::vector<double> extent;           // 6 per triangle: its own box (min x, y, z, max x, y, z), not grown
    std::vector<double> normal;           // 4 per triangle: unit outward normal, 1 / (2 area); 0 if degenerate
    // The cell index along axis c of coordinate v, clamped to the grid.
    int cell_of(double v, int c) const { return std::clamp(static_cast<int>((v - lo[c]) / cell), 0, n[c] - 1); }
  } grid;
  // Per slave node, two slots (the closest master face, and a second face in front of the node
  // at a concave corner): triangle (-1 none), and N (3), n (3), h.
  std::vector<std::int32_t> slot_triangle;  // 2 per slave
  std::vector<double> slot_data;            // 2 x 7 per slave

  // Verlet lists (Verlet 1967, as in molecular dynamics): the triangles within band + skin of each
  // slave node when they were built stay the only candidates while no node of the pair has moved
  // more than skin / 2 since (then no triangle can have come within band unseen).
  double skin = 0;                                         // extra search distance, m (set by the contact solver; 0: search every step)
  double moved = std::numeric_limits<double>::infinity();  // since the last search, at least (set by the contact solver)
  BuildSnapshot built;                                     // the last build of the lists
  std::vector<std::int32_t> candidate_start, candidates;   // per slave node, CSR
  std::vector<std::int32_t> active_triangles;              // the triangles whose normals the lists need, sorted
  std::size_t builds = 0, searches = 0;                    // list builds (mortar: integrations), and steps searched

  // A mortar pair's rows as last integrated, and where its nodes were then: the rows hold (their
  // gaps following the nodes' motion) until a node has moved a reach since.
  struct Mortar {
    std::vector<MortarRow> rows;
    std::vector<std::int32_t> masters;
    std::vector<double> weights;
    BuildSnapshot integrated;
    std::vector<std::size_t> slave_local;  // each slave triangle's nodes as positions in the pair's slave_nodes
  } mortar;
};

// A uniform grid over the triangles (3 node ids each, outward) at positions x, each triangle in
// the cells its box grown by `margin` touches; cells about `scale` wide (at most ~8 per triangle).
// Also each triangle's own box, unit outward normal and 1 / (2 area). (detection.cpp)
void build_triangle_grid(const std::vector<std::int32_t>& triangles, double scale, const double* x, double margin, DetectionScratch::Grid& g);

}  // namespace tactus::solver
