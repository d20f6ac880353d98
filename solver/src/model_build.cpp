// Building the model from a scenario, in named steps: read and place each body, make the
// material blocks (with the laws' per-element data), apply the boundaries, then the element
// geometry, lumped mass, locality order and contact surfaces.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <numeric>
#include <optional>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"
#include "tactus/solver/model_build.hpp"

namespace tactus::solver {

void compute_element_geometry(Model& m);  // model.cpp
void lump_mass(Model& m);

namespace {

// Two nodes of one mesh at the same place, both used by tets: the mesh is cracked there (the
// interface was meshed twice instead of sharing its nodes), and the two sides would separate
// under load without any error. Found by sorting along x and comparing neighbours within 1e-9 of
// the mesh size.
void check_no_duplicate_nodes(const TetMesh& mesh, const std::string& file) {
  std::vector<char> used(mesh.nodes.size(), 0);
  for (const auto& t : mesh.tets)
    for (int v : t) used[static_cast<std::size_t>(v)] = 1;
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < mesh.nodes.size(); ++i)
    if (used[i]) {
      order.push_back(i);
      for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], mesh.nodes[i][c]), hi[c] = std::max(hi[c], mesh.nodes[i][c]);
    }
  const double tol = 1e-9 * std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-300});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return mesh.nodes[a][0] < mesh.nodes[b][0]; });
  for (std::size_t k = 0; k < order.size(); ++k)
    for (std::size_t l = k + 1; l < order.size() && mesh.nodes[order[l]][0] - mesh.nodes[order[k]][0] <= tol; ++l) {
      const Vec3 &a = mesh.nodes[order[k]], &b = mesh.nodes[order[l]];
      if (std::abs(a[1] - b[1]) > tol || std::abs(a[2] - b[2]) > tol) continue;
      std::ostringstream f;
      f << "nodes " << std::min(order[k], order[l]) + 1 << " and " << std::max(order[k], order[l]) + 1 << " at (" << a[0] << ", " << a[1] << ", "
        << a[2] << ") both belong to tets: a crack";
      throw InputError(file, "$Nodes", "a conforming mesh, each point one node (merge the duplicates, e.g. gmsh's Coherence)", f.str());
    }
}

// The cell fields of a body's element-data file (bodies.fibres: a .vtu of the body's mesh),
// matched to the mesh's tets by their node sets, so the file's element order does not matter.
// Returns, per tet, the values of `fields` (name, components) in order.
std::vector<std::vector<double>> read_element_fields(const std::filesystem::path& file, const TetMesh& mesh, const std::string& key,
                                                     const std::vector<std::pair<std::string, int>>& fields) {
  const VtuContents vtu = read_vtu(file);
  if (vtu.mesh.nodes.size() != mesh.nodes.size() || vtu.mesh.tets.size() != mesh.tets.size())
    throw InputError(file.string(), key,
                     "a .vtu of the body's mesh (" + std::to_string(mesh.nodes.size()) + " nodes, " + std::to_string(mesh.tets.size()) + " tets)",
                     std::to_string(vtu.mesh.nodes.size()) + " nodes, " + std::to_string(vtu.mesh.tets.size()) + " tets");
  std::vector<const MeshField*> found;
  for (const auto& [name, components] : fields) {
    const MeshField* f = vtu.cell_field(name);
    if (!f || f->components != components)
      throw InputError(file.string(), name, "cell data with " + std::to_string(components) + " components per tet", f ? "other" : "missing");
    found.push_back(f);
  }
  std::map<std::array<int, 4>, std::size_t> index;
  for (std::size_t e = 0; e < vtu.mesh.tets.size(); ++e) {
    auto key4 = vtu.mesh.tets[e];
    std::sort(key4.begin(), key4.end());
    index[key4] = e;
  }
  std::vector<std::vector<double>> out(mesh.tets.size());
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    auto key4 = mesh.tets[e];
    std::sort(key4.begin(), key4.end());
    auto it = index.find(key4);
    if (it == index.end())
      throw InputError(file.string(), "tet " + std::to_string(e + 1), "the same tets (node numbers) as the body's mesh", "no matching tet");
    for (std::size_t k = 0; k < fields.size(); ++k) {
      const auto n = static_cast<std::size_t>(fields[k].second);
      out[e].insert(out[e].end(), found[k]->values.begin() + static_cast<std::ptrdiff_t>(n * it->second),
                    found[k]->values.begin() + static_cast<std::ptrdiff_t>(n * (it->second + 1)));
    }
  }
  return out;
}

// Every law's element fields, for a body's element-data file (the union, in registration order).
std::vector<std::pair<std::string, int>> all_element_fields(const Scenario& sc, const BodySpec& body) {
  std::vector<std::pair<std::string, int>> fields;
  for (const auto& [group, mat] : body.materials)
    for (const auto& f : material_type(sc.materials.at(mat).type).element_fields)
      if (std::find(fields.begin(), fields.end(), f) == fields.end()) fields.push_back(f);
  return fields;
}

// R a, R given by its rows (a direction: fibres).
Vec3 rotated(const BodySpec& body, const Vec3& a) {
  Vec3 out{};
  for (int i = 0; i < 3; ++i) out[i] = body.rotation[i][0] * a[0] + body.rotation[i][1] * a[1] + body.rotation[i][2] * a[2];
  return out;
}

// x -> R (x - about) + about (a point).
Vec3 rotate(const BodySpec& body, const Vec3& x) {
  Vec3 out = rotated(body, {x[0] - body.rotate_about[0], x[1] - body.rotate_about[1], x[2] - body.rotate_about[2]});
  for (int i = 0; i < 3; ++i) out[i] += body.rotate_about[i];
  return out;
}

// Scale, rotate, translate, then `against`: moved along one axis to leave the gap to an earlier
// body. Returns what `against` moved it by.
Vec3 place_body(const Scenario& sc, std::size_t bi, const Model& m, TetMesh& mesh) {
  const BodySpec& body = sc.bodies[bi];
  for (auto& x : mesh.nodes) {
    for (int c = 0; c < 3; ++c) x[c] *= body.scale;
    if (body.rotated) x = rotate(body, x);
    for (int c = 0; c < 3; ++c) x[c] += body.translate[c];
  }
  if (body.against.empty()) return {0, 0, 0};
  const int a = body.against_axis;
  std::size_t other = 0;
  while (sc.bodies[other].name != body.against) ++other;
  double other_lo = 1e300, other_hi = -1e300, lo = 1e300, hi = -1e300;
  for (std::size_t i = m.bodies[other].node_begin; i < m.bodies[other].node_end; ++i)
    other_lo = std::min(other_lo, m.input_mesh.nodes[i][a]), other_hi = std::max(other_hi, m.input_mesh.nodes[i][a]);
  for (const auto& x : mesh.nodes) lo = std::min(lo, x[a]), hi = std::max(hi, x[a]);
  const double shift = body.against_side > 0 ? other_hi + body.against_gap - lo : other_lo - body.against_gap - hi;
  for (auto& x : mesh.nodes) x[a] += shift;
  log::verbose() << "bodies[" << bi << "] '" << body.name << "' moved by " << shift << " m along "
                 << "xyz"[a] << " to lie " << body.against_gap << " m from '" << body.against << "'";
  Vec3 moved{0, 0, 0};
  moved[static_cast<std::size_t>(a)] = shift;
  return moved;
}

// What the blocks need to know about every input tet.
struct TetAssignment {
  std::vector<std::string> material;                     // material name
  std::vector<std::optional<std::vector<double>>> data;  // element-field values from the body's file
};

// Reads body bi, places it and appends it to the model's input mesh (its groups keep their file
// tags; the body is recorded by range), assigning a material to each of its tets.
void append_body(const Scenario& sc, std::size_t bi, Model& m, TetAssignment& tets) {
  const BodySpec& body = sc.bodies[bi];
  const std::string key = "bodies[" + std::to_string(bi) + "]";
  TetMesh mesh = read_msh(body.mesh);
  check_no_duplicate_nodes(mesh, body.mesh.string());
  const auto fields = all_element_fields(sc, body);
  std::vector<std::vector<double>> field_values;
  if (!body.fibres.empty()) field_values = read_element_fields(body.fibres, mesh, key + ".fibres", fields);
  const Vec3 shift = place_body(sc, bi, m, mesh);
  TetMesh& all = m.input_mesh;
  const std::size_t node0 = all.nodes.size();
  m.bodies.push_back({body.name, node0, node0 + mesh.nodes.size(), all.tets.size(), all.tets.size() + mesh.tets.size(), all.triangles.size(),
                      all.triangles.size() + mesh.triangles.size(), all.groups.size(), all.groups.size() + mesh.groups.size()});
  m.bodies.back().against_shift = shift;
  all.groups.insert(all.groups.end(), mesh.groups.begin(), mesh.groups.end());
  all.nodes.insert(all.nodes.end(), mesh.nodes.begin(), mesh.nodes.end());
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    std::array<int, 4> t = mesh.tets[e];
    for (int& v : t) v += static_cast<int>(node0);
    all.tets.push_back(t);
    all.tet_group.push_back(mesh.tet_group[e]);
    const std::string& gname = mesh.find_group(3, mesh.tet_group[e])->name;
    auto it = body.materials.find(gname);
    if (it == body.materials.end()) it = body.materials.find("*");
    if (it == body.materials.end()) {
      std::string groups;
      for (const auto& g : mesh.groups)
        if (g.dim == 3) groups += (groups.empty() ? "" : ", ") + g.name;
      throw InputError(
          sc.file.string(), key + ".materials",
          "a material for physical volume '" + gname + "' of " + body.mesh.string() + " (its volume groups: " + groups + "; or a \"*\" entry)",
          "none");
    }
    tets.material.push_back(it->second);
    if (field_values.empty())
      tets.data.emplace_back();
    else
      tets.data.emplace_back(std::move(field_values[e]));
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    std::array<int, 3> tri = mesh.triangles[t];
    for (int& v : tri) v += static_cast<int>(node0);
    all.triangles.push_back(tri);
    all.triangle_group.push_back(mesh.triangle_group[t]);
  }
  for (const auto& [gname, mat] : body.materials)
    if (gname != "*" && !mesh.find_group(3, gname))
      throw InputError(sc.file.string(), key + ".materials." + gname, "the name of a physical volume group in " + body.mesh.string(),
                       "no such group");
}

// The law's element data of a tet in a rotated body, rotated with it: every 3-component element
// field (hgo's fibre directions) is a direction in the reference frame.
void rotate_element_data(const MaterialType& type, const BodySpec& body, double* data, const std::string& key) {
  if (!type.element_data_is_directions)
    throw InputError("scenario", key + ".rotate_axis", "a body whose materials' element data can rotate (" + type.name + "'s cannot)", "a rotation");
  for (std::size_t k = 0; k + 2 < type.element_data_size; k += 3) {
    const Vec3 r = rotated(body, {data[k], data[k + 1], data[k + 2]});
    std::copy(r.begin(), r.end(), data + k);
  }
}

// The skeleton body's joint gaps (MaterialBlock::joint_gap), on input numbering: its deformable
// tets whose four nodes all lie on its rigid tets, or three of them on the tets of two different
// bones (the bones' physical groups).
std::vector<char> joint_gap_tets(const Scenario& sc, const Model& m, const TetAssignment& tets) {
  std::vector<char> gap(m.num_elements, 0);
  if (!sc.skeleton) return gap;
  auto rigid = [&](std::size_t e) {
    const auto it = sc.materials.find(tets.material[e]);
    return it != sc.materials.end() && it->second.type == "rigid";
  };
  for (const BodyRange& body : m.bodies) {
    if (body.name != sc.skeleton->body) continue;
    constexpr int kFree = -1;
    std::vector<int> bone_of(m.num_nodes, kFree);  // the group of a rigid tet the node lies on
    for (std::size_t e = body.tet_begin; e < body.tet_end; ++e)
      if (rigid(e))
        for (int v : m.input_mesh.tets[e]) bone_of[static_cast<std::size_t>(v)] = m.input_mesh.tet_group[e];
    for (std::size_t e = body.tet_begin; e < body.tet_end; ++e) {
      if (rigid(e)) continue;
      int on_bones = 0, first = kFree;
      bool two_bones = false;
      for (int v : m.input_mesh.tets[e]) {
        const int bone = bone_of[static_cast<std::size_t>(v)];
        if (bone == kFree) continue;
        ++on_bones;
        two_bones = two_bones || (first != kFree && bone != first);
        first = first == kFree ? bone : first;
      }
      gap[e] = on_bones == 4 || (on_bones == 3 && two_bones);
    }
  }
  return gap;
}

// One block per material (in the scenario's order), its elements in input order, then the
// material's joint gaps as a block of their own; a law's element data from the bodies' files where
// given, else the material's constants.
std::vector<std::size_t> make_blocks(const Scenario& sc, Model& m, const TetAssignment& tets) {
  std::vector<std::size_t> order;
  const std::vector<char> gap = joint_gap_tets(sc, m, tets);
  for (const auto& [name, inst] : sc.materials)
    for (const bool in_gap : {false, true}) {
      MaterialBlock b;
      b.name = in_gap ? name + "_joint_gap" : name;
      b.joint_gap = in_gap;
      const auto law = sc.laws.find(name);
      b.material = law != sc.laws.end() ? law->second : Material::make(inst.type, inst.values, "materials." + name);
      b.begin = order.size();
      for (std::size_t e = 0; e < m.num_elements; ++e)
        if (tets.material[e] == name && (gap[e] != 0) == in_gap) order.push_back(e);
      b.end = order.size();
      if (b.end == b.begin) continue;
      if (in_gap)
        log::info() << "joint gaps: " << b.end - b.begin << " tets of '" << name << "' lie on the bones of body '" << sc.skeleton->body
                    << "' (placed by the joints; no stress, no step of their own): material '" << b.name << "'";
      const MaterialType& type = b.material.type();
      const std::size_t n = type.element_data_size;
      bool from_files = false;
      for (std::size_t k = b.begin; k < b.end && n > 0; ++k) {
        if (tets.data[order[k]] || sc.bodies[m.body_of_tet(order[k])].rotated)
          from_files = true;
        else if (b.material.needs_element_data()) {
          std::string keys;
          for (const ValueSpec& s : type.parameters.keys)
            if (s.type == ValueType::vec3_list) keys += (keys.empty() ? "" : ", ") + s.key;
          throw InputError(sc.file.string(), "materials." + name + "." + keys,
                           "element data for " + type.name + ": " + keys + " here, or a per-element `fibres` file on body '" +
                               sc.bodies[m.body_of_tet(order[k])].name + "'",
                           "none");
        }
      }
      if (from_files) {
        b.element_data.resize(n * (b.end - b.begin));
        for (std::size_t k = b.begin; k < b.end; ++k) {
          double* out = &b.element_data[n * (k - b.begin)];
          const std::size_t body = m.body_of_tet(order[k]);
          if (const auto& d = tets.data[order[k]])
            type.element_data_from_fields(d->data(), out,
                                          sc.bodies[body].fibres.string() + ": tet " + std::to_string(order[k] - m.bodies[body].tet_begin + 1));
          else
            std::copy(b.material.constant_element_data().begin(), b.material.constant_element_data().end(), out);
          if (sc.bodies[body].rotated) rotate_element_data(type, sc.bodies[body], out, "bodies[" + std::to_string(body) + "]");
        }
      }
      m.blocks.push_back(std::move(b));
    }
  return order;
}

// The nodes a [[boundary]] entry selects (input numbering), by physical group or box.
std::vector<char> boundary_selection(const Scenario& sc, const Model& m, std::size_t k) {
  const BoundarySpec& bc = sc.boundaries[k];
  const std::string key = "boundary[" + std::to_string(k) + "]";
  std::size_t bi = 0;
  while (sc.bodies[bi].name != bc.body) ++bi;
  const BodyRange& range = m.bodies[bi];
  std::vector<char> selected(m.num_nodes, 0);
  if (!bc.group.empty()) {
    bool found = false;  // a name may be both a surface and a volume group: both select
    for (const PhysicalGroup* g : m.body_groups(bi)) {
      if (g->name != bc.group) continue;
      found = true;
      if (g->dim == 2) {
        for (std::size_t t = range.triangle_begin; t < range.triangle_end; ++t)
          if (m.input_mesh.triangle_group[t] == g->tag)
            for (int v : m.input_mesh.triangles[t]) selected[static_cast<std::size_t>(v)] = 1;
      } else {
        for (std::size_t t = range.tet_begin; t < range.tet_end; ++t)
          if (m.input_mesh.tet_group[t] == g->tag)
            for (int v : m.input_mesh.tets[t]) selected[static_cast<std::size_t>(v)] = 1;
      }
    }
    if (!found) {
      std::string groups;
      for (const PhysicalGroup* pg : m.body_groups(bi)) groups += (groups.empty() ? "" : ", ") + pg->name;
      throw InputError(sc.file.string(), key + ".group", "a physical group of body '" + bc.body + "' (" + groups + ")", "\"" + bc.group + "\"");
    }
  } else {
    const auto& box = *bc.box;
    for (std::size_t i = range.node_begin; i < range.node_end; ++i) {
      bool in = true;
      for (int c = 0; c < 3; ++c) in = in && m.X[3 * i + c] >= box[0][c] && m.X[3 * i + c] <= box[1][c];
      selected[i] = in;
    }
  }
  return selected;
}

// The index of a [curves] name in m.curves (-1 for none).
std::int32_t curve_index(const Model& m, const std::string& name) {
  for (std::size_t k = 0; k < m.curves.size(); ++k)
    if (m.curves[k].name == name) return static_cast<std::int32_t>(k);
  return -1;
}

// InputError when dof c of node i, which boundary k is about to constrain, is already constrained
// otherwise by an earlier boundary (fixed there, moving here: one of the two would be ignored).
void conflicting_constraint(const Scenario& sc, const Model& m, std::size_t k, std::size_t i, int c) {
  const std::int32_t j = m.constraint_boundary[3 * i + static_cast<std::size_t>(c)];
  if (j < 0) return;
  const BoundarySpec& a = sc.boundaries[static_cast<std::size_t>(j)];
  const BoundarySpec& b = sc.boundaries[k];
  const bool same =
      a.type == b.type && a.curve == b.curve &&
      (a.type == BoundaryType::fixed || (a.type == BoundaryType::velocity ? a.velocity[c] == b.velocity[c] : a.displacement[c] == b.displacement[c]));
  if (same) return;
  const std::size_t body = m.body_of_node(i);
  const std::string axis(1, static_cast<char>('x' + c));
  throw InputError(sc.file.string(), "boundary[" + std::to_string(k) + "]",
                   "nodes not constrained otherwise by an earlier [[boundary]] (one of the two would be ignored)",
                   "node " + std::to_string(i - m.bodies[body].node_begin + 1) + " of body '" + m.bodies[body].name + "' is " +
                       boundary_type_name(a.type) + " in " + axis + " by boundary[" + std::to_string(j) + "] and " + boundary_type_name(b.type) +
                       " by this one");
}

void apply_boundaries(const Scenario& sc, Model& m) {
  m.constrained.assign(3 * m.num_nodes, 0);
  m.constraint_velocity.assign(3 * m.num_nodes, 0.0);
  m.constraint_curve.assign(3 * m.num_nodes, -1);
  m.constraint_boundary.assign(3 * m.num_nodes, -1);
  for (std::size_t k = 0; k < sc.boundaries.size(); ++k) {
    const BoundarySpec& bc = sc.boundaries[k];
    const std::vector<char> selected = boundary_selection(sc, m, k);
    m.boundaries.push_back({bc.name.empty() ? "boundary" + std::to_string(k) : bc.name, bc.moment_about});
    const std::int32_t curve = curve_index(m, bc.curve);
    std::size_t count = 0;
    for (std::size_t i = 0; i < m.num_nodes; ++i) {
      if (!selected[i]) continue;
      ++count;
      for (int c = 0; c < 3; ++c)
        if (bc.components[c]) {
          conflicting_constraint(sc, m, k, i, c);
          m.constrained[3 * i + c] = bc.type == BoundaryType::displacement ? 2 : 1;
          m.constraint_velocity[3 * i + c] = bc.type == BoundaryType::velocity       ? bc.velocity[c]
                                             : bc.type == BoundaryType::displacement ? bc.displacement[c]
                                                                                     : 0.0;
          m.constraint_curve[3 * i + c] = bc.type == BoundaryType::fixed ? -1 : curve;
          m.constraint_boundary[3 * i + c] = static_cast<std::int32_t>(k);
        }
    }
    const std::string key = "boundary[" + std::to_string(k) + "]";
    if (count == 0) throw InputError(sc.file.string(), key, "a selection containing nodes of body '" + bc.body + "'", "no node");
    log::verbose() << key << ": " << count << " nodes " << boundary_type_name(bc.type);
  }
}

// [[load]] pressures: the group's triangles, oriented out of the body (outward_triangles), in
// internal numbering.
void add_pressure_loads(const Scenario& sc, Model& m) {
  for (std::size_t k = 0; k < sc.loads.size(); ++k) {
    const LoadSpec& spec = sc.loads[k];
    const std::string key = "load[" + std::to_string(k) + "]";
    std::size_t bi = 0;
    while (sc.bodies[bi].name != spec.body) ++bi;
    const PhysicalGroup* g = m.body_group(bi, 2, spec.group);
    if (!g) {
      std::string groups;
      for (const PhysicalGroup* pg : m.body_groups(bi))
        if (pg->dim == 2) groups += (groups.empty() ? "" : ", ") + pg->name;
      throw InputError(sc.file.string(), key + ".group", "a physical surface group of body '" + spec.body + "' (" + groups + ")",
                       "\"" + spec.group + "\"");
    }
    std::vector<int> owners;
    PressureLoad load;
    load.name = key + " " + spec.body + "/" + spec.group;
    load.pressure = spec.pressure;
    load.curve = curve_index(m, spec.curve);
    load.triangles = outward_triangles(m, surface_triangles(m, bi, g->tag), owners);
    const auto bad = static_cast<std::size_t>(std::count_if(owners.begin(), owners.end(), [](int n) { return n != 1; }));
    if (bad > 0)
      throw InputError(sc.file.string(), key + ".group",
                       "a surface on the boundary of body '" + spec.body + "' (each triangle the face of exactly one tet)",
                       std::to_string(bad) + " of its " + std::to_string(owners.size()) + " triangles are not");
    log::verbose() << key << ": pressure on " << owners.size() << " triangles of " << spec.body << "/" << spec.group;
    m.pressure_loads.push_back(std::move(load));
  }
}

// The bodies' spins (initial_angular_velocity, about each body's centre of mass) and their rigid
// pieces' prescribed motion (rigid.hpp), on input numbering.
void add_rigid_motion(const Scenario& sc, Model& m) {
  for (std::size_t bi = 0; bi < sc.bodies.size(); ++bi) {
    const BodySpec& spec = sc.bodies[bi];
    BodyRange& body = m.bodies[bi];
    const std::string key = "bodies[" + std::to_string(bi) + "]";
    if (spec.rigid_guide) body.rigid_guide = (1.0 / norm(*spec.rigid_guide)) * *spec.rigid_guide;
    if (spec.rigid_velocity) {
      // It moves the body's rigid pieces: on a body without one it would be silently ignored.
      std::string used;
      bool rigid = false;
      for (const auto& [group, material] : spec.materials) {
        const auto it = sc.materials.find(material);
        rigid = rigid || (it != sc.materials.end() && it->second.type == "rigid");
        used += (used.empty() ? "" : ", ") + material + (it != sc.materials.end() ? " (" + it->second.type + ")" : "");
      }
      if (!rigid)
        throw InputError(sc.file.string(), key + (spec.rigid_velocity ? ".rigid_velocity" : ".rigid_angular_velocity"),
                         "a body with rigid pieces (a material of type rigid) for the prescribed rigid motion to move",
                         "body '" + spec.name + "' has none: " + used);
      body.rigid_prescribed = true;
      body.rigid_velocity = *spec.rigid_velocity, body.rigid_angular_velocity = *spec.rigid_angular_velocity;
      body.rigid_curve = curve_index(m, spec.rigid_curve);
      if (!spec.rigid_curve.empty() && body.rigid_curve < 0)
        throw InputError(sc.file.string(), key + ".rigid_curve", "the name of a [curves] entry", "\"" + spec.rigid_curve + "\"");
    }
    const Vec3& w = spec.initial_angular_velocity;
    body.initial_angular_velocity = w;
    if (w[0] == 0 && w[1] == 0 && w[2] == 0) continue;
    double mass = 0;
    Vec3 c{0, 0, 0};
    for (std::size_t i = body.node_begin; i < body.node_end; ++i) {
      mass += m.mass[i];
      for (std::size_t d = 0; d < 3; ++d) c[d] += m.mass[i] * m.X[3 * i + d];
    }
    for (std::size_t d = 0; d < 3; ++d) c[d] /= mass;
    for (std::size_t i = body.node_begin; i < body.node_end; ++i) {
      const Vec3 r{m.X[3 * i] - c[0], m.X[3 * i + 1] - c[1], m.X[3 * i + 2] - c[2]};
      const Vec3 v = cross(w, r);
      for (std::size_t d = 0; d < 3; ++d) m.initial_velocity[3 * i + d] += v[d];
    }
  }
}

// The skeleton placed like its body (scale, rotation, translation, `against`), in radians.
Skeleton placed_skeleton(const Scenario& sc, std::size_t bi, const Model& m) {
  Skeleton sk = read_skeleton(sc.skeleton->file);
  const BodySpec& body = sc.bodies[bi];
  auto direction = [&](const Vec3& a) { return body.rotated ? rotated(body, a) : a; };
  auto point = [&](Vec3 x) {
    x = body.scale * x;
    if (body.rotated) x = rotate(body, x);
    return x + body.translate + m.bodies[bi].against_shift;
  };
  sk.palm_normal = direction(sk.palm_normal);
  for (SkeletonBone& b : sk.bones) b.centroid = point(b.centroid), b.long_axis = direction(b.long_axis), b.length *= body.scale;
  for (SkeletonJoint& j : sk.joints)
    j.centre = point(j.centre), j.flexion_axis = direction(j.flexion_axis), j.abduction_axis = direction(j.abduction_axis);
  return sk;
}

// [grasp].handle_centre: the handle's bounding box centred on that point of the palm frame, its
// longest side turned across the palm (the rotation that takes one to the other, Rodrigues).
void place_handle(const Scenario& sc, Model& m) {
  if (!sc.skeleton || !sc.grasp.on() || (!sc.grasp.handle_centre && !sc.grasp.handle_guided)) return;
  std::size_t hand = 0, handle = 0;
  while (sc.bodies[hand].name != sc.skeleton->body) ++hand;
  while (sc.bodies[handle].name != sc.grasp.handle) ++handle;
  const PalmFrame frame = palm_frame(placed_skeleton(sc, hand, m), sc.skeleton->file.string());
  if (sc.grasp.handle_guided) {
    const BodySpec& spec = sc.bodies[handle];
    if (spec.rigid_velocity || spec.rigid_guide)
      throw InputError(sc.file.string(), "grasp.handle_guided", "a free handle (no rigid_velocity or rigid_guide on body '" + spec.name + "')",
                       spec.rigid_velocity ? "a prescribed handle" : "a handle with its own rigid_guide");
    m.bodies[handle].rigid_guide = frame.normal;
    log::info() << "grasp: handle '" << sc.grasp.handle << "' on a rail along the palm's normal (" << frame.normal[0] << ", " << frame.normal[1]
                << ", " << frame.normal[2] << ")";
  }
  if (!sc.grasp.handle_centre) return;
  const BodyRange& body = m.bodies[handle];
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (std::size_t i = body.node_begin; i < body.node_end; ++i)
    for (std::size_t d = 0; d < 3; ++d) lo[d] = std::min(lo[d], m.input_mesh.nodes[i][d]), hi[d] = std::max(hi[d], m.input_mesh.nodes[i][d]);
  std::size_t longest = 0;
  for (std::size_t d = 1; d < 3; ++d)
    if (hi[d] - lo[d] > hi[longest] - lo[longest]) longest = d;
  Vec3 side{0, 0, 0};
  side[longest] = 1;
  const Vec3 centre = 0.5 * (lo + hi), target = frame.point(*sc.grasp.handle_centre);
  // R = cos t I + sin t [k]x + (1 - cos t) k k^T about k = side x across (a half turn about any
  // axis normal to `side` when they are opposite).
  Vec3 k = cross(side, frame.across);
  const double s = norm(k), c = dot(side, frame.across);
  if (s < 1e-12) k = cross(side, std::abs(side[0]) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0});
  k = (1.0 / norm(k)) * k;
  const double angle = std::atan2(s, c);
  for (std::size_t i = body.node_begin; i < body.node_end; ++i) {
    const Vec3 r = m.input_mesh.nodes[i] - centre;
    const Vec3 turned = std::cos(angle) * r + std::sin(angle) * cross(k, r) + (1 - std::cos(angle)) * dot(k, r) * k;
    m.input_mesh.nodes[i] = target + turned;
  }
  log::info() << "grasp: handle '" << sc.grasp.handle << "' centred at (" << target[0] << ", " << target[1] << ", " << target[2] << ") m, its "
              << "xyz"[longest] << " side across the palm";
}

// The point of triangle abc closest to p (Ericson, Real-Time Collision Detection, 5.1.5).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  const double denom = 1 / (va + vb + vc);
  return a + (vb * denom) * ab + (vc * denom) * ac;
}

// A grasp starts with the handle clear of the hand: a hand node inside the handle (its winding
// number over the handle's outward boundary faces above 1/2, Van Oosterom-Strackee solid angles)
// deeper than 1 % of the handle's smallest side would be pushed out at the recovery speed in the
// first steps, a jolt no grip force explains. Refused naming the key that placed the handle.
void refuse_handle_inside_hand(const Scenario& sc, const Model& m) {
  if (!sc.skeleton || !sc.grasp.on()) return;
  std::size_t hand = 0, handle = 0;
  while (sc.bodies[hand].name != sc.skeleton->body) ++hand;
  while (sc.bodies[handle].name != sc.grasp.handle) ++handle;
  const BodyRange &hb = m.bodies[handle], &kb = m.bodies[hand];
  const auto& X = m.input_mesh.nodes;
  std::map<std::array<int, 3>, std::array<int, 4>> faces;  // sorted face -> face as in the tet, opposite vertex
  for (std::size_t e = hb.tet_begin; e < hb.tet_end; ++e) {
    const auto& t = m.input_mesh.tets[e];
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> f{t[(k + 1) % 4], t[(k + 2) % 4], t[(k + 3) % 4]}, key = f;
      std::sort(key.begin(), key.end());
      if (!faces.erase(key)) faces[key] = {f[0], f[1], f[2], t[k]};
    }
  }
  std::vector<std::array<Vec3, 3>> outward;
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const auto& [key, f] : faces) {
    std::array<Vec3, 3> tri{X[f[0]], X[f[1]], X[f[2]]};
    if (dot(cross(tri[1] - tri[0], tri[2] - tri[0]), X[f[3]] - tri[0]) > 0) std::swap(tri[1], tri[2]);
    outward.push_back(tri);
    for (const Vec3& v : tri)
      for (std::size_t d = 0; d < 3; ++d) lo[d] = std::min(lo[d], v[d]), hi[d] = std::max(hi[d], v[d]);
  }
  const double tolerance = 0.01 * std::min({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  std::size_t inside = 0;
  double deepest = 0;
  Vec3 where{0, 0, 0};
  for (std::size_t i = kb.node_begin; i < kb.node_end; ++i) {
    const Vec3& p = X[i];
    if (p[0] < lo[0] || p[0] > hi[0] || p[1] < lo[1] || p[1] > hi[1] || p[2] < lo[2] || p[2] > hi[2]) continue;
    double solid_angle = 0, depth = 1e300;
    for (const auto& t : outward) {
      const Vec3 a = t[0] - p, b = t[1] - p, c = t[2] - p;
      const double la = norm(a), lb = norm(b), lc = norm(c);
      solid_angle += 2 * std::atan2(dot(a, cross(b, c)), la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb);
      depth = std::min(depth, norm(p - closest_on_triangle(p, t[0], t[1], t[2])));
    }
    if (solid_angle < 2 * M_PI || depth <= tolerance) continue;
    ++inside;
    if (depth > deepest) deepest = depth, where = p;
  }
  if (inside == 0) return;
  std::ostringstream found;
  found << std::setprecision(3) << inside << (inside == 1 ? " node" : " nodes") << " of '" << sc.bodies[hand].name << "' more than "
        << tolerance * 1e3 << " mm inside the handle '" << sc.grasp.handle << "', the deepest " << deepest * 1e3 << " mm at (" << where[0] << ", "
        << where[1] << ", " << where[2] << ") m; move the handle (across, along the fingers, out of the palm)";
  throw InputError(sc.file.string(),
                   sc.grasp.handle_centre ? "grasp.handle_centre" : "bodies[" + std::to_string(handle) + "] (the handle's placement)",
                   "a handle clear of the hand at the start", found.str());
}

// [skeleton], [[joint]] and [grasp] into the model's joint drive (joint_settings.hpp).
void add_joint_drive(const Scenario& sc, Model& m) {
  if (!sc.skeleton) return;
  JointDriveSetup& d = m.joint_drive;
  std::size_t bi = 0;
  while (sc.bodies[bi].name != sc.skeleton->body) ++bi;
  d.body = bi;
  d.file = sc.skeleton->file.string();
  d.skeleton = placed_skeleton(sc, bi, m);
  std::string names;
  for (const SkeletonJoint& j : d.skeleton.joints) names += (names.empty() ? "" : ", ") + j.name;
  auto joint_index = [&](const std::string& name, const std::string& key) {
    for (std::size_t j = 0; j < d.skeleton.joints.size(); ++j)
      if (d.skeleton.joints[j].name == name) return j;
    throw InputError(sc.file.string(), key, "a joint of the skeleton " + d.file + " (" + names + ")", "\"" + name + "\"");
  };
  for (std::size_t k = 0; k < sc.joints.size(); ++k) {
    const JointSpec& spec = sc.joints[k];
    const std::string key = "joint[" + std::to_string(k) + "]";
    JointDriveSetup::Kinematic kin;
    kin.joint = joint_index(spec.name, key + ".name");
    kin.flexion = spec.flexion * M_PI / 180, kin.abduction = spec.abduction * M_PI / 180;
    kin.curve = curve_index(m, spec.curve);
    if (const double c0 = m.curve_at(kin.curve, 0.0); c0 != 0)
      throw InputError(sc.file.string(), key + ".curve", "a curve that is 0 at t = 0 (a posture cannot jump)",
                       "'" + spec.curve + "' is " + std::to_string(c0) + " at t = 0");
    d.kinematic.push_back(kin);
  }
  d.grasp = sc.grasp;
  if (!d.grasp.on()) return;
  for (const SkeletonJoint& j : d.skeleton.joints) {
    const double w = grasp_weight(d.grasp, j.name);
    if (w < 0)
      throw InputError(d.file, "joint '" + j.name + "'",
                       "a joint named <kind>_<digit> with kind mcp, pip, dip or cmc (ip, mcp or cmc for the thumb), whose [grasp] weight "
                       "sets its torque",
                       "\"" + j.name + "\"");
    d.torque_weight.push_back(w);
  }
  for (std::size_t k = 0; k < sc.contacts.size(); ++k) {
    const ContactSpec& c = sc.contacts[k];
    if (!c.plane && (c.slave_body == d.grasp.handle) != (c.master_body == d.grasp.handle)) d.grip_entries.push_back(static_cast<int>(k));
  }
  if (d.grip_entries.empty())
    throw InputError(sc.file.string(), "grasp.handle", "a [[contact]] entry between the handle '" + d.grasp.handle + "' and another body",
                     "none: the grip force would always be 0");
}

}  // namespace

Model build_model(const Scenario& sc) {
  Model m;
  if (!sc.file.empty()) m.source = sc.file.string();
  TetAssignment tets;
  for (std::size_t bi = 0; bi < sc.bodies.size(); ++bi) append_body(sc, bi, m, tets);
  place_handle(sc, m);
  refuse_handle_inside_hand(sc, m);

  m.num_nodes = m.input_mesh.nodes.size();
  m.num_elements = m.input_mesh.tets.size();
  m.X.resize(3 * m.num_nodes);
  for (std::size_t i = 0; i < m.num_nodes; ++i)
    for (int c = 0; c < 3; ++c) m.X[3 * i + c] = m.input_mesh.nodes[i][c];
  m.initial_velocity.assign(3 * m.num_nodes, 0.0);
  for (std::size_t bi = 0; bi < sc.bodies.size(); ++bi)
    for (std::size_t i = m.bodies[bi].node_begin; i < m.bodies[bi].node_end; ++i)
      for (int c = 0; c < 3; ++c) m.initial_velocity[3 * i + c] = sc.bodies[bi].initial_velocity[c];

  const std::vector<std::size_t> order = make_blocks(sc, m, tets);
  m.conn.resize(4 * m.num_elements);
  m.input_element.resize(m.num_elements);
  for (std::size_t k = 0; k < m.num_elements; ++k) {
    for (int a = 0; a < 4; ++a) m.conn[4 * k + a] = m.input_mesh.tets[order[k]][a];
    m.input_element[k] = static_cast<std::int32_t>(order[k]);
  }
  m.node_of_input.resize(m.num_nodes);
  std::iota(m.node_of_input.begin(), m.node_of_input.end(), 0);

  for (const auto& [name, curve] : sc.curves) m.curves.push_back(curve);
  m.gravity_curve = curve_index(m, sc.run.gravity_curve);
  apply_boundaries(sc, m);  // on input numbering, before reordering
  compute_element_geometry(m);
  lump_mass(m);
  add_rigid_motion(sc, m);
  add_joint_drive(sc, m);
  reorder_for_locality(m);
  add_contacts(m, sc.contacts);
  add_pressure_loads(sc, m);
  m.contact_settings = sc.contact_solver;
  // Held once, as conn and X (Model::input_mesh).
  m.input_mesh.tets = std::vector<std::array<int, 4>>(), m.input_mesh.nodes = std::vector<Vec3>();
  return m;
}

}  // namespace tactus::solver
