// The skeleton file (skeleton.hpp): forward kinematics, validation, JSON.
#include "tactus/core/skeleton.hpp"

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"

namespace tactus {

const SkeletonBone* Skeleton::bone(const std::string& name) const {
  for (const auto& b : bones)
    if (b.name == name) return &b;
  return nullptr;
}

const SkeletonJoint* Skeleton::joint(const std::string& name) const {
  for (const auto& j : joints)
    if (j.name == name) return &j;
  return nullptr;
}

const SkeletonJoint* Skeleton::joint_into(const std::string& bone_name) const {
  for (const auto& j : joints)
    if (j.distal == bone_name) return &j;
  return nullptr;
}

Vec3 RigidTransform::turn(const Vec3& d) const {
  const auto& r = rotation;
  return {r[0] * d[0] + r[1] * d[1] + r[2] * d[2], r[3] * d[0] + r[4] * d[1] + r[5] * d[2], r[6] * d[0] + r[7] * d[1] + r[8] * d[2]};
}

Vec3 RigidTransform::apply(const Vec3& x) const { return turn(x) + translation; }

RigidTransform RigidTransform::then(const RigidTransform& next) const {
  RigidTransform out;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double s = 0;
      for (int k = 0; k < 3; ++k) s += next.rotation[3 * i + k] * rotation[3 * k + j];
      out.rotation[3 * i + j] = s;
    }
  out.translation = next.apply(translation);
  return out;
}

RigidTransform rotation_about(const Vec3& centre, const Vec3& axis, double angle) {
  // Rodrigues: R = cos t I + sin t [a]x + (1 - cos t) a a^T, for a unit axis a.
  const double c = std::cos(angle), s = std::sin(angle), v = 1 - c;
  const double x = axis[0], y = axis[1], z = axis[2];
  RigidTransform t;
  t.rotation = {c + v * x * x,     v * x * y - s * z, v * x * z + s * y,  //
                v * x * y + s * z, c + v * y * y,     v * y * z - s * x,  //
                v * x * z - s * y, v * y * z + s * x, c + v * z * z};
  t.translation = centre - t.turn(centre);
  return t;
}

namespace {

// Bones in an order where every parent comes before its children.
std::vector<std::size_t> parents_first(const Skeleton& sk) {
  std::map<std::string, std::size_t> index;
  for (std::size_t b = 0; b < sk.bones.size(); ++b) index[sk.bones[b].name] = b;
  std::vector<std::size_t> order;
  std::vector<int> state(sk.bones.size(), 0);  // 0 new, 1 on the path, 2 placed
  for (std::size_t start = 0; start < sk.bones.size(); ++start) {
    std::vector<std::size_t> path;
    std::size_t b = start;
    while (state[b] == 0) {
      state[b] = 1;
      path.push_back(b);
      if (sk.bones[b].parent.empty()) break;
      b = index.at(sk.bones[b].parent);
    }
    if (state[b] == 1 && !sk.bones[b].parent.empty()) return {};  // a cycle
    for (auto it = path.rbegin(); it != path.rend(); ++it) {
      state[*it] = 2;
      order.push_back(*it);
    }
  }
  return order;
}

}  // namespace

std::vector<RigidTransform> forward_kinematics(const Skeleton& sk, const std::vector<JointAngles>& angles) {
  std::map<std::string, const JointAngles*> by_joint;
  for (const auto& a : angles) {
    if (!sk.joint(a.joint)) throw InputError("skeleton", "joint '" + a.joint + "'", "the name of a joint of the skeleton", "no such joint");
    by_joint[a.joint] = &a;
  }
  std::map<std::string, std::size_t> index;
  for (std::size_t b = 0; b < sk.bones.size(); ++b) index[sk.bones[b].name] = b;
  std::vector<RigidTransform> placed(sk.bones.size());
  for (std::size_t b : parents_first(sk)) {
    const SkeletonBone& bone = sk.bones[b];
    if (bone.parent.empty()) continue;  // a root stays where it is
    const SkeletonJoint* j = sk.joint_into(bone.name);
    if (!j) throw InputError("skeleton", "bone '" + bone.name + "'", "a joint into it from its parent '" + bone.parent + "'", "none");
    RigidTransform local;
    if (const auto it = by_joint.find(j->name); it != by_joint.end())
      local =
          rotation_about(j->centre, j->flexion_axis, it->second->flexion).then(rotation_about(j->centre, j->abduction_axis, it->second->abduction));
    placed[b] = local.then(placed[index.at(bone.parent)]);
  }
  return placed;
}

Vec3 PalmFrame::point(const Vec3& l) const { return origin + l[0] * across + l[1] * along + l[2] * normal; }

PalmFrame palm_frame(const Skeleton& s, const std::string& file) {
  PalmFrame f;
  f.normal = s.palm_normal;
  Vec3 axis{0, 0, 0};
  int n = 0;
  for (const SkeletonJoint& j : s.joints) {
    if (j.name.rfind("mcp_", 0) != 0 || j.name == "mcp_thumb") continue;
    const SkeletonBone* metacarpal = s.bone(j.proximal);
    f.origin = f.origin + j.centre;
    if (metacarpal) axis = axis + metacarpal->long_axis;
    ++n;
  }
  if (n == 0) throw InputError(file, "joints", "the fingers' MCP joints (mcp_index, mcp_middle, ...) for the palm frame", "none");
  f.origin = (1.0 / n) * f.origin;
  axis = axis - dot(axis, f.normal) * f.normal;
  if (!(norm(axis) > 0)) throw InputError(file, "bones", "metacarpals along the palm (not along its normal) for the palm frame");
  f.along = (1.0 / norm(axis)) * axis;
  f.across = cross(f.along, f.normal);
  return f;
}

void validate_skeleton(const Skeleton& sk, const std::string& file) {
  std::set<std::string> names;
  for (const auto& b : sk.bones) {
    if (b.name.empty() || !names.insert(b.name).second)
      throw InputError(file, "bones", "unique, non-empty bone names", "'" + b.name + "' twice or empty");
  }
  for (const auto& b : sk.bones)
    if (!b.parent.empty() && !names.count(b.parent))
      throw InputError(file, "bone '" + b.name + "'", "a parent that is a bone of the skeleton", "parent '" + b.parent + "'");
  std::set<std::string> joint_names, entered;
  auto unit = [](const Vec3& v) { return std::abs(norm(v) - 1) < 1e-6; };
  for (const auto& j : sk.joints) {
    if (j.name.empty() || !joint_names.insert(j.name).second)
      throw InputError(file, "joints", "unique, non-empty joint names", "'" + j.name + "' twice or empty");
    const SkeletonBone* distal = sk.bone(j.distal);
    if (!sk.bone(j.proximal) || !distal)
      throw InputError(file, "joint '" + j.name + "'", "proximal and distal bones of the skeleton", "'" + j.proximal + "' and '" + j.distal + "'");
    if (distal->parent != j.proximal)
      throw InputError(file, "joint '" + j.name + "'", "a distal bone whose parent is its proximal bone",
                       "'" + j.distal + "' has parent '" + distal->parent + "', not '" + j.proximal + "'");
    if (!entered.insert(j.distal).second)
      throw InputError(file, "joint '" + j.name + "'", "one joint into each bone", "a second joint into '" + j.distal + "'");
    if (!unit(j.flexion_axis) || !unit(j.abduction_axis) || std::abs(dot(j.flexion_axis, j.abduction_axis)) > 1e-6)
      throw InputError(file, "joint '" + j.name + "'", "unit, orthogonal flexion and abduction axes");
  }
  for (const auto& b : sk.bones)
    if (!b.parent.empty() && !entered.count(b.name))
      throw InputError(file, "bone '" + b.name + "'", "a joint into it from its parent '" + b.parent + "'", "none");
  if (parents_first(sk).size() != sk.bones.size()) throw InputError(file, "bones", "parents that lead to a root", "a cycle");
}

namespace {

nlohmann::json vec(const Vec3& v) { return nlohmann::json::array({v[0], v[1], v[2]}); }

Vec3 vec_of(const nlohmann::json& j, const std::string& file, const std::string& field) {
  if (!j.is_array() || j.size() != 3) throw InputError(file, field, "three numbers");
  Vec3 v{};
  for (int a = 0; a < 3; ++a) {
    if (!j[a].is_number() || !std::isfinite(j[a].get<double>())) throw InputError(file, field, "three finite numbers");
    v[a] = j[a].get<double>();
  }
  return v;
}

std::string text_of(const nlohmann::json& j, const char* key, const std::string& file, const std::string& field) {
  if (!j.contains(key) || !j[key].is_string()) throw InputError(file, field + "." + key, "a string");
  return j[key].get<std::string>();
}

}  // namespace

std::string skeleton_json(const Skeleton& sk) {
  nlohmann::json j;
  j["format"] = "tactus skeleton 1";
  j["units"] = "m";
  j["source"] = sk.source;
  j["conventions"] =
      "joint centre: the proximal bone's head centre; flexion axis a = d x n / |d x n| (d the distal bone's long axis, n the palm normal, out of "
      "the palm): positive flexion turns towards the palm; abduction axis: n orthogonal to a";
  j["palm_normal"] = vec(sk.palm_normal);
  j["bones"] = nlohmann::json::array();
  for (const auto& b : sk.bones)
    j["bones"].push_back({{"name", b.name},
                          {"parent", b.parent.empty() ? nlohmann::json(nullptr) : nlohmann::json(b.parent)},
                          {"label", b.label},
                          {"centroid", vec(b.centroid)},
                          {"long_axis", vec(b.long_axis)},
                          {"length", b.length}});
  j["joints"] = nlohmann::json::array();
  for (const auto& x : sk.joints)
    j["joints"].push_back({{"name", x.name},
                           {"proximal", x.proximal},
                           {"distal", x.distal},
                           {"centre", vec(x.centre)},
                           {"flexion_axis", vec(x.flexion_axis)},
                           {"abduction_axis", vec(x.abduction_axis)}});
  return j.dump(2) + '\n';
}

void write_skeleton(const std::filesystem::path& file, const Skeleton& sk) { write_file(file, skeleton_json(sk)); }

Skeleton read_skeleton(const std::filesystem::path& path) {
  const std::string file = path.string();
  require_regular_file(path, "a skeleton (.json)");
  std::ifstream in(path);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) throw InputError(file, "(whole file)", "a JSON object (tactus skeleton)");
  if (j.value("format", "") != "tactus skeleton 1") throw InputError(file, "format", "\"tactus skeleton 1\"");
  if (j.value("units", "") != "m") throw InputError(file, "units", "\"m\"");
  Skeleton sk;
  sk.source = j.value("source", "");
  sk.palm_normal = vec_of(j.value("palm_normal", nlohmann::json()), file, "palm_normal");
  if (!j.contains("bones") || !j["bones"].is_array()) throw InputError(file, "bones", "an array");
  for (const auto& b : j["bones"]) {
    SkeletonBone bone;
    bone.name = text_of(b, "name", file, "bones[]");
    const std::string field = "bone '" + bone.name + "'";
    if (b.contains("parent") && !b["parent"].is_null()) bone.parent = text_of(b, "parent", file, field);
    bone.label = b.value("label", -1);
    bone.centroid = vec_of(b.value("centroid", nlohmann::json()), file, field + ".centroid");
    bone.long_axis = vec_of(b.value("long_axis", nlohmann::json()), file, field + ".long_axis");
    bone.length = b.value("length", 0.0);
    sk.bones.push_back(bone);
  }
  if (!j.contains("joints") || !j["joints"].is_array()) throw InputError(file, "joints", "an array");
  for (const auto& x : j["joints"]) {
    SkeletonJoint joint;
    joint.name = text_of(x, "name", file, "joints[]");
    const std::string field = "joint '" + joint.name + "'";
    joint.proximal = text_of(x, "proximal", file, field);
    joint.distal = text_of(x, "distal", file, field);
    joint.centre = vec_of(x.value("centre", nlohmann::json()), file, field + ".centre");
    joint.flexion_axis = vec_of(x.value("flexion_axis", nlohmann::json()), file, field + ".flexion_axis");
    joint.abduction_axis = vec_of(x.value("abduction_axis", nlohmann::json()), file, field + ".abduction_axis");
    sk.joints.push_back(joint);
  }
  validate_skeleton(sk, file);
  return sk;
}

}  // namespace tactus
