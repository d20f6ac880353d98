#pragma once
// Closed triangle surfaces of the skin and of each bone from a label volume: marching cubes
// (VTK flying edges) on the binary mask, windowed-sinc smoothing (which does not shrink the
// volume as Laplacian smoothing does), isotropic remeshing to well-shaped triangles (CGAL), and
// checks (closed, 2-manifold, no self-intersection) before writing STL and PLY (metres).
#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "tactus/core/volume.hpp"

namespace tactus::segment {

struct SurfaceParams {
  int smoothing_iterations = 20;
  double smoothing_passband = 0.1;
  double target_edge_voxels = 1.5;  // remeshing target edge length, in voxels
  int remeshing_iterations = 3;
  // false: no repair when a surface fails its checks (for the tests of the degraded path).
  bool repair = true;
};

struct SurfaceReport {
  std::string name;
  std::vector<int> labels;  // label ids enclosed
  std::size_t vertices = 0, triangles = 0;
  double surface_volume_m3 = 0, label_volume_m3 = 0, area_m2 = 0;
  double min_angle_deg = 0;
  bool closed = false, manifold = false, self_intersecting = true;
  double edge_factor = 1;                                  // the target edge it was remeshed at, x SurfaceParams::target_edge_voxels
  bool passed = false;                                     // the checks: closed, 2-manifold, not self-intersecting
  std::vector<std::string> repairs;                        // what was tried after the first remeshing, in order
  std::size_t intersecting_pairs = 0;                      // when it failed: its self-intersecting triangle pairs
  std::array<double, 3> worst_self_intersection{0, 0, 0};  // m, world frame: where the most of them crowd
  std::string failure;                                     // when it failed: what and where, as warned
  std::filesystem::path stl, ply;
};

// Extracts "skin" (every label >= 1) and one surface per bone label (>= 2) into `folder`
// (skin.stl/.ply, bone_NN.stl/.ply). A surface that fails its checks after the repairs is written
// as <name>_failed_checks.stl/.ply, its report saying what failed and where (a warning, not an
// error: the labels are what the mesher reads).
std::vector<SurfaceReport> extract_surfaces(const Volume<std::uint8_t>& labels, const LabelTable& table, const std::filesystem::path& folder,
                                            const SurfaceParams& params);

}  // namespace tactus::segment
