#pragma once
// Mesh quality for explicit dynamics: per-subdomain counts, dihedral angles, radius ratio, edge
// ratio, volumes, slivers, and the characteristic length L_e of core's stable-step function,
// from which the critical time step for given wave speeds follows.
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "tactus/core/mesh.hpp"

namespace tactus::mesher {

struct TetQuality {
  double min_dihedral_deg, max_dihedral_deg, radius_ratio, edge_ratio, volume, length;  // length = L_e
};
TetQuality tet_quality(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// Report as JSON (written as quality.json). wave_speed(group tag) gives the dilatational speed
// used for the critical step (<= 0: group skipped).
nlohmann::json quality_report(const TetMesh& mesh, const std::map<int, double>& wave_speed, double sliver_deg = 10.0);

}  // namespace tactus::mesher
