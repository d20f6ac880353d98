// The skeleton of a meshed hand (skeleton.hpp): principal axes, chains, head fits.
#include "tactus/mesher/skeleton.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/log.hpp"

namespace tactus::mesher {

namespace {

using V = Eigen::Vector3d;

const char* const kDigits[5] = {"index", "middle", "ring", "little", "thumb"};
const char* const kFingerBones[4] = {"distal_phalanx", "middle_phalanx", "proximal_phalanx", "metacarpal"};  // tip first
const char* const kThumbBones[3] = {"distal_phalanx", "proximal_phalanx", "metacarpal"};
const char* const kFingerJoints[4] = {"dip", "pip", "mcp", "cmc"};  // the joint into each bone, tip first
const char* const kThumbJoints[3] = {"ip", "mcp", "cmc"};

V eig(const Vec3& v) { return {v[0], v[1], v[2]}; }
Vec3 arr(const V& v) { return {v.x(), v.y(), v.z()}; }

struct BoneShape {
  int label = 0;
  std::string group;
  double volume = 0;
  V centroid = V::Zero(), axis = V::Zero();
  double elongation = 1;   // sqrt(largest / middle principal spread): >= 2 for a long bone
  std::vector<V> surface;  // its boundary nodes
  V lo = V::Constant(1e300), hi = V::Constant(-1e300);
};

// Volume, centroid and principal axis of each bone group's tets; their boundary nodes.
std::vector<BoneShape> bone_shapes(const TetMesh& mesh) {
  std::map<int, std::size_t> slot;
  std::vector<BoneShape> bones;
  std::vector<Eigen::Matrix3d> second(0);
  std::vector<V> first, shift;
  std::map<std::array<int, 4>, int> faces;  // (group, sorted face) -> tets of the group on it
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    const int g = mesh.tet_group[e];
    if (g < contracts::kFirstBoneLabel) continue;
    auto [it, fresh] = slot.emplace(g, bones.size());
    if (fresh) {
      bones.push_back({});
      bones.back().label = g;
      const PhysicalGroup* pg = mesh.find_group(3, g);
      bones.back().group = pg ? pg->name : "label_" + std::to_string(g);
      second.push_back(Eigen::Matrix3d::Zero());
      first.push_back(V::Zero());
      shift.push_back(eig(mesh.nodes[mesh.tets[e][0]]));  // moments about a point of the bone, for rounding
    }
    const std::size_t b = it->second;
    const auto& t = mesh.tets[e];
    V p[4];
    for (int i = 0; i < 4; ++i) p[i] = eig(mesh.nodes[t[i]]) - shift[b];
    const double vol = std::abs((p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0])) / 6;
    const V s = p[0] + p[1] + p[2] + p[3];
    // Over a tet: int x dV = V s / 4, int x x^T dV = V / 20 (sum p_i p_i^T + s s^T).
    Eigen::Matrix3d m = s * s.transpose();
    for (const V& q : p) m += q * q.transpose();
    bones[b].volume += vol;
    first[b] += vol * s / 4;
    second[b] += vol / 20 * m;
    for (int i = 0; i < 4; ++i) {
      std::array<int, 3> f{t[(i + 1) % 4], t[(i + 2) % 4], t[(i + 3) % 4]};
      std::sort(f.begin(), f.end());
      ++faces[{g, f[0], f[1], f[2]}];
    }
  }
  std::vector<std::set<int>> surface_nodes(bones.size());
  for (const auto& [key, count] : faces)
    if (count == 1)
      for (int i = 1; i < 4; ++i) surface_nodes[slot.at(key[0])].insert(key[i]);
  for (std::size_t b = 0; b < bones.size(); ++b) {
    BoneShape& s = bones[b];
    const V c = first[b] / s.volume;
    const Eigen::Matrix3d cov = second[b] / s.volume - c * c.transpose();
    s.centroid = c + shift[b];
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    s.axis = es.eigenvectors().col(2);  // the largest spread: the long axis
    s.elongation = std::sqrt(es.eigenvalues()(2) / std::max(es.eigenvalues()(1), 1e-30));
    for (int n : surface_nodes[b]) {
      s.surface.push_back(eig(mesh.nodes[n]));
      s.lo = s.lo.cwiseMin(s.surface.back());
      s.hi = s.hi.cwiseMax(s.surface.back());
    }
  }
  return bones;
}

// The smallest distance between two bones' surface nodes (infinity when their boxes are further apart than `reach`).
double surface_gap(const BoneShape& a, const BoneShape& b, double reach) {
  const V apart = (a.lo - b.hi).cwiseMax(b.lo - a.hi).cwiseMax(V::Zero());
  if (apart.norm() > reach) return INFINITY;
  double best = INFINITY;
  for (const V& p : a.surface)
    for (const V& q : b.surface) best = std::min(best, (p - q).squaredNorm());
  return std::sqrt(best);
}

std::string labels_of(const std::vector<BoneShape>& bones, const std::vector<std::size_t>& which) {
  std::ostringstream s;
  for (std::size_t i = 0; i < which.size(); ++i) s << (i ? ", " : "") << bones[which[i]].label << " (" << bones[which[i]].group << ")";
  return s.str();
}

// What the chain refusals add when the hand has fewer bone groups than a hand's 27 bones: two
// bones closer than about two voxels fuse in the segmentation (the phantom at 1.2 mm voxels has
// 26, two carpals one elongated group that passes for a long bone; at 1.5 mm 21), and a fused pair
// breaks the chains. Not a refusal by itself: a scan may hold part of a hand, or sesamoids more.
std::string fused_bones_hint(std::size_t groups) {
  constexpr std::size_t kHandBones = 27;
  if (groups >= kHandBones) return "";
  return " (the mesh has " + std::to_string(groups) + " bone groups where a hand has 27: bones closer than about two voxels fuse " +
         "in the segmentation, so segment at a finer voxel or name the groups with --names)";
}

// A long bone (phalanx, metacarpal) spreads at least twice as far along its axis as across it; a
// carpal is compact (the phantom's: 1.6, its phalanges 3 and more).
constexpr double kLongBone = 2.0;

struct Digit {
  std::vector<std::size_t> bones;  // tip first, metacarpal last
  std::size_t carpal = 0;
};

// The chains of the neighbour graph: four fingers and a thumb, or an InputError naming the labels.
std::vector<Digit> chains(const std::vector<BoneShape>& bones, const std::vector<std::vector<std::size_t>>& near,
                          const std::vector<std::vector<double>>& gap, const std::string& source) {
  std::vector<Digit> fingers, thumbs;
  auto is_long = [&](std::size_t b) { return bones[b].elongation >= kLongBone; };
  for (std::size_t leaf = 0; leaf < bones.size(); ++leaf) {
    if (near[leaf].size() != 1 || !is_long(leaf)) continue;
    Digit d;
    d.bones.push_back(leaf);
    std::set<std::size_t> seen{leaf};
    bool at_carpal = false;
    while (d.bones.size() < 8) {
      std::vector<std::size_t> next_long;
      double nearest_compact = INFINITY;
      for (std::size_t n : near[d.bones.back()]) {
        if (seen.count(n)) continue;
        if (!is_long(n)) {
          if (gap[d.bones.back()][n] < nearest_compact) nearest_compact = gap[d.bones.back()][n], d.carpal = n;
        } else {
          next_long.push_back(n);
        }
      }
      if (std::isfinite(nearest_compact)) {  // the wrist: this bone is the metacarpal
        at_carpal = true;
        break;
      }
      if (next_long.size() != 1) break;
      d.bones.push_back(next_long[0]);
      seen.insert(next_long[0]);
    }
    if (!at_carpal)
      throw InputError(source, "bones " + labels_of(bones, d.bones),
                       "a chain of long bones that ends on a carpal (a compact bone); give their names with --names",
                       "it does not reach one" + fused_bones_hint(bones.size()));
    if (d.bones.size() == 4)
      fingers.push_back(d);
    else if (d.bones.size() == 3)
      thumbs.push_back(d);
    else
      throw InputError(source, "bones " + labels_of(bones, d.bones), "chains of 4 bones (a finger) or 3 (the thumb); give their names with --names",
                       "a chain of " + std::to_string(d.bones.size()) + fused_bones_hint(bones.size()));
  }
  if (fingers.size() != 4 || thumbs.size() != 1) {
    std::vector<std::size_t> all;
    for (const auto* set : {&fingers, &thumbs})
      for (const auto& d : *set) all.insert(all.end(), d.bones.begin(), d.bones.end());
    throw InputError(source, "bones " + labels_of(bones, all), "four finger chains and one thumb chain; give their names with --names",
                     std::to_string(fingers.size()) + " and " + std::to_string(thumbs.size()) + fused_bones_hint(bones.size()));
  }
  // Index to little: by the metacarpals' distance from the thumb's.
  const V thumb = bones[thumbs[0].bones.back()].centroid;
  std::sort(fingers.begin(), fingers.end(), [&](const Digit& a, const Digit& b) {
    return (bones[a.bones.back()].centroid - thumb).norm() < (bones[b.bones.back()].centroid - thumb).norm();
  });
  fingers.push_back(thumbs[0]);
  return fingers;
}

// The digits from names: the groups' own (or the user's), when they name every digit bone.
std::vector<Digit> named_digits(const std::vector<BoneShape>& bones, const std::map<int, std::string>& names, const std::string& source) {
  std::map<std::string, std::size_t> by_name;
  for (std::size_t b = 0; b < bones.size(); ++b) {
    const auto it = names.find(bones[b].label);
    by_name[it != names.end() ? it->second : bones[b].group] = b;
  }
  std::vector<Digit> digits;
  for (int d = 0; d < 5; ++d) {
    Digit digit;
    const int n = d < 4 ? 4 : 3;
    for (int s = 0; s < n; ++s) {
      const std::string name = std::string(d < 4 ? kFingerBones[s] : kThumbBones[s]) + "_" + kDigits[d];
      const auto it = by_name.find(name);
      if (it == by_name.end()) return {};
      digit.bones.push_back(it->second);
    }
    digits.push_back(digit);
  }
  (void)source;
  return digits;
}

// The centre of the sphere through points (algebraic least squares: |x|^2 = 2 c.x + k), by its
// 4 x 4 normal equations. Fixed-size on purpose: a dynamic-size Eigen decomposition instantiated
// here (-march=native) is a weak symbol that libgmsh's own calls bind to, with another ABI, and
// gmsh's mesher then crashed (double free) in every executable that linked this file.
V sphere_centre(const std::vector<V>& points) {
  V mean = V::Zero();
  for (const V& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
  Eigen::Vector4d rhs = Eigen::Vector4d::Zero();
  for (const V& p : points) {
    const V q = p - mean;
    const Eigen::Vector4d row(2 * q.x(), 2 * q.y(), 2 * q.z(), 1);
    normal += row * row.transpose();
    rhs += row * q.squaredNorm();
  }
  const Eigen::Vector4d x = normal.fullPivLu().solve(rhs);
  return mean + x.head<3>();
}

// The centre of a bone's end cap (head: its distal end; base: its proximal end): the surface
// nodes within 0.8 of the shaft's radius of that end, fitted with a sphere.
V end_centre(const BoneShape& bone, const V& axis, bool head) {
  std::vector<double> t;
  for (const V& p : bone.surface) t.push_back((p - bone.centroid).dot(axis));
  const auto [tmin, tmax] = std::minmax_element(t.begin(), t.end());
  const double lo = *tmin, hi = *tmax, mid = 0.5 * (lo + hi), quarter = 0.25 * (hi - lo);
  std::vector<double> radial;
  for (std::size_t i = 0; i < t.size(); ++i)
    if (std::abs(t[i] - mid) < quarter) radial.push_back((bone.surface[i] - bone.centroid - t[i] * axis).norm());
  if (radial.empty()) radial.push_back(quarter);
  std::nth_element(radial.begin(), radial.begin() + static_cast<std::ptrdiff_t>(radial.size() / 2), radial.end());
  const double rho = radial[radial.size() / 2];
  std::vector<V> cap;
  for (std::size_t i = 0; i < t.size(); ++i)
    if (head ? t[i] >= hi - 0.8 * rho : t[i] <= lo + 0.8 * rho) cap.push_back(bone.surface[i]);
  return cap.size() >= 8 ? sphere_centre(cap) : bone.centroid + (head ? hi - rho : lo + rho) * axis;
}

// The palm: the plane of the finger metacarpals (centroids and head centres); its normal points to
// the side the digits' tips lie on (they flex towards the palm).
V palm_normal(const std::vector<BoneShape>& bones, const std::vector<Digit>& digits, const std::string& source) {
  std::vector<V> palm;
  for (int f = 0; f < 4; ++f) {
    const BoneShape& mc = bones[digits[f].bones.back()];
    palm.push_back(mc.centroid);
    palm.push_back(end_centre(mc, mc.axis, true));
  }
  V mean = V::Zero();
  for (const V& p : palm) mean += p / 8;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const V& p : palm) cov += (p - mean) * (p - mean).transpose();
  V normal = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
  double side = 0;
  for (const auto& d : digits) side += (bones[d.bones.front()].centroid - mean).dot(normal);
  if (std::abs(side) < 1e-3)
    throw InputError(source, "palm", "digits whose tips lie on one side of the metacarpals' plane (a hand flexed a little)",
                     "their tips lie in it: the palm cannot be told from the back");
  return side < 0 ? V(-normal) : normal;
}

}  // namespace

Skeleton extract_skeleton(const TetMesh& mesh, const SkeletonOptions& options) {
  const std::string& source = options.source;
  std::vector<BoneShape> bones = bone_shapes(mesh);
  if (bones.size() < 19) throw InputError(source, "bone groups", "at least the 19 bones of five digits", std::to_string(bones.size()));
  std::vector<std::vector<std::size_t>> near(bones.size());
  std::vector<std::vector<double>> gap(bones.size(), std::vector<double>(bones.size(), INFINITY));
  for (std::size_t a = 0; a < bones.size(); ++a)
    for (std::size_t b = a + 1; b < bones.size(); ++b) {
      gap[a][b] = gap[b][a] = surface_gap(bones[a], bones[b], 4 * options.neighbour_gap_m);
      if (gap[a][b] <= options.neighbour_gap_m) near[a].push_back(b), near[b].push_back(a);
    }
  std::vector<Digit> digits = named_digits(bones, options.names, source);
  const bool inferred = digits.empty();
  if (inferred) digits = chains(bones, near, gap, source);
  std::set<std::size_t> in_digit;
  for (const auto& d : digits) in_digit.insert(d.bones.begin(), d.bones.end());
  for (auto& d : digits) {  // a metacarpal's parent: the nearest bone outside the digits
    const std::size_t mc = d.bones.back();
    double best = INFINITY;
    for (std::size_t b = 0; b < bones.size(); ++b)
      if (!in_digit.count(b) && gap[mc][b] < best) best = gap[mc][b], d.carpal = b;
    if (!std::isfinite(best)) throw InputError(source, "bone " + labels_of(bones, {mc}), "a carpal within reach of the metacarpal", "none");
  }
  // Long axes point away from the parent.
  for (auto& d : digits)
    for (std::size_t s = 0; s < d.bones.size(); ++s) {
      const std::size_t b = d.bones[s], parent = s + 1 < d.bones.size() ? d.bones[s + 1] : d.carpal;
      if (bones[b].axis.dot(bones[b].centroid - bones[parent].centroid) < 0) bones[b].axis = -bones[b].axis;
    }
  const V normal = palm_normal(bones, digits, source);
  Skeleton sk;
  sk.source = "tactus-mesh skeleton of " + source + (inferred ? " (bones named by their chains)" : " (bones named by their labels)");
  sk.palm_normal = arr(normal);
  std::map<std::size_t, std::string> name;
  std::map<std::size_t, std::string> parent;
  for (std::size_t b = 0; b < bones.size(); ++b) {
    const auto it = options.names.find(bones[b].label);
    name[b] = it != options.names.end() ? it->second : bones[b].group;
  }
  for (int d = 0; d < 5; ++d)
    for (std::size_t s = 0; s < digits[d].bones.size(); ++s) {
      const std::size_t b = digits[d].bones[s];
      name[b] = std::string(d < 4 ? kFingerBones[s] : kThumbBones[s]) + "_" + kDigits[d];
    }
  for (int d = 0; d < 5; ++d)
    for (std::size_t s = 0; s < digits[d].bones.size(); ++s) {
      const std::size_t b = digits[d].bones[s];
      const bool base = s + 1 == digits[d].bones.size();
      const std::size_t up = base ? digits[d].carpal : digits[d].bones[s + 1];
      parent[b] = name[up];
      const V axis = bones[b].axis;
      // The joint centre: the proximal bone's head; for a carpometacarpal joint, the metacarpal's base.
      const V centre = base ? end_centre(bones[b], axis, false) : end_centre(bones[up], bones[up].axis, true);
      const V flexion = axis.cross(normal).normalized();
      sk.joints.push_back({std::string(d < 4 ? kFingerJoints[s] : kThumbJoints[s]) + "_" + kDigits[d], name[up], name[b], arr(centre), arr(flexion),
                           arr(flexion.cross(axis).normalized())});
    }
  for (std::size_t b = 0; b < bones.size(); ++b) {
    const BoneShape& s = bones[b];
    double lo = INFINITY, hi = -INFINITY;
    for (const V& p : s.surface) lo = std::min(lo, (p - s.centroid).dot(s.axis)), hi = std::max(hi, (p - s.centroid).dot(s.axis));
    sk.bones.push_back({name[b], parent.count(b) ? parent[b] : std::string(), s.label, arr(s.centroid), arr(s.axis), hi - lo});
  }
  // Joints in the order of the bones they move, tip last (parents before children).
  std::sort(sk.joints.begin(), sk.joints.end(), [](const SkeletonJoint& a, const SkeletonJoint& b) { return a.name < b.name; });
  validate_skeleton(sk, source);
  log::info() << "skeleton: " << sk.bones.size() << " bones (" << sk.joints.size() << " joints), bones named "
              << (inferred ? "by their chains" : "by their labels");
  return sk;
}

std::map<int, std::string> read_bone_names(const std::filesystem::path& path) {
  const std::string file = path.string();
  require_regular_file(path, "a bone names file (.json)");
  std::ifstream in(path);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("labels") || !j["labels"].is_object())
    throw InputError(file, "labels", "a JSON object {\"labels\": {\"<label>\": \"<bone name>\"}}");
  std::map<int, std::string> names;
  for (const auto& [key, value] : j["labels"].items()) {
    int label = -1;
    try {
      std::size_t used = 0;
      label = std::stoi(key, &used);
      if (used != key.size()) label = -1;
    } catch (const std::exception&) {
    }
    if (label < contracts::kFirstBoneLabel || label > 255) throw InputError(file, "labels." + key, "a bone label (2-255)");
    if (!value.is_string() || value.get<std::string>().empty()) throw InputError(file, "labels." + key, "a bone name");
    names[label] = value.get<std::string>();
  }
  return names;
}

}  // namespace tactus::mesher
