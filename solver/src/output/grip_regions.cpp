// The grip's regions: each handle-touching skin node to its nearest bone's segment or palm zone,
// and the handle's load summed per region (grip_regions.hpp).
#include "tactus/solver/grip_regions.hpp"

#include <algorithm>
#include <array>
#include <limits>

namespace tactus::solver {

namespace {

// The first pass of a handle entry: its slaves are the hand's skin (a two_pass entry's second
// pass has its slaves on the handle; an edge pass reports onto the first pass's nodes).
bool skin_pass(const ContactPair& pair) { return pair.report_sign > 0 && !pair.edge_pass; }

std::string digit_name(const std::string& metacarpal) {
  const std::string prefix = "metacarpal_";
  return metacarpal.rfind(prefix, 0) == 0 ? metacarpal.substr(prefix.size()) : metacarpal;
}

// Per bone: whether it is a palm bone (a root, or named "metacarpal_..."), and for a phalanx (any
// other bone) the palm bone its digit hangs from: the first metacarpal up its chain or, on a
// chain without one, the bone below the root.
void chains_of(const Skeleton& s, std::vector<char>& palm_bone, std::vector<std::size_t>& metacarpal) {
  const std::size_t nb = s.bones.size();
  palm_bone.assign(nb, 0), metacarpal.assign(nb, nb);
  auto index = [&](const std::string& name) { return static_cast<std::size_t>(s.bone(name) - s.bones.data()); };
  for (std::size_t b = 0; b < nb; ++b) palm_bone[b] = s.bones[b].parent.empty() || s.bones[b].name.rfind("metacarpal", 0) == 0;
  for (std::size_t b = 0; b < nb; ++b) {
    if (palm_bone[b]) continue;
    std::size_t below = b;
    for (std::size_t up = index(s.bones[b].parent), guard = 0; guard < nb; up = index(s.bones[up].parent), ++guard) {
      if (palm_bone[up]) {
        metacarpal[b] = s.bones[up].parent.empty() && s.bones[up].name.rfind("metacarpal", 0) != 0 ? below : up;
        break;
      }
      below = up;
    }
  }
}

}  // namespace

GripRegions::GripRegions(const Model& model, const RigidBodies& rigid, const JointDrive& drive, const ContactSolver& contact)
    : entries_(drive.grip_entries()) {
  const Skeleton& s = drive.skeleton();
  const std::size_t nb = s.bones.size();
  std::vector<char> palm_bone;
  std::vector<std::size_t> metacarpal;
  chains_of(s, palm_bone, metacarpal);
  std::vector<char> is_metacarpal(nb, 0);  // the bones the digits hang from
  for (std::size_t b = 0; b < nb; ++b)
    if (metacarpal[b] < nb) is_metacarpal[metacarpal[b]] = 1;
  // The digits in the hand's order where the names say it, then any other chain; the palm last.
  for (const char* d : {"thumb", "index", "middle", "ring", "little"})
    for (std::size_t b = 0; b < nb; ++b)
      if (is_metacarpal[b] && digit_name(s.bones[b].name) == d) digits_.push_back(d);
  for (std::size_t b = 0; b < nb; ++b)
    if (is_metacarpal[b] && std::find(digits_.begin(), digits_.end(), digit_name(s.bones[b].name)) == digits_.end())
      digits_.push_back(digit_name(s.bones[b].name));
  const std::size_t palm = digits_.size();
  digits_.push_back("palm");
  auto digit_of = [&](std::size_t b) {
    return static_cast<std::size_t>(std::find(digits_.begin(), digits_.end(), digit_name(s.bones[metacarpal[b]].name)) - digits_.begin());
  };
  auto depth = [&](std::size_t b) {
    int d = 0;
    for (std::string p = s.bones[b].parent; !p.empty() && d <= static_cast<int>(nb); p = s.bone(p)->parent) ++d;
    return d;
  };
  // Regions: each digit's phalanges from proximal to distal, then the three palm zones.
  std::vector<std::int32_t> region_of_bone(nb, -1);
  for (std::size_t d = 0; d < palm; ++d)
    for (int level = 1; level <= static_cast<int>(nb); ++level)
      for (std::size_t b = 0; b < nb; ++b)
        if (!palm_bone[b] && depth(b) == level && digit_of(b) == d)
          region_of_bone[b] = static_cast<std::int32_t>(names_.size()), names_.push_back(s.bones[b].name), digit_.push_back(d);
  const auto thenar = static_cast<std::int32_t>(names_.size());
  for (const char* zone : {"palm_thenar", "palm_central", "palm_hypothenar"}) names_.emplace_back(zone), digit_.push_back(palm);
  auto palm_zone = [&](std::size_t b) {  // b: a metacarpal
    const std::string d = digit_name(s.bones[b].name);
    return thenar + (d == "thumb" ? 0 : d == "little" ? 2 : 1);
  };
  // The bones' nodes (a loose or fused piece counts as a root), and the metacarpals' alone.
  struct BoneNode {
    std::array<double, 3> x;
    std::size_t bone;  // nb: a held piece no bone owns alone
  };
  std::vector<BoneNode> bone_nodes;
  auto add_piece = [&](std::size_t piece, std::size_t bone) {
    for (std::int32_t n : rigid.bodies()[piece].nodes) {
      const double* X = &model.X[3 * static_cast<std::size_t>(n)];
      bone_nodes.push_back({{X[0], X[1], X[2]}, bone});
    }
  };
  for (std::size_t b = 0; b < nb; ++b)
    for (std::size_t k : drive.pieces(b)) add_piece(k, b);
  for (std::size_t k : drive.loose_pieces()) add_piece(k, nb);
  auto nearest = [&](const double* x, bool metacarpals_only) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t bone = nb;
    for (const BoneNode& n : bone_nodes) {
      if (metacarpals_only && (n.bone == nb || !is_metacarpal[n.bone])) continue;
      const double d = (n.x[0] - x[0]) * (n.x[0] - x[0]) + (n.x[1] - x[1]) * (n.x[1] - x[1]) + (n.x[2] - x[2]) * (n.x[2] - x[2]);
      if (d < best) best = d, bone = n.bone;
    }
    return bone;
  };
  region_.assign(model.num_nodes, -1);
  node_area_.assign(model.num_nodes, 0.0);
  node_force_.assign(model.num_nodes, 0.0);
  node_pressure_.assign(model.num_nodes, 0.0);
  is_pressed_.assign(model.num_nodes, 0);
  for (const ContactPair& pair : contact.pairs()) {
    if (!counts_in_grip(pair, entries_) || !skin_pass(pair)) continue;
    surface_.insert(surface_.end(), pair.slave_triangles.begin(), pair.slave_triangles.end());
    for (std::size_t i = 0; i < pair.slave_nodes.size(); ++i) {
      const auto node = static_cast<std::size_t>(pair.slave_nodes[i]);
      node_area_[node] = pair.slave_area[i];
      if (region_[node] >= 0) continue;
      const double* x = &model.X[3 * node];
      const std::size_t bone = nearest(x, false);
      if (bone < nb && !palm_bone[bone]) {
        region_[node] = region_of_bone[bone];
      } else {
        const std::size_t m = bone < nb && is_metacarpal[bone] ? bone : nearest(x, true);
        region_[node] = m < nb ? palm_zone(m) : thenar + 1;
      }
    }
  }
  force_.assign(names_.size(), 0.0), area_.assign(names_.size(), 0.0), peak_.assign(names_.size(), 0.0);
  digit_force_.assign(digits_.size(), 0.0);
}

void GripRegions::sum(const ContactSolver& contact) {
  for (std::int32_t n : pressed_) {
    const auto i = static_cast<std::size_t>(n);
    node_force_[i] = 0, node_pressure_[i] = 0, is_pressed_[i] = 0;
  }
  pressed_.clear();
  const ContactRows& rows = contact.rows();
  // A node's force, and its pressure as the run's pressure field has it (ContactSolver::update_windows):
  // a row's r_n over the row's own area, an edge pass's share over the node's tributary area.
  auto add = [&](std::int32_t node, double f, double area) {
    const auto i = static_cast<std::size_t>(node);
    if (!is_pressed_[i]) is_pressed_[i] = 1, pressed_.push_back(node);
    node_force_[i] += f;
    if (area > 0) node_pressure_[i] += f / area;
  };
  for (std::size_t k = 0; k < rows.size(); ++k) {
    if (rows.status[k] == ContactStatus::open) continue;
    const ContactPair& pair = contact.pairs()[static_cast<std::size_t>(rows.pair[k])];
    if (!counts_in_grip(pair, entries_)) continue;
    const double* r = &rows.reaction[3 * k];
    const double* n = &rows.normal[3 * k];
    const double rn = r[0] * n[0] + r[1] * n[1] + r[2] * n[2];
    if (pair.edge_pass) {  // -w_a r_n at each skin node of the master side (sum of -w_a = 1)
      for (auto a = rows.start[k] + 1; a < rows.start[k + 1]; ++a) {
        const std::int32_t node = rows.nodes[static_cast<std::size_t>(a)];
        add(node, -rows.weights[static_cast<std::size_t>(a)] * rn, node_area_[static_cast<std::size_t>(node)]);
      }
    } else {
      add(rows.slave(k), rn, rows.area[k]);
    }
  }
  std::fill(force_.begin(), force_.end(), 0.0), std::fill(area_.begin(), area_.end(), 0.0), std::fill(peak_.begin(), peak_.end(), 0.0);
  std::sort(pressed_.begin(), pressed_.end());  // the sums in node order, whatever the rows' order
  for (std::int32_t node : pressed_) {
    const auto i = static_cast<std::size_t>(node);
    const std::int32_t reg = region_[i];
    if (reg < 0 || !(node_force_[i] > 0)) {
      node_pressure_[i] = 0;
      continue;
    }
    const auto r = static_cast<std::size_t>(reg);
    force_[r] += node_force_[i], area_[r] += node_area_[i], peak_[r] = std::max(peak_[r], node_pressure_[i]);
  }
  std::fill(digit_force_.begin(), digit_force_.end(), 0.0);
  for (std::size_t r = 0; r < names_.size(); ++r) digit_force_[digit_[r]] += force_[r];
}

std::vector<double> GripRegions::averaged_peak_pressure(const Model& model, const double* u, double sensor_area) const {
  std::vector<double> out(names_.size(), 0.0);
  for (std::size_t r = 0; r < names_.size(); ++r) {
    std::vector<std::int32_t> centres;
    for (std::int32_t node : pressed_)
      if (region_[static_cast<std::size_t>(node)] == static_cast<std::int32_t>(r) && node_pressure_[static_cast<std::size_t>(node)] > 0)
        centres.push_back(node);
    out[r] = disc_averaged_peak(model.X.data(), u, surface_, node_pressure_.data(), centres, sensor_area).value;
  }
  return out;
}

}  // namespace tactus::solver
