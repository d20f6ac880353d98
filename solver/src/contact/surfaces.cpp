// Contact surfaces of the model: slave nodes with tributary areas, master triangles oriented out
// of their body, built from the meshes' physical surface groups named in [[contact]].
#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_map>

#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"
#include "tactus/solver/contact.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/rigid.hpp"

namespace tactus::solver {

namespace {

Vec3 at(const Model& m, int v) { return load3(&m.X[3 * static_cast<std::size_t>(v)]); }

std::uint64_t face_key(int a, int b, int c) {
  int v[3] = {a, b, c};
  std::sort(v, v + 3);
  return (static_cast<std::uint64_t>(v[0]) << 42) ^ (static_cast<std::uint64_t>(v[1]) << 21) ^ static_cast<std::uint64_t>(v[2]);
}

double mean_edge(const Model& m, const std::vector<std::array<int, 3>>& tris) {
  double sum = 0;
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k) sum += norm(at(m, t[k]) - at(m, t[(k + 1) % 3]));
  return tris.empty() ? 0.0 : sum / (3.0 * static_cast<double>(tris.size()));
}

// Triangles of a body's physical surface group, in internal numbering.
using Triangles = std::vector<std::array<int, 3>>;

Triangles group_triangles(const Model& m, std::size_t body, const std::string& group, const std::string& file, const std::string& key) {
  const PhysicalGroup* g = m.body_group(body, 2, group);
  if (!g) {
    std::string names;
    for (const PhysicalGroup* pg : m.body_groups(body))
      if (pg->dim == 2) names += (names.empty() ? "" : ", ") + pg->name;
    throw InputError(file, key, "a physical surface group of body '" + m.bodies[body].name + "' (" + (names.empty() ? "it has none" : names) + ")",
                     "\"" + group + "\"");
  }
  std::vector<std::array<int, 3>> out = surface_triangles(m, body, g->tag);
  if (out.empty()) throw InputError(file, key, "a surface group with triangles", "group \"" + group + "\" is empty");
  return out;
}

}  // namespace

std::vector<std::array<int, 3>> surface_triangles(const Model& m, int tag) { return surface_triangles(m, 0, tag); }

std::vector<std::array<int, 3>> surface_triangles(const Model& m, std::size_t body, int tag) {
  std::vector<std::array<int, 3>> out;
  for (std::size_t t = m.bodies[body].triangle_begin; t < m.bodies[body].triangle_end; ++t)
    if (m.input_mesh.triangle_group[t] == tag) {
      std::array<int, 3> tri{};
      for (int k = 0; k < 3; ++k) tri[k] = m.node_of_input[static_cast<std::size_t>(m.input_mesh.triangles[t][k])];
      out.push_back(tri);
    }
  return out;
}

std::vector<std::int32_t> outward_triangles(const Model& m, const std::vector<std::array<int, 3>>& triangles, std::vector<int>& owners) {
  std::unordered_map<std::uint64_t, std::size_t> index;
  index.reserve(2 * triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) index.emplace(face_key(triangles[t][0], triangles[t][1], triangles[t][2]), t);
  std::vector<int> opposite(triangles.size(), -1);
  owners.assign(triangles.size(), 0);
  static constexpr int faces[4][4] = {{1, 2, 3, 0}, {0, 2, 3, 1}, {0, 1, 3, 2}, {0, 1, 2, 3}};
  for (std::size_t e = 0; e < m.num_elements; ++e) {
    const std::int32_t* c = &m.conn[4 * e];
    for (const auto& f : faces) {
      auto it = index.find(face_key(c[f[0]], c[f[1]], c[f[2]]));
      if (it == index.end()) continue;
      if (opposite[it->second] < 0) opposite[it->second] = c[f[3]];
      ++owners[it->second];
    }
  }
  std::vector<std::int32_t> oriented;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    std::array<int, 3> tri = triangles[t];
    if (opposite[t] >= 0) {
      const Vec3 n = cross(at(m, tri[1]) - at(m, tri[0]), at(m, tri[2]) - at(m, tri[0]));
      if (dot(n, at(m, opposite[t]) - at(m, tri[0])) > 0) std::swap(tri[1], tri[2]);  // point out of the tet
    }
    for (int v : tri) oriented.push_back(v);
  }
  return oriented;
}

namespace {

// outward_triangles, with a triangle that is not a tet face an InputError naming `where`.
std::vector<std::int32_t> outward_tet_faces(const Model& m, const std::vector<std::array<int, 3>>& triangles, const std::string& where) {
  std::vector<int> owners;
  std::vector<std::int32_t> oriented = outward_triangles(m, triangles, owners);
  for (std::size_t t = 0; t < owners.size(); ++t)
    if (owners[t] == 0) {
      std::ostringstream f;
      f << "triangle " << t + 1 << " of the surface is not a face of any tet";
      throw InputError("mesh", where, "a surface made of tet faces", f.str());
    }
  return oriented;
}

// The nodes on the convex edges of an outward-oriented surface whose two faces' normals differ by
// more than `angle_deg` (a block's edges and corners; not the gentle folds of a curved surface).
std::vector<int> convex_edge_nodes(const Model& m, const std::vector<std::int32_t>& oriented, double angle_deg) {
  const std::size_t n = oriented.size() / 3;
  auto normal = [&](std::size_t t) {
    const Vec3 a = at(m, oriented[3 * t]), b = at(m, oriented[3 * t + 1]), c = at(m, oriented[3 * t + 2]);
    const Vec3 v = cross(b - a, c - a);
    const double l = norm(v);
    return Vec3{v[0] / l, v[1] / l, v[2] / l};
  };
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> edges;
  for (std::size_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) {
      const auto a = static_cast<std::uint64_t>(oriented[3 * t + k]), b = static_cast<std::uint64_t>(oriented[3 * t + (k + 1) % 3]);
      edges[(std::min(a, b) << 32) | std::max(a, b)].push_back(t);
    }
  const double cos_limit = std::cos(angle_deg * M_PI / 180.0);
  std::vector<char> feature(m.num_nodes, 0);
  for (const auto& [key, tris] : edges) {
    if (tris.size() != 2) continue;
    const Vec3 n0 = normal(tris[0]), n1 = normal(tris[1]);
    if (!(dot(n0, n1) < cos_limit)) continue;  // (a degenerate face's NaN normal: not an edge)
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
    int opposite = -1;  // the second face's vertex off the edge
    for (int k = 0; k < 3; ++k)
      if (const int v = oriented[3 * tris[1] + k]; v != a && v != b) opposite = v;
    if (!(dot(n0, at(m, opposite) - at(m, a)) < 0)) continue;  // concave: the second face rises in front of the first
    feature[static_cast<std::size_t>(a)] = feature[static_cast<std::size_t>(b)] = 1;
  }
  std::vector<int> out;
  for (std::size_t v = 0; v < m.num_nodes; ++v)
    if (feature[v]) out.push_back(static_cast<int>(v));
  return out;
}

}  // namespace

void set_slave_surface(ContactPair& pair, const Model& m, const std::vector<std::array<int, 3>>& triangles) {
  std::unordered_map<int, double> area;
  std::vector<int> order;
  for (const auto& t : triangles) {
    const double a = 0.5 * norm(cross(at(m, t[1]) - at(m, t[0]), at(m, t[2]) - at(m, t[0])));
    for (int v : t) {
      auto [it, inserted] = area.emplace(v, 0.0);
      if (inserted) order.push_back(v);
      it->second += a / 3.0;
    }
  }
  std::sort(order.begin(), order.end());  // node order = memory order
  pair.slave_nodes.assign(order.begin(), order.end());
  pair.slave_area.clear();
  for (int v : order) pair.slave_area.push_back(area[v]);
  std::vector<int> owners;
  pair.slave_triangles = outward_triangles(m, triangles, owners);           // mortar: its normals face the master's
  if (pair.search_scale <= 0) pair.search_scale = mean_edge(m, triangles);  // a rigid plane: the slave's own size
}

void set_master_surface(ContactPair& pair, const Model& m, const std::vector<std::array<int, 3>>& triangles, const std::string& where, bool mortar) {
  std::vector<std::int32_t> oriented = outward_tet_faces(m, triangles, where);
  pair.master = mortar ? mortar_surface_master(std::move(oriented)) : deformable_surface_master(std::move(oriented));
  pair.search_scale = mean_edge(m, triangles);
}

void set_self_contact_surface(ContactPair& pair, const Model& m, const std::vector<std::array<int, 3>>& triangles, const std::string& where) {
  pair.master = deformable_surface_master(outward_tet_faces(m, triangles, where), true);
  pair.search_scale = mean_edge(m, triangles);
  pair.self_contact = true;
  set_slave_surface(pair, m, triangles);
}

void set_rigid_plane(ContactPair& pair, const Vec3& point, const Vec3& outward_normal) {
  const double len = norm(outward_normal);
  pair.master = rigid_plane_master(point, {outward_normal[0] / len, outward_normal[1] / len, outward_normal[2] / len});
}

namespace {

// Mortar's edge pass: a one-pass slave-node method lets a sharp master edge through the slave
// surface between its nodes (skin wrapping round a block's edge: the edge cuts the skin's straight
// facets, and the skin nodes beyond it come round already inside). The master's convex edge and
// corner nodes become node-to-surface slaves against the slave surface, in a second pair of the
// same entry (counted reversed, area the mortar pass's). Their rows carry no slave triangles: the
// sensor-averaged pressure samples the slave surface only, onto whose nodes their reactions are
// reported (ContactSolver::update_windows).
// mortar_master: the entry's mortar pass's master triangles, already oriented out of their body.
void add_edge_pass(Model& m, const ContactSpec& cs, int entry, const std::string& key, const std::vector<std::array<int, 3>>& slave_tris,
                   const std::vector<std::array<int, 3>>& master_tris, const std::vector<std::int32_t>& mortar_master) {
  ContactPair p;
  p.name = key + " " + cs.master_body + "/" + cs.master_surface + " edges -> " + cs.slave_body + "/" + cs.slave_surface;
  p.friction = cs.friction;
  p.report_sign = -1.0;
  p.entry = entry;
  p.edge_pass = true;
  set_master_surface(p, m, slave_tris, key + ".slave_surface", false);
  set_slave_surface(p, m, master_tris);
  const std::vector<int> edge = convex_edge_nodes(m, mortar_master, kEdgePassAngleDeg);
  // Nodes of rigid pieces are left out: a rigid slave adds no compliance of its own, and the
  // Gauss-Seidel sweep then creeps over the light master nodes neighbouring rows share (docs/design.md,
  // "Choose the slave side"; with the hand_block_rigid block: 11 steps at the 200-iteration limit).
  const std::vector<char> rigid = rigid_nodes(m);
  std::vector<std::int32_t> nodes;
  std::vector<double> area;
  for (std::size_t i = 0; i < p.slave_nodes.size(); ++i)
    if (std::binary_search(edge.begin(), edge.end(), p.slave_nodes[i]) && !rigid[static_cast<std::size_t>(p.slave_nodes[i])])
      nodes.push_back(p.slave_nodes[i]), area.push_back(p.slave_area[i]);
  p.slave_nodes = std::move(nodes), p.slave_area = std::move(area);
  p.slave_triangles.clear();
  if (p.slave_nodes.empty()) return;  // a smooth or rigid master (or one face of a block): nothing to add
  log::verbose() << p.name << ": " << p.slave_nodes.size() << " edge and corner nodes, " << p.master->describe();
  m.contact_pairs.push_back(std::move(p));
}

// One directed surface-to-surface pair of an entry (swap: the second pass, master's nodes against
// the slave surface), with a mortar or a node-to-surface master.
void add_surface_pair(Model& m, const ContactSpec& cs, int k, const std::string& key, bool swap, const Triangles& slave_tris,
                      const Triangles& master_tris, bool mortar) {
  ContactPair p;
  const std::string& s_body = swap ? cs.master_body : cs.slave_body;
  const std::string& s_surf = swap ? cs.master_surface : cs.slave_surface;
  const std::string& m_body = swap ? cs.slave_body : cs.master_body;
  const std::string& m_surf = swap ? cs.slave_surface : cs.master_surface;
  p.name = key + " " + s_body + "/" + s_surf + " -> " + m_body + "/" + m_surf;
  p.friction = cs.friction;
  p.report_sign = swap ? -1.0 : 1.0;
  p.entry = k;
  set_master_surface(p, m, swap ? slave_tris : master_tris, key + (swap ? ".slave_surface" : ".master_surface"), mortar);
  set_slave_surface(p, m, swap ? master_tris : slave_tris);
  log::verbose() << p.name << ": " << p.slave_nodes.size() << " slave nodes, " << p.master->describe() << ", mean master edge "
                 << p.search_scale * 1e3 << " mm";
  m.contact_pairs.push_back(std::move(p));
}

}  // namespace

const char* contact_method_name(ContactMethod m) {
  return m == ContactMethod::mortar ? "mortar" : m == ContactMethod::node_to_surface ? "node_to_surface" : "automatic";
}

ContactMethod contact_method(const ContactSpec& c) {
  if (c.method != ContactMethod::automatic) return c.method;
  return c.plane || is_self_contact(c) || c.two_pass ? ContactMethod::node_to_surface : ContactMethod::mortar;
}

bool is_self_contact(const ContactSpec& c) { return !c.plane && c.master_body == c.slave_body && c.master_surface == c.slave_surface; }

namespace {

// A node-to-surface entry: the slave's nodes against a rigid plane, against their own surface
// (self-contact), or against the master surface (and, two_pass, the master's nodes against the
// slave surface).
void add_node_to_surface(Model& m, const ContactSpec& cs, int k, const std::string& key, const Triangles& slave_tris, const Triangles& master_tris) {
  ContactPair p;
  p.friction = cs.friction;
  p.entry = k;
  if (cs.plane) {
    p.name = key + " " + cs.slave_body + "/" + cs.slave_surface + " -> rigid plane";
    set_rigid_plane(p, (*cs.plane)[0], (*cs.plane)[1]);
    set_slave_surface(p, m, slave_tris);
    m.contact_pairs.push_back(std::move(p));
    return;
  }
  if (is_self_contact(cs)) {
    p.name = key + " " + cs.slave_body + "/" + cs.slave_surface + " self-contact";
    set_self_contact_surface(p, m, slave_tris, key + ".slave_surface");
    log::verbose() << p.name << ": " << p.slave_nodes.size() << " nodes, " << p.master->describe();
    m.contact_pairs.push_back(std::move(p));
    return;
  }
  for (int pass = 0; pass < (cs.two_pass ? 2 : 1); ++pass) add_surface_pair(m, cs, k, key, pass == 1, slave_tris, master_tris, false);
}

}  // namespace

void add_contacts(Model& m, const std::vector<ContactSpec>& contacts) {
  auto body_index = [&](const std::string& name) {
    for (std::size_t b = 0; b < m.bodies.size(); ++b)
      if (m.bodies[b].name == name) return b;
    return m.bodies.size();
  };
  for (std::size_t k = 0; k < contacts.size(); ++k) {
    const ContactSpec& cs = contacts[k];
    const std::string key = "contact[" + std::to_string(k) + "]";
    const auto slave_tris = group_triangles(m, body_index(cs.slave_body), cs.slave_surface, m.source, key + ".slave_surface");
    const bool surface_master = !cs.plane && !is_self_contact(cs);
    const Triangles master_tris =
        surface_master ? group_triangles(m, body_index(cs.master_body), cs.master_surface, m.source, key + ".master_surface") : Triangles();
    switch (contact_method(cs)) {  // the one place the method is chosen
      case ContactMethod::mortar:
        add_surface_pair(m, cs, static_cast<int>(k), key, false, slave_tris, master_tris, true);
        if (cs.edge_pass) add_edge_pass(m, cs, static_cast<int>(k), key, slave_tris, master_tris, m.contact_pairs.back().master->triangles());
        break;
      case ContactMethod::node_to_surface:
      case ContactMethod::automatic:  // (contact_method resolves it)
        add_node_to_surface(m, cs, static_cast<int>(k), key, slave_tris, master_tris);
        break;
    }
  }
}

}  // namespace tactus::solver
