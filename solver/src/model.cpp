// Assembling the discrete model from a scenario: placement, materials, lumped mass,
// constraints, and reordering for locality.
#include "tactus/solver/model.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <numeric>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/stable_step.hpp"

namespace tactus::solver {

namespace {

std::uint64_t spread_bits(std::uint64_t v) {  // 21 bits -> every third bit
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

struct MortonFrame {
  double lo[3], scale;
  explicit MortonFrame(const std::vector<double>& X) {
    double hi[3];
    for (int c = 0; c < 3; ++c) lo[c] = hi[c] = X.empty() ? 0 : X[c];
    for (std::size_t i = 0; i < X.size(); i += 3)
      for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], X[i + c]), hi[c] = std::max(hi[c], X[i + c]);
    const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-300});
    scale = 2097151.0 / extent;
  }
  std::uint64_t code(const double* x) const {
    std::uint64_t k = 0;
    for (int c = 0; c < 3; ++c) k |= spread_bits(static_cast<std::uint64_t>((x[c] - lo[c]) * scale)) << c;
    return k;
  }
};

// Fills grad and volume of every element from X; an inverted or flat tet is an input error.
void compute_element_geometry(Model& m) {
  m.grad.assign(9 * m.num_elements, 0.0);
  m.volume.assign(m.num_elements, 0.0);
  for (std::size_t e = 0; e < m.num_elements; ++e) {
    Vec3 x[4];
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 3; ++c) x[a][c] = m.X[3 * static_cast<std::size_t>(m.conn[4 * e + a]) + c];
    const TetGradients g = tet_shape_gradients(x[0], x[1], x[2], x[3]);
    if (!(g.volume > 0))
      throw InputError("mesh", m.describe_element(e), "a tetrahedron with positive volume (nodes ordered as gmsh does)",
                       "volume " + std::to_string(g.volume) + " m^3 (inverted or flat)");
    for (int a = 1; a < 4; ++a)
      for (int c = 0; c < 3; ++c) m.grad[9 * e + 3 * (a - 1) + c] = g.grad[a][c];
    m.volume[e] = g.volume;
  }
}

void lump_mass(Model& m) {
  m.mass.assign(m.num_nodes, 0.0);
  for (const auto& b : m.blocks) {
    const double rho = material_density(b.material);
    for (std::size_t e = b.begin; e < b.end; ++e)
      for (int a = 0; a < 4; ++a) m.mass[static_cast<std::size_t>(m.conn[4 * e + a])] += rho * m.volume[e] / 4.0;
  }
  for (std::size_t i = 0; i < m.num_nodes; ++i)
    if (!(m.mass[i] > 0))
      throw InputError("mesh", "node " + std::to_string(i + 1), "a node attached to at least one tet", "an isolated node");
}

// Applies node permutation `new_of_old` to every node array and to the connectivity.
void permute_nodes(Model& m, const std::vector<std::int32_t>& new_of_old) {
  auto permute3 = [&](std::vector<double>& v) {
    if (v.empty()) return;
    std::vector<double> out(v.size());
    for (std::size_t i = 0; i < m.num_nodes; ++i)
      for (int c = 0; c < 3; ++c) out[3 * static_cast<std::size_t>(new_of_old[i]) + c] = v[3 * i + c];
    v.swap(out);
  };
  permute3(m.X);
  permute3(m.initial_velocity);
  permute3(m.constraint_velocity);
  if (!m.mass.empty()) {
    std::vector<double> out(m.num_nodes);
    for (std::size_t i = 0; i < m.num_nodes; ++i) out[static_cast<std::size_t>(new_of_old[i])] = m.mass[i];
    m.mass.swap(out);
  }
  if (!m.constrained.empty()) {
    std::vector<std::uint8_t> out(m.constrained.size());
    for (std::size_t i = 0; i < m.num_nodes; ++i)
      for (int c = 0; c < 3; ++c) out[3 * static_cast<std::size_t>(new_of_old[i]) + c] = m.constrained[3 * i + c];
    m.constrained.swap(out);
  }
  for (auto& v : m.conn) v = new_of_old[static_cast<std::size_t>(v)];
  for (auto& v : m.node_of_input) v = new_of_old[static_cast<std::size_t>(v)];
}

}  // namespace

void reorder_for_locality(Model& m) {
  // Nodes along the Morton curve of their reference position.
  const MortonFrame frame(m.X);
  std::vector<std::uint64_t> key(m.num_nodes);
  for (std::size_t i = 0; i < m.num_nodes; ++i) key[i] = frame.code(&m.X[3 * i]);
  std::vector<std::int32_t> order(m.num_nodes);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return key[a] < key[b]; });
  std::vector<std::int32_t> new_of_old(m.num_nodes);
  for (std::size_t k = 0; k < order.size(); ++k) new_of_old[static_cast<std::size_t>(order[k])] = static_cast<std::int32_t>(k);
  permute_nodes(m, new_of_old);

  // Elements within each block by the smallest (now locality-ordered) node index.
  std::vector<std::size_t> eorder(m.num_elements);
  std::iota(eorder.begin(), eorder.end(), 0);
  std::vector<std::int32_t> first(m.num_elements);
  for (std::size_t e = 0; e < m.num_elements; ++e)
    first[e] = *std::min_element(&m.conn[4 * e], &m.conn[4 * e] + 4);
  for (const auto& b : m.blocks)
    std::stable_sort(eorder.begin() + static_cast<std::ptrdiff_t>(b.begin), eorder.begin() + static_cast<std::ptrdiff_t>(b.end),
                     [&](std::size_t a, std::size_t c) { return first[a] < first[c]; });
  std::vector<std::int32_t> conn(m.conn.size()), input(m.num_elements);
  std::vector<double> grad(m.grad.size()), vol(m.volume.size()), fib(m.fibres.size());
  for (std::size_t k = 0; k < m.num_elements; ++k) {
    const std::size_t e = eorder[k];
    for (int a = 0; a < 4; ++a) conn[4 * k + a] = m.conn[4 * e + a];
    if (!fib.empty())
      for (int j = 0; j < 6; ++j) fib[6 * k + j] = m.fibres[6 * e + j];
    input[k] = m.input_element[e];
    if (!grad.empty()) {
      for (int j = 0; j < 9; ++j) grad[9 * k + j] = m.grad[9 * e + j];
      vol[k] = m.volume[e];
    }
  }
  m.conn.swap(conn);
  m.input_element.swap(input);
  m.grad.swap(grad);
  m.volume.swap(vol);
  m.fibres.swap(fib);
  for (std::size_t k = 0; k < m.num_elements; ++k) m.element_of_input[static_cast<std::size_t>(m.input_element[k])] = static_cast<std::int32_t>(k);
}

namespace {
template <class V>
std::size_t bytes(const V& v) {
  return v.capacity() * sizeof(typename V::value_type);
}
}  // namespace

std::size_t Model::memory_bytes() const {
  return bytes(X) + bytes(mass) + bytes(initial_velocity) + bytes(conn) + bytes(grad) + bytes(volume) + bytes(constrained) + bytes(fibres) +
         bytes(constraint_velocity) + bytes(node_of_input) + bytes(element_of_input) + bytes(input_element) +
         bytes(input_mesh.nodes) + bytes(input_mesh.tets) + bytes(input_mesh.tet_group) + bytes(input_mesh.triangles) +
         bytes(input_mesh.triangle_group);
}

const MaterialBlock& Model::block_of(std::size_t e) const {
  for (const auto& b : blocks)
    if (e >= b.begin && e < b.end) return b;
  return blocks.front();
}

std::string Model::describe_element(std::size_t e) const {
  std::ostringstream o;
  const std::size_t in = e < input_element.size() ? static_cast<std::size_t>(input_element[e]) : e;
  const BodyRange* body = nullptr;
  for (const auto& b : bodies)
    if (in >= b.tet_begin && in < b.tet_end) body = &b;
  // Body-local tet number, 1-based, in the order its .msh was read.
  o << "tet " << (body ? in - body->tet_begin : in) + 1;
  if (body) o << " of body '" << body->name << "'";
  std::vector<std::string> facts;
  if (in < input_mesh.tet_group.size())
    if (const auto* g = input_mesh.find_group(3, input_mesh.tet_group[in])) facts.push_back("group '" + g->name + "'");
  if (!blocks.empty()) facts.push_back("material '" + block_of(e).name + "'");
  for (std::size_t k = 0; k < facts.size(); ++k) o << (k == 0 ? " (" : ", ") << facts[k] << (k + 1 == facts.size() ? ")" : "");
  return o.str();
}

namespace {

// Per-tet fibre directions of one body from a .vtu of its mesh (cell data fibre_1, fibre_2),
// matched to the mesh's tets by their node sets, so the file's element order does not matter.
std::vector<std::array<double, 6>> read_element_fibres(const std::filesystem::path& file, const TetMesh& mesh,
                                                       const std::string& key) {
  const VtuContents vtu = read_vtu(file);
  if (vtu.mesh.nodes.size() != mesh.nodes.size() || vtu.mesh.tets.size() != mesh.tets.size())
    throw InputError(file.string(), key,
                     "a .vtu of the body's mesh (" + std::to_string(mesh.nodes.size()) + " nodes, " +
                         std::to_string(mesh.tets.size()) + " tets)",
                     std::to_string(vtu.mesh.nodes.size()) + " nodes, " + std::to_string(vtu.mesh.tets.size()) + " tets");
  const MeshField* f1 = vtu.cell_field("fibre_1");
  const MeshField* f2 = vtu.cell_field("fibre_2");
  for (const MeshField* f : {f1, f2})
    if (!f || f->components != 3)
      throw InputError(file.string(), f == f1 ? "fibre_1" : "fibre_2", "cell data with 3 components per tet", f ? "other" : "missing");
  std::map<std::array<int, 4>, std::size_t> index;
  for (std::size_t e = 0; e < vtu.mesh.tets.size(); ++e) {
    auto key4 = vtu.mesh.tets[e];
    std::sort(key4.begin(), key4.end());
    index[key4] = e;
  }
  std::vector<std::array<double, 6>> out(mesh.tets.size());
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    auto key4 = mesh.tets[e];
    std::sort(key4.begin(), key4.end());
    auto it = index.find(key4);
    if (it == index.end())
      throw InputError(file.string(), "tet " + std::to_string(e + 1), "the same tets (node numbers) as the body's mesh",
                       "no matching tet");
    for (int k = 0; k < 2; ++k) {
      const MeshField& f = k == 0 ? *f1 : *f2;
      const double* a = &f.values[3 * it->second];
      const double len = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
      if (!(len > 1e-12))
        throw InputError(file.string(), std::string(k == 0 ? "fibre_1" : "fibre_2") + " of tet " + std::to_string(e + 1),
                         "a non-zero direction", "zero vector");
      for (int c = 0; c < 3; ++c) out[e][3 * k + c] = a[c] / len;
    }
  }
  return out;
}

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
      f << "nodes " << std::min(order[k], order[l]) + 1 << " and " << std::max(order[k], order[l]) + 1 << " at (" << a[0] << ", " << a[1]
        << ", " << a[2] << ") both belong to tets: a crack";
      throw InputError(file, "$Nodes", "a conforming mesh, each point one node (merge the duplicates, e.g. gmsh's Coherence)", f.str());
    }
}

}  // namespace

std::size_t Model::input_node(std::size_t internal) const {
  for (std::size_t i = 0; i < node_of_input.size(); ++i)
    if (static_cast<std::size_t>(node_of_input[i]) == internal) return i;
  return internal;
}

std::vector<const PhysicalGroup*> Model::body_groups(std::size_t body) const {
  const int offset = static_cast<int>(kBodyTagStride * body);
  std::vector<const PhysicalGroup*> out;
  for (const auto& g : input_mesh.groups)
    if (g.tag >= offset && g.tag < offset + kBodyTagStride) out.push_back(&g);
  return out;
}

Model build_model(const Scenario& sc) {
  Model m;
  std::vector<std::string> tet_material;  // per input tet
  std::vector<int> tet_body;
  std::vector<std::optional<std::array<double, 6>>> tet_fibres;
  for (std::size_t bi = 0; bi < sc.bodies.size(); ++bi) {
    const BodySpec& body = sc.bodies[bi];
    TetMesh mesh = read_msh(body.mesh);
    check_no_duplicate_nodes(mesh, body.mesh.string());
    const std::size_t node0 = m.input_mesh.nodes.size();
    m.bodies.push_back({body.name, node0, node0 + mesh.nodes.size(), m.input_mesh.tets.size(), m.input_mesh.tets.size() + mesh.tets.size()});
    std::vector<std::array<double, 6>> body_fibres;
    if (!body.fibres.empty()) body_fibres = read_element_fibres(body.fibres, mesh, "bodies[" + std::to_string(bi) + "].fibres");
    for (auto& x : mesh.nodes)
      for (int c = 0; c < 3; ++c) x[c] = x[c] * body.scale + body.translate[c];
    if (!body.against.empty()) {
      const int a = body.against_axis;
      std::size_t other = 0;
      while (sc.bodies[other].name != body.against) ++other;
      double other_lo = 1e300, other_hi = -1e300, lo = 1e300, hi = -1e300;
      for (std::size_t i = m.bodies[other].node_begin; i < m.bodies[other].node_end; ++i)
        other_lo = std::min(other_lo, m.input_mesh.nodes[i][a]), other_hi = std::max(other_hi, m.input_mesh.nodes[i][a]);
      for (const auto& x : mesh.nodes) lo = std::min(lo, x[a]), hi = std::max(hi, x[a]);
      const double shift = body.against_side > 0 ? other_hi + body.against_gap - lo : other_lo - body.against_gap - hi;
      for (auto& x : mesh.nodes) x[a] += shift;
      log::verbose() << "bodies[" << bi << "] '" << body.name << "' moved by " << shift << " m along " << "xyz"[a]
                     << " to lie " << body.against_gap << " m from '" << body.against << "'";
    }
    // Group tags are per file: offset them so bodies keep distinct groups.
    const int tag_offset = static_cast<int>(kBodyTagStride * bi);
    for (auto g : mesh.groups) {
      g.tag += tag_offset;
      m.input_mesh.groups.push_back(g);
    }
    for (const auto& x : mesh.nodes) m.input_mesh.nodes.push_back(x);
    for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
      std::array<int, 4> t = mesh.tets[e];
      for (int& v : t) v += static_cast<int>(node0);
      m.input_mesh.tets.push_back(t);
      m.input_mesh.tet_group.push_back(mesh.tet_group[e] + tag_offset);
      const std::string& gname = mesh.find_group(3, mesh.tet_group[e])->name;
      auto it = body.materials.find(gname);
      if (it == body.materials.end()) it = body.materials.find("*");
      if (it == body.materials.end()) {
        std::string groups;
        for (const auto& g : mesh.groups)
          if (g.dim == 3) groups += (groups.empty() ? "" : ", ") + g.name;
        throw InputError(sc.file.string(), "bodies[" + std::to_string(bi) + "].materials",
                         "a material for physical volume '" + gname + "' of " + body.mesh.string() +
                             " (its volume groups: " + groups + "; or a \"*\" entry)",
                         "none");
      }
      tet_material.push_back(it->second);
      tet_body.push_back(static_cast<int>(bi));
      if (body_fibres.empty())
        tet_fibres.emplace_back();
      else
        tet_fibres.emplace_back(body_fibres[e]);
    }
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      std::array<int, 3> tri = mesh.triangles[t];
      for (int& v : tri) v += static_cast<int>(node0);
      m.input_mesh.triangles.push_back(tri);
      m.input_mesh.triangle_group.push_back(mesh.triangle_group[t] + tag_offset);
    }
    for (const auto& [gname, mat] : body.materials)
      if (gname != "*" && !mesh.find_group(3, gname))
        throw InputError(sc.file.string(), "bodies[" + std::to_string(bi) + "].materials." + gname,
                         "the name of a physical volume group in " + body.mesh.string(), "no such group");
  }

  m.num_nodes = m.input_mesh.nodes.size();
  m.num_elements = m.input_mesh.tets.size();
  m.X.resize(3 * m.num_nodes);
  for (std::size_t i = 0; i < m.num_nodes; ++i)
    for (int c = 0; c < 3; ++c) m.X[3 * i + c] = m.input_mesh.nodes[i][c];
  m.initial_velocity.assign(3 * m.num_nodes, 0.0);
  for (std::size_t bi = 0; bi < sc.bodies.size(); ++bi)
    for (std::size_t i = m.bodies[bi].node_begin; i < m.bodies[bi].node_end; ++i)
      for (int c = 0; c < 3; ++c) m.initial_velocity[3 * i + c] = sc.bodies[bi].initial_velocity[c];

  // Blocks: elements grouped by material name, in scenario order.
  std::vector<std::size_t> order;
  for (const auto& [name, inst] : sc.materials) {
    MaterialBlock b;
    b.name = name;
    b.material = make_material(inst.type, inst.params);
    if (auto* h = std::get_if<Hgo>(&b.material); h && inst.fibres) {
      h->a1 = Vec3d((*inst.fibres)[0][0], (*inst.fibres)[0][1], (*inst.fibres)[0][2]);
      h->a2 = Vec3d((*inst.fibres)[1][0], (*inst.fibres)[1][1], (*inst.fibres)[1][2]);
    }
    b.begin = order.size();
    for (std::size_t e = 0; e < m.num_elements; ++e)
      if (tet_material[e] == name) order.push_back(e);
    b.end = order.size();
    if (b.end == b.begin) continue;
    if (inst.type == "hgo") {
      for (std::size_t k = b.begin; k < b.end; ++k) {
        if (tet_fibres[order[k]]) b.element_fibres = true;
        else if (!inst.fibres)
          throw InputError(sc.file.string(), "materials." + name + ".fibres",
                           "fibre directions for hgo: [[ax, ay, az], [bx, by, bz]] here, or a per-element `fibres` file "
                           "on body '" + sc.bodies[static_cast<std::size_t>(tet_body[order[k]])].name + "'",
                           "none");
      }
    }
    m.blocks.push_back(b);
  }
  if (std::any_of(m.blocks.begin(), m.blocks.end(), [](const MaterialBlock& b) { return b.element_fibres; })) {
    m.fibres.assign(6 * m.num_elements, 0.0);
    for (const auto& b : m.blocks) {
      if (!b.element_fibres) continue;
      const Hgo& h = std::get<Hgo>(b.material);
      for (std::size_t k = b.begin; k < b.end; ++k) {
        const auto& f = tet_fibres[order[k]];
        for (int c = 0; c < 3; ++c) {
          m.fibres[6 * k + c] = f ? (*f)[c] : h.a1[c];
          m.fibres[6 * k + 3 + c] = f ? (*f)[3 + c] : h.a2[c];
        }
      }
    }
  }
  m.conn.resize(4 * m.num_elements);
  m.input_element.resize(m.num_elements);
  m.element_of_input.resize(m.num_elements);
  for (std::size_t k = 0; k < m.num_elements; ++k) {
    for (int a = 0; a < 4; ++a) m.conn[4 * k + a] = m.input_mesh.tets[order[k]][a];
    m.input_element[k] = static_cast<std::int32_t>(order[k]);
    m.element_of_input[order[k]] = static_cast<std::int32_t>(k);
  }
  m.node_of_input.resize(m.num_nodes);
  std::iota(m.node_of_input.begin(), m.node_of_input.end(), 0);

  // Constraints, on input numbering before reordering.
  m.constrained.assign(3 * m.num_nodes, 0);
  m.constraint_velocity.assign(3 * m.num_nodes, 0.0);
  for (std::size_t k = 0; k < sc.boundaries.size(); ++k) {
    const BoundarySpec& bc = sc.boundaries[k];
    const std::string key = "boundary[" + std::to_string(k) + "]";
    std::size_t bi = 0;
    while (sc.bodies[bi].name != bc.body) ++bi;
    const BodyRange& range = m.bodies[bi];
    std::vector<char> selected(m.num_nodes, 0);
    if (!bc.group.empty()) {
      bool found = false;
      for (const PhysicalGroup* g : m.body_groups(bi)) {
        if (g->name != bc.group) continue;
        found = true;
        if (g->dim == 2) {
          for (std::size_t t = 0; t < m.input_mesh.triangles.size(); ++t)
            if (m.input_mesh.triangle_group[t] == g->tag)
              for (int v : m.input_mesh.triangles[t]) selected[static_cast<std::size_t>(v)] = 1;
        } else {
          for (std::size_t t = 0; t < m.input_mesh.tets.size(); ++t)
            if (m.input_mesh.tet_group[t] == g->tag)
              for (int v : m.input_mesh.tets[t]) selected[static_cast<std::size_t>(v)] = 1;
        }
      }
      if (!found) {
        std::string groups;
        for (const PhysicalGroup* g : m.body_groups(bi)) groups += (groups.empty() ? "" : ", ") + g->name;
        throw InputError(sc.file.string(), key + ".group", "a physical group of body '" + bc.body + "' (" + groups + ")",
                         "\"" + bc.group + "\"");
      }
    } else {
      const auto& box = *bc.box;
      for (std::size_t i = range.node_begin; i < range.node_end; ++i) {
        bool in = true;
        for (int c = 0; c < 3; ++c) in = in && m.X[3 * i + c] >= box[0][c] && m.X[3 * i + c] <= box[1][c];
        selected[i] = in;
      }
    }
    std::size_t count = 0;
    for (std::size_t i = range.node_begin; i < range.node_end; ++i) {
      if (!selected[i]) continue;
      ++count;
      for (int c = 0; c < 3; ++c)
        if (bc.components[c]) {
          m.constrained[3 * i + c] = 1;
          m.constraint_velocity[3 * i + c] = bc.type == "velocity" ? bc.velocity[c] : 0.0;
        }
    }
    if (count == 0) throw InputError(sc.file.string(), key, "a selection containing nodes of body '" + bc.body + "'", "no node");
    log::verbose() << key << ": " << count << " nodes " << bc.type;
  }

  compute_element_geometry(m);
  lump_mass(m);
  reorder_for_locality(m);
  add_scenario_contacts(m, sc);
  m.contact_settings = sc.contact_solver;
  return m;
}

Model build_model(const TetMesh& mesh, const Material& material, const std::string& material_name,
                  const Vec3a& initial_velocity, bool reorder) {
  Model m;
  m.input_mesh = mesh;
  m.bodies.push_back({"body", 0, mesh.nodes.size(), 0, mesh.tets.size()});
  m.num_nodes = mesh.nodes.size();
  m.num_elements = mesh.tets.size();
  m.X.resize(3 * m.num_nodes);
  m.initial_velocity.resize(3 * m.num_nodes);
  for (std::size_t i = 0; i < m.num_nodes; ++i)
    for (int c = 0; c < 3; ++c) m.X[3 * i + c] = mesh.nodes[i][c], m.initial_velocity[3 * i + c] = initial_velocity[c];
  m.conn.resize(4 * m.num_elements);
  m.input_element.resize(m.num_elements);
  m.element_of_input.resize(m.num_elements);
  for (std::size_t e = 0; e < m.num_elements; ++e) {
    for (int a = 0; a < 4; ++a) m.conn[4 * e + a] = mesh.tets[e][a];
    m.input_element[e] = m.element_of_input[e] = static_cast<std::int32_t>(e);
  }
  m.node_of_input.resize(m.num_nodes);
  std::iota(m.node_of_input.begin(), m.node_of_input.end(), 0);
  m.blocks.push_back({material_name, material, 0, m.num_elements});
  m.constrained.assign(3 * m.num_nodes, 0);
  m.constraint_velocity.assign(3 * m.num_nodes, 0.0);
  compute_element_geometry(m);
  lump_mass(m);
  if (reorder) reorder_for_locality(m);
  return m;
}

}  // namespace tactus::solver

namespace tactus::solver {
std::size_t constrain_nodes(Model& m, const std::function<bool(const double*)>& select, std::array<bool, 3> components,
                            const Vec3a& velocity) {
  std::size_t count = 0;
  for (std::size_t i = 0; i < m.num_nodes; ++i) {
    if (!select(&m.X[3 * i])) continue;
    ++count;
    for (int c = 0; c < 3; ++c)
      if (components[c]) m.constrained[3 * i + c] = 1, m.constraint_velocity[3 * i + c] = velocity[c];
  }
  return count;
}
}  // namespace tactus::solver
