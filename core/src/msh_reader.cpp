// tactus's own reader of gmsh MSH files, 4.1 and 2.2, ASCII and binary. libgmsh's reader trusts
// the file (inserted or deleted bytes, absurd counts or negative tags crashed it), so reading is
// done here, every count checked against the bytes that remain before anything is allocated,
// every tag and reference validated; gmsh is kept for writing and meshing.
//
// Format references (gmsh manual, "MSH file format"): 4.1 has $Entities (entity -> physical
// tags) and entity blocks in $Nodes / $Elements; binary files store ints as 4 bytes and size_t as
// the header's data size (8); 2.2 puts the physical tag first in each element's tag list.
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <unordered_map>

#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/mesh.hpp"

namespace fs = std::filesystem;

namespace tactus {

namespace {

constexpr int kTriangle = 2, kTet = 4;
constexpr double kMaxCoordinate = 1e9;  // |x| beyond this is not a mesh of anything tactus simulates

// Nodes per element type (gmsh's numbering 1..19), for skipping the types tactus does not use:
// line, triangle, quadrangle, tetrahedron, hexahedron, prism, pyramid, then the second-order
// line, triangle, quadrangle, tetrahedron, hexahedron, prism, pyramid, the point, and the
// serendipity quadrangle, hexahedron, prism, pyramid.
constexpr std::array<int, 20> kNodesPerElementType{0, 2, 3, 4, 4, 8, 6, 5, 3, 6, 9, 10, 27, 18, 14, 1, 8, 20, 15, 13};
int nodes_per_element(int type) {
  return type > 0 && type < static_cast<int>(kNodesPerElementType.size()) ? kNodesPerElementType[static_cast<std::size_t>(type)] : 0;
}

// A cursor over the file's bytes that reads ASCII tokens or binary values, with bounds checks.
class Cursor {
 public:
  Cursor(const std::string& bytes, std::string file) : b_(bytes), file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& where, const std::string& expected, const std::string& found = {}) const {
    throw InputError(file_, where + " (byte " + std::to_string(pos_) + ")", expected, found);
  }
  std::size_t remaining() const { return b_.size() - pos_; }
  std::size_t pos() const { return pos_; }
  bool at_end() {
    skip_space();
    return pos_ >= b_.size();
  }

  void skip_space() {
    while (pos_ < b_.size() && (b_[pos_] == ' ' || b_[pos_] == '\t' || b_[pos_] == '\n' || b_[pos_] == '\r')) ++pos_;
  }
  std::string_view token(const std::string& where) {
    skip_space();
    const std::size_t start = pos_;
    while (pos_ < b_.size() && !std::isspace(static_cast<unsigned char>(b_[pos_]))) ++pos_;
    if (pos_ == start) fail(where, "more data", "the end of the file");
    return std::string_view(b_).substr(start, pos_ - start);
  }
  // The rest of the current line (without the newline).
  std::string_view line() {
    const std::size_t start = pos_;
    while (pos_ < b_.size() && b_[pos_] != '\n') ++pos_;
    std::string_view l = std::string_view(b_).substr(start, pos_ - start);
    if (pos_ < b_.size()) ++pos_;
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    return l;
  }
  template <class T>
  T ascii_integer(const std::string& where, T lo, T hi) {
    const std::string_view t = token(where);
    T v{};
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || end != t.data() + t.size() || v < lo || v > hi)
      fail(where, "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]", "\"" + std::string(t.substr(0, 40)) + "\"");
    return v;
  }
  double ascii_double(const std::string& where) {
    const std::string_view t = token(where);
    double v = 0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || end != t.data() + t.size() || !std::isfinite(v))
      fail(where, "a finite number", std::string("\"").append(t.substr(0, 40)).append("\""));
    return v;
  }
  template <class T>
  T binary(const std::string& where) {
    if (remaining() < sizeof(T)) fail(where, "more binary data", "the end of the file");
    T v;
    std::memcpy(&v, b_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  // Expects the exact text (after white space).
  void expect(const std::string& text, const std::string& where) {
    skip_space();
    if (b_.compare(pos_, text.size(), text) != 0)
      fail(where, "\"" + text + "\"", "\"" + b_.substr(pos_, std::min<std::size_t>(24, remaining())) + "\"");
    pos_ += text.size();
  }
  // Skips to just after "$End<name>" (for sections tactus does not use).
  void skip_section(const std::string& name) {
    const std::string end = "$End" + name;
    const std::size_t at = b_.find(end, pos_);
    if (at == std::string::npos) fail("$" + name, "a closing " + end, "none");
    pos_ = at + end.size();
  }
  // Guards an allocation: `count` items of at least `min_bytes` each must fit in what remains.
  void check_count(std::uint64_t count, std::size_t min_bytes, const std::string& where) const {
    if (count > remaining() / std::max<std::size_t>(min_bytes, 1))
      fail(where, "a count the file can hold (" + std::to_string(remaining()) + " bytes remain)", std::to_string(count));
  }

 private:
  const std::string& b_;
  std::string file_;
  std::size_t pos_ = 0;
};

// What the sections give, before assembling the TetMesh.
struct RawMesh {
  std::map<std::pair<int, int>, std::string> names;                 // (dim, physical tag) -> name
  std::map<std::pair<int, int>, std::vector<int>> entity_physical;  // (dim, entity tag) -> physical tags (4.1)
  std::vector<std::uint64_t> node_tags;
  std::vector<Vec3> coords;
  struct Element {
    int dim, entity, physical;  // physical: 2.2's own tag; -1 in 4.1 (from the entity)
    std::size_t first;          // into `element_nodes`
  };
  std::vector<Element> tets, triangles;
  std::vector<std::uint64_t> element_nodes;
};

// Reads a number that is ASCII or binary depending on the file.
struct Number {
  Cursor& c;
  bool binary;
  std::size_t size_t_bytes;
  std::uint64_t size(const std::string& where, std::uint64_t hi = std::numeric_limits<std::int64_t>::max()) {
    if (!binary) return c.ascii_integer<std::uint64_t>(where, 0, hi);
    const std::uint64_t v = size_t_bytes == 8 ? c.binary<std::uint64_t>(where) : c.binary<std::uint32_t>(where);
    if (v > hi) c.fail(where, "at most " + std::to_string(hi), std::to_string(v));
    return v;
  }
  int integer(const std::string& where, int lo = std::numeric_limits<int>::min(), int hi = std::numeric_limits<int>::max()) {
    if (!binary) return c.ascii_integer<int>(where, lo, hi);
    const int v = c.binary<std::int32_t>(where);
    if (v < lo || v > hi) c.fail(where, "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]", std::to_string(v));
    return v;
  }
  double real(const std::string& where) {
    if (!binary) return c.ascii_double(where);
    const double v = c.binary<double>(where);
    if (!std::isfinite(v)) c.fail(where, "a finite number", "NaN or infinity");
    return v;
  }
  std::size_t min_size() const { return binary ? size_t_bytes : 2; }  // an ASCII number takes >= 2 bytes with its separator
  std::size_t min_int() const { return binary ? 4 : 2; }
  std::size_t min_real() const { return binary ? 8 : 2; }
};

void read_physical_names(Cursor& c, RawMesh& raw) {
  const int n = c.ascii_integer<int>("$PhysicalNames count", 0, 1 << 24);
  c.check_count(static_cast<std::uint64_t>(n), 6, "$PhysicalNames count");
  for (int i = 0; i < n; ++i) {
    const std::string where = "$PhysicalNames entry " + std::to_string(i + 1);
    const int dim = c.ascii_integer<int>(where + " dimension", 0, 3);
    const int tag = c.ascii_integer<int>(where + " tag", 1, std::numeric_limits<int>::max());
    c.skip_space();
    std::string_view rest = c.line();
    const auto open = rest.find('"'), close = rest.rfind('"');
    if (open == std::string_view::npos || close == open) c.fail(where + " name", "a quoted name", std::string(rest.substr(0, 40)));
    std::string name(rest.substr(open + 1, close - open - 1));
    if (name.size() > 256) c.fail(where + " name", "a name of at most 256 characters");
    raw.names[{dim, tag}] = name;
  }
  c.expect("$EndPhysicalNames", "$PhysicalNames");
}

void read_entities(Cursor& c, Number& num, RawMesh& raw) {
  std::uint64_t count[4];
  for (int d = 0; d < 4; ++d) count[d] = num.size("$Entities counts");
  for (int d = 0; d < 4; ++d) {
    c.check_count(count[d], 4 * num.min_real(), "$Entities count of dimension " + std::to_string(d));
    for (std::uint64_t i = 0; i < count[d]; ++i) {
      const std::string where = "$Entities dimension " + std::to_string(d) + " entity " + std::to_string(i + 1);
      const int tag = num.integer(where + " tag", 1);
      for (int k = 0; k < (d == 0 ? 3 : 6); ++k) num.real(where + " coordinates");
      const std::uint64_t np = num.size(where + " physical tag count", 1 << 20);
      c.check_count(np, num.min_int(), where);
      std::vector<int> phys;
      for (std::uint64_t k = 0; k < np; ++k) phys.push_back(num.integer(where + " physical tag", 1));
      if (d > 0) {
        const std::uint64_t nb = num.size(where + " bounding entity count", 1 << 24);
        c.check_count(nb, num.min_int(), where);
        for (std::uint64_t k = 0; k < nb; ++k) num.integer(where + " bounding entity");  // signed: orientation
      }
      if (!raw.entity_physical.emplace(std::pair{d, tag}, std::move(phys)).second)
        c.fail(where, "unique entity tags per dimension", "tag " + std::to_string(tag) + " twice");
    }
  }
  c.expect("$EndEntities", "$Entities");
}

void read_nodes_41(Cursor& c, Number& num, RawMesh& raw) {
  const std::uint64_t blocks = num.size("$Nodes block count");
  const std::uint64_t total = num.size("$Nodes node count");
  num.size("$Nodes min tag"), num.size("$Nodes max tag");
  c.check_count(total, 4 * num.min_real(), "$Nodes node count");
  c.check_count(blocks, 4 * num.min_int(), "$Nodes block count");
  raw.node_tags.reserve(total);
  raw.coords.reserve(total);
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const std::string where = "$Nodes block " + std::to_string(b + 1);
    const int dim = num.integer(where + " entity dimension", 0, 3);
    num.integer(where + " entity tag");
    const int parametric = num.integer(where + " parametric flag", 0, 1);
    const std::uint64_t n = num.size(where + " node count");
    if (raw.node_tags.size() + n > total) c.fail(where, "blocks adding up to the declared " + std::to_string(total) + " nodes", "more");
    c.check_count(n, num.min_size() + 3 * num.min_real(), where);
    for (std::uint64_t i = 0; i < n; ++i) raw.node_tags.push_back(num.size(where + " node tag"));
    const int params = parametric ? dim : 0;
    for (std::uint64_t i = 0; i < n; ++i) {
      Vec3 x{num.real(where + " x"), num.real(where + " y"), num.real(where + " z")};
      for (int k = 0; k < params; ++k) num.real(where + " parametric coordinate");
      raw.coords.push_back(x);
    }
  }
  if (raw.node_tags.size() != total) c.fail("$Nodes", std::to_string(total) + " nodes as declared", std::to_string(raw.node_tags.size()));
  c.expect("$EndNodes", "$Nodes");
}

void read_elements_41(Cursor& c, Number& num, RawMesh& raw) {
  const std::uint64_t blocks = num.size("$Elements block count");
  const std::uint64_t total = num.size("$Elements element count");
  num.size("$Elements min tag"), num.size("$Elements max tag");
  c.check_count(total, 2 * num.min_size(), "$Elements element count");
  c.check_count(blocks, 4 * num.min_int(), "$Elements block count");
  std::uint64_t seen = 0;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const std::string where = "$Elements block " + std::to_string(b + 1);
    const int dim = num.integer(where + " entity dimension", 0, 3);
    const int entity = num.integer(where + " entity tag");
    const int type = num.integer(where + " element type", 1);
    const std::uint64_t n = num.size(where + " element count");
    const int nn = nodes_per_element(type);
    if (nn == 0) c.fail(where, "a known gmsh element type (1-19)", std::to_string(type));
    if (type == 11) c.fail(where, "linear tetrahedra (type 4); tactus uses first-order tets", "10-node tetrahedra (type 11)");
    seen += n;
    if (seen > total) c.fail(where, "blocks adding up to the declared " + std::to_string(total) + " elements", "more");
    c.check_count(n, static_cast<std::size_t>(1 + nn) * num.min_size(), where);
    auto& list = type == kTet ? raw.tets : raw.triangles;
    const bool keep = type == kTet || type == kTriangle;
    if (keep && ((type == kTet && dim != 3) || (type == kTriangle && dim != 2)))
      c.fail(where, "tetrahedra on volume entities and triangles on surface entities",
             "type " + std::to_string(type) + " on a dimension-" + std::to_string(dim) + " entity");
    for (std::uint64_t i = 0; i < n; ++i) {
      num.size(where + " element tag");
      if (keep) list.push_back({dim, entity, -1, raw.element_nodes.size()});
      for (int k = 0; k < nn; ++k) {
        const std::uint64_t node = num.size(where + " node tag");
        if (keep) raw.element_nodes.push_back(node);
      }
    }
  }
  if (seen != total) c.fail("$Elements", std::to_string(total) + " elements as declared", std::to_string(seen));
  c.expect("$EndElements", "$Elements");
}

void read_nodes_22(Cursor& c, bool binary, RawMesh& raw) {
  const auto n = c.ascii_integer<std::uint64_t>("$Nodes count", 0, std::numeric_limits<std::int64_t>::max());
  Number num{c, binary, 4};
  c.check_count(n, binary ? 28 : 8, "$Nodes count");
  if (binary) c.line();
  for (std::uint64_t i = 0; i < n; ++i) {
    const std::string where = "$Nodes node " + std::to_string(i + 1);
    raw.node_tags.push_back(binary ? static_cast<std::uint64_t>(c.binary<std::int32_t>(where))
                                   : c.ascii_integer<std::uint64_t>(where, 0, std::numeric_limits<std::int64_t>::max()));
    raw.coords.push_back({num.real(where), num.real(where), num.real(where)});
  }
  c.expect("$EndNodes", "$Nodes");
}

void read_elements_22(Cursor& c, bool binary, RawMesh& raw) {
  const auto n = c.ascii_integer<std::uint64_t>("$Elements count", 0, std::numeric_limits<std::int64_t>::max());
  c.check_count(n, binary ? 12 : 8, "$Elements count");
  if (binary) c.line();
  std::uint64_t done = 0;
  auto element = [&](int type, const std::vector<int>& tags, const std::vector<std::uint64_t>& nodes) {
    if (type == kTet || type == kTriangle) {
      const int physical = tags.empty() ? 0 : tags[0];
      const int entity = tags.size() > 1 ? tags[1] : 0;
      (type == kTet ? raw.tets : raw.triangles).push_back({type == kTet ? 3 : 2, entity, physical, raw.element_nodes.size()});
      raw.element_nodes.insert(raw.element_nodes.end(), nodes.begin(), nodes.end());
    }
  };
  std::vector<int> tags;
  std::vector<std::uint64_t> nodes;
  while (done < n) {
    const std::string where = "$Elements element " + std::to_string(done + 1);
    if (binary) {
      const int type = c.binary<std::int32_t>(where + " type"), follow = c.binary<std::int32_t>(where + " count"),
                ntags = c.binary<std::int32_t>(where + " tag count");
      const int nn = nodes_per_element(type);
      if (nn == 0) c.fail(where, "a known gmsh element type (1-19)", std::to_string(type));
      if (follow < 0 || static_cast<std::uint64_t>(follow) > n - done || ntags < 0 || ntags > 64)
        c.fail(where, "a valid element block header", std::to_string(follow) + " elements with " + std::to_string(ntags) + " tags");
      c.check_count(static_cast<std::uint64_t>(follow), static_cast<std::size_t>(4 * (1 + ntags + nn)), where);
      for (int e = 0; e < follow; ++e) {
        c.binary<std::int32_t>(where);
        tags.clear(), nodes.clear();
        for (int k = 0; k < ntags; ++k) tags.push_back(c.binary<std::int32_t>(where + " tag"));
        for (int k = 0; k < nn; ++k) {
          const int v = c.binary<std::int32_t>(where + " node");
          if (v < 0) c.fail(where, "node numbers >= 0", std::to_string(v));
          nodes.push_back(static_cast<std::uint64_t>(v));
        }
        element(type, tags, nodes);
      }
      done += static_cast<std::uint64_t>(follow);
    } else {
      c.ascii_integer<std::uint64_t>(where + " number", 0, std::numeric_limits<std::int64_t>::max());
      const int type = c.ascii_integer<int>(where + " type", 1, 1000);
      const int nn = nodes_per_element(type);
      if (nn == 0) c.fail(where, "a known gmsh element type (1-19)", std::to_string(type));
      const int ntags = c.ascii_integer<int>(where + " tag count", 0, 64);
      tags.clear(), nodes.clear();
      for (int k = 0; k < ntags; ++k)
        tags.push_back(c.ascii_integer<int>(where + " tag", std::numeric_limits<int>::min(), std::numeric_limits<int>::max()));
      for (int k = 0; k < nn; ++k) nodes.push_back(c.ascii_integer<std::uint64_t>(where + " node", 0, std::numeric_limits<std::int64_t>::max()));
      element(type, tags, nodes);
      ++done;
    }
  }
  c.expect("$EndElements", "$Elements");
}

// Builds the TetMesh: nodes by tag, elements by physical group in (dim, tag) order, file order
// within (the order libgmsh's API gave, so meshes read the same as before).
TetMesh assemble(const RawMesh& raw, bool v41, const std::string& fname) {
  TetMesh mesh;
  if (raw.node_tags.empty()) throw InputError(fname, "$Nodes", "at least one node", "none");
  std::unordered_map<std::uint64_t, int> index_of;
  index_of.reserve(raw.node_tags.size());
  for (std::size_t i = 0; i < raw.node_tags.size(); ++i) {
    if (!index_of.emplace(raw.node_tags[i], static_cast<int>(i)).second)
      throw InputError(fname, "$Nodes", "unique node tags", "tag " + std::to_string(raw.node_tags[i]) + " twice");
    for (double c : raw.coords[i])
      if (std::abs(c) > kMaxCoordinate)
        throw InputError(fname, "$Nodes node " + std::to_string(raw.node_tags[i]), "coordinates within 1e9 (of the mesh's unit)", std::to_string(c));
  }
  if (raw.node_tags.size() > static_cast<std::size_t>(std::numeric_limits<int>::max() / 4))
    throw InputError(fname, "$Nodes", "fewer than 500 million nodes");
  mesh.nodes = raw.coords;

  // Physical tags of each element.
  auto physical_tags = [&](const RawMesh::Element& e) -> std::vector<int> {
    if (!v41) return e.physical > 0 ? std::vector<int>{e.physical} : std::vector<int>{};
    auto it = raw.entity_physical.find({e.dim, e.entity});
    return it == raw.entity_physical.end() ? std::vector<int>{} : it->second;
  };
  std::set<std::pair<int, int>> groups;  // (dim, tag)
  if (v41) {
    for (const auto& [key, phys] : raw.entity_physical)
      if (key.first >= 2)
        for (int p : phys) groups.insert({key.first, p});
  } else {
    for (const auto* list : {&raw.tets, &raw.triangles})
      for (const auto& e : *list)
        if (e.physical > 0) groups.insert({e.dim, e.physical});
  }
  for (const auto& [dim, tag] : groups) {
    auto it = raw.names.find({dim, tag});
    mesh.groups.push_back(
        {dim, tag, it != raw.names.end() && !it->second.empty() ? it->second : (dim == 3 ? "volume_" : "surface_") + std::to_string(tag)});
  }
  auto node = [&](std::uint64_t tag, const char* what, std::size_t k) {
    auto it = index_of.find(tag);
    if (it == index_of.end())
      throw InputError(fname, std::string("$Elements ") + what + " " + std::to_string(k + 1), "node tags defined in $Nodes",
                       "tag " + std::to_string(tag));
    return it->second;
  };
  std::size_t unassigned = 0;
  // Elements grouped by physical tag (ascending), entity tag, then file order.
  for (int dim : {3, 2}) {
    const auto& list = dim == 3 ? raw.tets : raw.triangles;
    std::vector<std::pair<int, std::size_t>> order;  // (physical, element index), stable
    std::vector<std::pair<int, int>> keys;
    for (std::size_t k = 0; k < list.size(); ++k) {
      const auto phys = physical_tags(list[k]);
      if (phys.empty()) ++unassigned;
      if (dim == 3 && phys.size() > 1)
        throw InputError(fname, "$Elements tetrahedron " + std::to_string(k + 1), "one physical volume group per tet (its material)",
                         std::to_string(phys.size()) + " groups");
      for (int p : phys) order.push_back({p, k});
    }
    std::stable_sort(order.begin(), order.end(), [&](const auto& a, const auto& b) {
      if (a.first != b.first) return a.first < b.first;
      return list[a.second].entity < list[b.second].entity;
    });
    for (const auto& [p, k] : order) {
      const auto& e = list[k];
      if (dim == 3) {
        std::array<int, 4> t{};
        for (int a = 0; a < 4; ++a) t[a] = node(raw.element_nodes[e.first + a], "tetrahedron", k);
        mesh.tets.push_back(t);
        mesh.tet_group.push_back(p);
      } else {
        std::array<int, 3> t{};
        for (int a = 0; a < 3; ++a) t[a] = node(raw.element_nodes[e.first + a], "triangle", k);
        mesh.triangles.push_back(t);
        mesh.triangle_group.push_back(p);
      }
    }
  }
  if (mesh.tets.empty())
    throw InputError(fname, "physical volumes", "4-node tetrahedra in at least one physical volume group",
                     "none (tactus assigns materials by physical group)");
  (void)unassigned;
  mesh.validate(fname);
  return mesh;
}

}  // namespace

TetMesh read_msh(const fs::path& file) {
  const std::string fname = file.string();
  std::error_code ec;
  require_regular_file(file, "a mesh (.msh)");
  std::string bytes;
  {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw InputError(fname, "", "a readable .msh file", "cannot open it");
    const auto size = fs::file_size(file, ec);
    if (ec) throw InputError(fname, "", "a readable .msh file", ec.message());
    bytes.resize(size);
    in.read(bytes.data(), static_cast<std::streamsize>(size));
    if (static_cast<std::uintmax_t>(in.gcount()) != size) throw InputError(fname, "", "a readable .msh file", "a short read");
  }
  Cursor c(bytes, fname);
  c.expect("$MeshFormat", "start of file");
  const std::string_view version = c.token("$MeshFormat version");
  const bool v41 = version == "4.1";
  if (!v41 && version != "2.2")
    c.fail("$MeshFormat", "MSH version 4.1 or 2.2 (convert with: gmsh file.msh -save -format msh41)",
           "version " + std::string(version.substr(0, 20)));
  const int file_type = c.ascii_integer<int>("$MeshFormat file type", 0, 1);
  const int data_size = c.ascii_integer<int>("$MeshFormat data size", 4, 8);
  if (data_size != 8 && data_size != 4) c.fail("$MeshFormat data size", "4 or 8");
  const bool binary = file_type == 1;
  if (binary) {
    c.line();  // the rest of the version line
    if (c.binary<std::int32_t>("$MeshFormat endianness") != 1) c.fail("$MeshFormat", "a binary file of this machine's byte order (the integer 1)");
  }
  c.expect("$EndMeshFormat", "$MeshFormat");
  RawMesh raw;
  Number num{c, binary, static_cast<std::size_t>(data_size)};
  std::set<std::string> seen;
  while (!c.at_end()) {
    const std::string_view header = c.token("section header");
    if (header.empty() || header[0] != '$') c.fail("section header", "a $Section", "\"" + std::string(header.substr(0, 24)) + "\"");
    const std::string name(header.substr(1));
    c.line();  // the header's line: binary data starts on the next one
    if (name.rfind("End", 0) == 0) c.fail("section header", "a $Section", "an unmatched $" + name);
    const bool known = name == "PhysicalNames" || name == "Entities" || name == "Nodes" || name == "Elements";
    if (known && !seen.insert(name).second) c.fail("$" + name, "one $" + name + " section", "two");
    if (name == "PhysicalNames")
      read_physical_names(c, raw);
    else if (name == "Entities" && v41)
      read_entities(c, num, raw);
    else if (name == "Nodes") {
      if (v41)
        read_nodes_41(c, num, raw);
      else
        read_nodes_22(c, binary, raw);
    } else if (name == "Elements") {
      if (!seen.count("Nodes")) c.fail("$Elements", "$Nodes before $Elements");
      if (v41)
        read_elements_41(c, num, raw);
      else
        read_elements_22(c, binary, raw);
    } else if (name == "PartitionedEntities") {
      c.fail("$PartitionedEntities", "an unpartitioned mesh (tactus reads whole meshes)");
    } else {
      c.skip_section(name);
    }
  }
  if (!seen.count("Nodes") || !seen.count("Elements")) throw InputError(fname, "", "$Nodes and $Elements sections", "a mesh without them");
  return assemble(raw, v41, fname);
}

}  // namespace tactus
