// The discrete model: element geometry, lumped mass, reordering for locality, and the Model's
// look-ups. Building one from a scenario is model_build.cpp's.
#include "tactus/solver/model.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>
#include <sstream>
#include <type_traits>

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

// For k in [begin, end): item k of v (width values each, v holding the range's items from item
// `begin`) becomes the item that was at order[k], which lies in [begin, end) too (order permutes
// the range); the items move along the permutation's cycles with one held aside, so no second
// array is needed. placed: scratch.
template <class T>
void gather_in_place(std::vector<T>& v, std::size_t width, const std::vector<std::size_t>& order, std::size_t begin, std::size_t end,
                     std::vector<bool>& placed) {
  placed.assign(end - begin, false);
  std::vector<T> held(width);
  const auto at = [&](std::size_t item) { return v.begin() + static_cast<std::ptrdiff_t>(width * (item - begin)); };
  for (std::size_t start = begin; start < end; ++start) {
    if (placed[start - begin]) continue;
    std::copy(at(start), at(start) + static_cast<std::ptrdiff_t>(width), held.begin());
    std::size_t k = start;
    while (order[k] != start) {  // k takes its item from order[k], which then needs its own
      std::copy(at(order[k]), at(order[k]) + static_cast<std::ptrdiff_t>(width), at(k));
      placed[k - begin] = true;
      k = order[k];
    }
    std::copy(held.begin(), held.end(), at(k));
    placed[k - begin] = true;
  }
}

// Applies node permutation `new_of_old` to every node array and to the connectivity.
void permute_nodes(Model& m, const std::vector<std::int32_t>& new_of_old) {
  auto permute3 = [&](auto& v) {
    if (v.empty()) return;
    std::remove_reference_t<decltype(v)> out(v.size());
    for (std::size_t i = 0; i < m.num_nodes; ++i)
      for (int c = 0; c < 3; ++c) out[3 * static_cast<std::size_t>(new_of_old[i]) + c] = v[3 * i + c];
    v.swap(out);
  };
  permute3(m.X);
  permute3(m.initial_velocity);
  permute3(m.constraint_velocity);
  permute3(m.constraint_curve);
  permute3(m.constraint_boundary);
  if (!m.mass.empty()) {
    std::vector<double> out(m.num_nodes);
    for (std::size_t i = 0; i < m.num_nodes; ++i) out[static_cast<std::size_t>(new_of_old[i])] = m.mass[i];
    m.mass.swap(out);
  }
  permute3(m.constrained);
  for (auto& v : m.conn) v = new_of_old[static_cast<std::size_t>(v)];
  for (auto& v : m.node_of_input) v = new_of_old[static_cast<std::size_t>(v)];
}

}  // namespace

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
    const double rho = b.material.density();
    for (std::size_t e = b.begin; e < b.end; ++e)
      for (int a = 0; a < 4; ++a) m.mass[static_cast<std::size_t>(m.conn[4 * e + a])] += rho * m.volume[e] / 4.0;
  }
  for (std::size_t i = 0; i < m.num_nodes; ++i)
    if (!(m.mass[i] > 0)) throw InputError("mesh", "node " + std::to_string(i + 1), "a node attached to at least one tet", "an isolated node");
}

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
  for (std::size_t e = 0; e < m.num_elements; ++e) first[e] = *std::min_element(&m.conn[4 * e], &m.conn[4 * e] + 4);
  for (const auto& b : m.blocks)
    std::stable_sort(eorder.begin() + static_cast<std::ptrdiff_t>(b.begin), eorder.begin() + static_cast<std::ptrdiff_t>(b.end),
                     [&](std::size_t a, std::size_t c) { return first[a] < first[c]; });
  // Each per-element array in place (no second copy of the model's largest arrays at its build's
  // peak: on a 1M-tet model a copy of the reference gradients alone is 72 MB).
  std::vector<bool> placed;
  for (auto& b : m.blocks)  // the blocks' per-element data follows its elements
    if (b.per_element_data()) gather_in_place(b.element_data, b.material.type().element_data_size, eorder, b.begin, b.end, placed);
  gather_in_place(m.conn, 4, eorder, 0, m.num_elements, placed);
  gather_in_place(m.input_element, 1, eorder, 0, m.num_elements, placed);
  if (!m.grad.empty()) {
    gather_in_place(m.grad, 9, eorder, 0, m.num_elements, placed);
    gather_in_place(m.volume, 1, eorder, 0, m.num_elements, placed);
  }
}

namespace {
template <class V>
std::size_t bytes(const V& v) {
  return v.capacity() * sizeof(typename V::value_type);
}
}  // namespace

std::size_t Model::memory_bytes() const {
  std::size_t block_data = 0;
  for (const auto& b : blocks) block_data += bytes(b.element_data);
  return bytes(X) + bytes(mass) + bytes(initial_velocity) + bytes(conn) + bytes(grad) + bytes(volume) + bytes(constrained) + block_data +
         bytes(constraint_velocity) + bytes(node_of_input) + bytes(input_element) + bytes(input_mesh.nodes) + bytes(input_mesh.tets) +
         bytes(input_mesh.tet_group) + bytes(input_mesh.triangles) + bytes(input_mesh.triangle_group);
}

void Model::release_tet_geometry() {
  conn = std::vector<std::int32_t>(), grad = std::vector<double>(), volume = std::vector<double>();
  for (MaterialBlock& b : blocks)
    if (b.per_element_data()) b.element_data = std::vector<double>(), b.element_data_released = true;
  tet_geometry_released = true;
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
  if (body && in < input_mesh.tet_group.size())
    for (const PhysicalGroup* g : body_groups(static_cast<std::size_t>(body - bodies.data())))
      if (g->dim == 3 && g->tag == input_mesh.tet_group[in]) facts.push_back("group '" + g->name + "'");
  if (!blocks.empty()) facts.push_back("material '" + block_of(e).name + "'");
  for (std::size_t k = 0; k < facts.size(); ++k) o << (k == 0 ? " (" : ", ") << facts[k] << (k + 1 == facts.size() ? ")" : "");
  return o.str();
}

std::size_t Model::input_node(std::size_t internal) const {
  for (std::size_t i = 0; i < node_of_input.size(); ++i)
    if (static_cast<std::size_t>(node_of_input[i]) == internal) return i;
  return internal;
}

std::vector<const PhysicalGroup*> Model::body_groups(std::size_t body) const {
  std::vector<const PhysicalGroup*> out;
  for (std::size_t g = bodies[body].group_begin; g < bodies[body].group_end; ++g) out.push_back(&input_mesh.groups[g]);
  return out;
}

const PhysicalGroup* Model::body_group(std::size_t body, int dim, const std::string& name) const {
  for (const PhysicalGroup* g : body_groups(body))
    if (g->dim == dim && g->name == name) return g;
  return nullptr;
}

std::size_t Model::body_of_node(std::size_t input_node) const {
  for (std::size_t b = 0; b < bodies.size(); ++b)
    if (input_node >= bodies[b].node_begin && input_node < bodies[b].node_end) return b;
  return 0;
}

std::size_t Model::body_of_tet(std::size_t input_tet) const {
  for (std::size_t b = 0; b < bodies.size(); ++b)
    if (input_tet >= bodies[b].tet_begin && input_tet < bodies[b].tet_end) return b;
  return 0;
}

Model build_model(const TetMesh& mesh, const Material& material, const std::string& material_name, const Vec3& initial_velocity, bool reorder) {
  Model m;
  m.input_mesh = mesh;
  m.bodies.push_back({"body", 0, mesh.nodes.size(), 0, mesh.tets.size(), 0, mesh.triangles.size(), 0, mesh.groups.size()});
  m.num_nodes = mesh.nodes.size();
  m.num_elements = mesh.tets.size();
  m.X.resize(3 * m.num_nodes);
  m.initial_velocity.resize(3 * m.num_nodes);
  for (std::size_t i = 0; i < m.num_nodes; ++i)
    for (int c = 0; c < 3; ++c) m.X[3 * i + c] = mesh.nodes[i][c], m.initial_velocity[3 * i + c] = initial_velocity[c];
  m.conn.resize(4 * m.num_elements);
  m.input_element.resize(m.num_elements);
  for (std::size_t e = 0; e < m.num_elements; ++e) {
    for (int a = 0; a < 4; ++a) m.conn[4 * e + a] = mesh.tets[e][a];
    m.input_element[e] = static_cast<std::int32_t>(e);
  }
  m.node_of_input.resize(m.num_nodes);
  std::iota(m.node_of_input.begin(), m.node_of_input.end(), 0);
  if (material.needs_element_data())
    throw InputError("material", material_name, "the material's element data (e.g. hgo's fibres) in its values", "none");
  m.blocks.push_back({material_name, material, 0, m.num_elements, {}});
  m.constrained.assign(3 * m.num_nodes, 0);
  m.constraint_velocity.assign(3 * m.num_nodes, 0.0);
  compute_element_geometry(m);
  lump_mass(m);
  // Held once, as conn and X (Model::input_mesh).
  m.input_mesh.tets = std::vector<std::array<int, 4>>(), m.input_mesh.nodes = std::vector<Vec3>();
  if (reorder) reorder_for_locality(m);
  return m;
}

}  // namespace tactus::solver

namespace tactus::solver {
std::size_t constrain_nodes(Model& m, const std::function<bool(const double*)>& select, std::array<bool, 3> components, const Vec3& velocity) {
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
