#include "tactus/mesher/objects.hpp"
#include "tactus/core/file_io.hpp"

#include <gmsh.h>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/core/gmsh_session.hpp"

namespace tactus::mesher {

namespace {

constexpr int kSurfaceTag = 20;

// `fine_size` > 0: a background size field set by the caller goes down to it.
void mesh_volume(double element_size, const std::string& source, double fine_size = 0) {
  gmsh::option::setNumber("Mesh.MeshSizeMax", element_size);
  gmsh::option::setNumber("Mesh.MeshSizeMin", fine_size > 0 ? std::min(0.3 * element_size, fine_size) : 0.3 * element_size);
  gmsh::option::setNumber("Mesh.Algorithm3D", 1);  // Delaunay
  gmsh::option::setNumber("Mesh.Optimize", 1);
  gmsh::option::setNumber("Mesh.RandomSeed", 1);
  try {
    gmsh::model::mesh::generate(3);
  } catch (...) {
    throw InputError(source, "", "a volume gmsh can mesh", GmshSession::last_error());
  }
}

}  // namespace

namespace {

void check_expected_tets(double volume, double h, double max_elements, const std::string& source) {
  const double expected = 6.0 * volume / (h * h * h);
  if (expected > max_elements) {
    std::ostringstream f;
    f << "about " << expected << " tets for " << volume << " m^3 at element size " << h << " m";
    throw InputError(source, "element size",
                     "a mesh of at most " + std::to_string(static_cast<long long>(max_elements)) + " tets (raise --max-elements to allow more)",
                     f.str());
  }
}

}  // namespace

TetMesh mesh_box(const Vec3& size, const Vec3& origin, double h, const std::string& name, double max_elements, double edge_radius) {
  for (int a = 0; a < 3; ++a) {
    if (!(size[a] > 0) || !std::isfinite(size[a]) || size[a] > 1e3)
      throw InputError("box", "size", "edge lengths from 0 to 1000 m", std::to_string(size[a]));
    if (!std::isfinite(origin[a]) || std::abs(origin[a]) > 1e3)
      throw InputError("box", "origin", "a finite corner within 1 km", std::to_string(origin[a]));
  }
  if (!(h > 0) || h > 2 * std::max({size[0], size[1], size[2]}))
    throw InputError("box", "element size", "a size > 0 m and not larger than the box", std::to_string(h));
  if (!(edge_radius >= 0) || !(edge_radius < 0.5 * std::min({size[0], size[1], size[2]})))
    throw InputError("box", "edge radius", "from 0 to less than half the shortest edge", std::to_string(edge_radius));
  // The curved faces get elements of about half the radius (12 per 2 pi of arc): the expected
  // count adds their strips, a band of that size along the 12 edges.
  const double curved = 0.52 * edge_radius;
  check_expected_tets(size[0] * size[1] * size[2], h, max_elements, "box");
  if (edge_radius > 0) check_expected_tets(4 * (size[0] + size[1] + size[2]) * h * h, curved, max_elements, "box");
  GmshSession session;
  gmsh::model::add(name);
  int vol = gmsh::model::occ::addBox(origin[0], origin[1], origin[2], size[0], size[1], size[2]);
  if (edge_radius > 0) {  // every edge rounded (a real tool's edges are not sharp; the contact pressure under a sharp one is singular)
    gmsh::vectorpair edges, rounded;
    gmsh::model::occ::getEntities(edges, 1);
    std::vector<int> curves;
    for (const auto& [dim, tag] : edges) curves.push_back(tag);
    try {
      gmsh::model::occ::fillet({vol}, curves, {edge_radius}, rounded, true);
    } catch (...) {
      rounded.clear();
    }
    if (rounded.size() != 1 || rounded[0].first != 3)
      throw InputError("box", "edge radius", "edges gmsh can round", std::to_string(edge_radius) + " m: " + GmshSession::last_error());
    vol = rounded[0].second;
  }
  gmsh::model::occ::synchronize();
  gmsh::model::addPhysicalGroup(3, {vol}, 1);
  gmsh::model::setPhysicalName(3, 1, name);
  gmsh::vectorpair faces;
  gmsh::model::getBoundary({{3, vol}}, faces, false, false, false);
  std::vector<int> all, rounded_faces;
  const char* names[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  for (const auto& [dim, tag] : faces) {
    double b[6];
    gmsh::model::getBoundingBox(dim, tag, b[0], b[1], b[2], b[3], b[4], b[5]);
    all.push_back(tag);
    // OCC pads bounding boxes by its tolerance (~1e-7): compare at 1e-4 of the box size.
    const double tol = 1e-4 * std::min({size[0], size[1], size[2]});
    bool flat = false;
    for (int axis = 0; axis < 3; ++axis) flat = flat || std::abs(b[axis + 3] - b[axis]) <= tol;
    if (!flat) rounded_faces.push_back(tag);
    for (int axis = 0; axis < 3; ++axis) {
      if (std::abs(b[axis + 3] - b[axis]) > tol) continue;  // not flat along this axis
      const int side = std::abs(0.5 * (b[axis] + b[axis + 3]) - origin[axis]) < tol ? 0 : 1;
      gmsh::model::addPhysicalGroup(2, {tag}, 11 + 2 * axis + side);
      gmsh::model::setPhysicalName(2, 11 + 2 * axis + side, names[2 * axis + side]);
    }
  }
  gmsh::model::addPhysicalGroup(2, all, kSurfaceTag);
  gmsh::model::setPhysicalName(2, kSurfaceTag, "surface");
  if (edge_radius > 0) {
    // Elements of `curved` on the rounded faces, growing linearly to h over 2 h from them (the
    // flat faces' own sizes would otherwise spread the fine size over the whole block).
    gmsh::model::mesh::field::add("Distance", 1);
    gmsh::model::mesh::field::setNumbers(1, "SurfacesList", std::vector<double>(rounded_faces.begin(), rounded_faces.end()));
    gmsh::model::mesh::field::setNumber(1, "NumPointsPerCurve", 20);
    gmsh::model::mesh::field::add("Threshold", 2);
    gmsh::model::mesh::field::setNumber(2, "InField", 1);
    gmsh::model::mesh::field::setNumber(2, "SizeMin", curved);
    gmsh::model::mesh::field::setNumber(2, "SizeMax", h);
    gmsh::model::mesh::field::setNumber(2, "DistMin", 0);
    gmsh::model::mesh::field::setNumber(2, "DistMax", 2 * h);
    gmsh::model::mesh::field::setAsBackgroundMesh(2);
    gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
    gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
    gmsh::option::setNumber("Mesh.OptimizeThreshold", 0.5);  // the corners, where three rounded edges meet, leave slivers otherwise
  }
  mesh_volume(h, "box", edge_radius > 0 ? curved : 0);
  return tet_mesh_from_gmsh_model("box");
}

StlSurface read_stl(const std::filesystem::path& stl) {
  const std::string file = stl.string();
  std::error_code ec;
  require_regular_file(stl, "an STL surface");
  std::ifstream in(stl, std::ios::binary);
  const std::string b((std::istreambuf_iterator<char>(in)), {});
  std::vector<Vec3> corners;  // 3 per triangle
  auto add_corner = [&](const Vec3& x, std::size_t triangle) {
    for (double c : x)
      if (!std::isfinite(c) || std::abs(c) > 1e9)
        throw InputError(file, "triangle " + std::to_string(triangle + 1), "finite coordinates within 1e9", std::to_string(c));
    corners.push_back(x);
  };
  // Binary: 80-byte header, uint32 count, 50 bytes per triangle; the size must match exactly.
  std::uint32_t count = 0;
  if (b.size() >= 84) std::memcpy(&count, b.data() + 80, 4);
  const bool binary = b.size() >= 84 && b.size() == 84 + 50 * static_cast<std::uint64_t>(count);
  if (binary) {
    for (std::uint32_t t = 0; t < count; ++t) {
      const char* p = b.data() + 84 + 50 * static_cast<std::size_t>(t) + 12;  // after the normal
      for (int k = 0; k < 3; ++k) {
        float v[3];
        std::memcpy(v, p + 12 * k, 12);
        add_corner({v[0], v[1], v[2]}, t);
      }
    }
  } else {
    std::istringstream text(b);
    std::string word;
    if (!(text >> word) || word != "solid")
      throw InputError(
          file, "", "an STL file (ASCII starting with 'solid', or binary with 84 + 50 n bytes)",
          b.size() >= 84 ? "a binary header declaring " + std::to_string(count) + " triangles in " + std::to_string(b.size()) + " bytes" : "neither");
    std::size_t t = 0;
    while (text >> word) {
      if (word != "vertex") continue;
      Vec3 x{};
      std::string token;
      for (double& c : x) {
        if (!(text >> token)) throw InputError(file, "vertex " + std::to_string(corners.size() + 1), "three coordinates", "the end of the file");
        const auto [end, err] = std::from_chars(token.data(), token.data() + token.size(), c);
        if (err != std::errc() || end != token.data() + token.size())
          throw InputError(file, "vertex " + std::to_string(corners.size() + 1), "a number", "\"" + token.substr(0, 30) + "\"");
      }
      add_corner(x, t);
      if (corners.size() % 3 == 0) ++t;
    }
    if (corners.size() % 3 != 0) throw InputError(file, "", "three vertices per facet", std::to_string(corners.size()) + " vertices");
  }
  if (corners.empty()) throw InputError(file, "", "a readable STL surface", "no triangles");
  if (corners.size() / 3 > 50'000'000) throw InputError(file, "", "at most 50 million triangles", std::to_string(corners.size() / 3));
  StlSurface s;
  std::map<Vec3, int> index;
  for (std::size_t t = 0; t < corners.size() / 3; ++t) {
    std::array<int, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      auto [it, added] = index.emplace(corners[3 * t + k], static_cast<int>(s.vertices.size()));
      if (added) s.vertices.push_back(corners[3 * t + k]);
      tri[k] = it->second;
    }
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;  // degenerate facet
    s.triangles.push_back(tri);
  }
  std::map<std::pair<int, int>, int> edges;
  for (const auto& t : s.triangles)
    for (int k = 0; k < 3; ++k) ++edges[{std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])}];
  for (const auto& [e, n] : edges) s.boundary_edges += n == 1, s.non_manifold_edges += n > 2;
  return s;
}

TetMesh mesh_stl_object(const std::filesystem::path& stl, double h, double scale, const std::string& name, double max_elements) {
  const std::string file = stl.string();
  if (!(h > 0) || !std::isfinite(h)) throw InputError(file, "element size", "a size > 0 m", std::to_string(h));
  if (!(scale > 0) || !std::isfinite(scale)) throw InputError(file, "scale", "a factor > 0", std::to_string(scale));
  // Read and checked by tactus: gmsh only ever sees the validated triangles.
  const StlSurface surface = read_stl(stl);
  if (const std::size_t n = surface.boundary_edges + surface.non_manifold_edges; n > 0)
    throw InputError(file, "", "a closed 2-manifold surface", std::to_string(n) + " open or non-manifold edges");
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (const auto& x : surface.vertices)
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], x[c] * scale), hi[c] = std::max(hi[c], x[c] * scale);
  double volume = 0;  // enclosed volume (divergence theorem), for the size guard
  for (const auto& t : surface.triangles) {
    const Vec3 &a = surface.vertices[t[0]], &b = surface.vertices[t[1]], &c = surface.vertices[t[2]];
    volume += tet_volume({0, 0, 0}, a, b, c);
  }
  volume = std::abs(volume) * scale * scale * scale;
  if (!(volume > 0)) throw InputError(file, "", "a surface enclosing a volume", "zero volume");
  check_expected_tets(volume, h, max_elements, file);
  GmshSession session;
  gmsh::model::add(name);
  gmsh::model::addDiscreteEntity(2, 1);
  std::vector<std::size_t> node_tags(surface.vertices.size()), element_tags(surface.triangles.size()), element_nodes;
  std::vector<double> coords;
  for (std::size_t i = 0; i < surface.vertices.size(); ++i) {
    node_tags[i] = i + 1;
    coords.insert(coords.end(), surface.vertices[i].begin(), surface.vertices[i].end());
  }
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    element_tags[t] = t + 1;
    for (int v : surface.triangles[t]) element_nodes.push_back(static_cast<std::size_t>(v) + 1);
  }
  gmsh::model::mesh::addNodes(2, 1, node_tags, coords);
  gmsh::model::mesh::addElementsByType(1, 2, element_tags, element_nodes);
  // Patches split until each is parametrizable: a smooth closed surface (a sphere, a cylinder
  // handle's round end) has no feature edge to split it, and gmsh cannot parametrize it whole.
  try {
    gmsh::model::mesh::classifySurfaces(40.0 * M_PI / 180.0, true, true, M_PI);
    gmsh::model::mesh::createGeometry();
  } catch (...) {  // gmsh's API throws strings
    throw InputError(file, "", "a surface gmsh can rebuild for meshing", GmshSession::last_error());
  }
  gmsh::vectorpair surfaces;
  gmsh::model::getEntities(surfaces, 2);
  std::vector<int> tags;
  for (const auto& [dim, tag] : surfaces) tags.push_back(tag);
  const int loop = gmsh::model::geo::addSurfaceLoop(tags);
  const int vol = gmsh::model::geo::addVolume({loop});
  gmsh::model::geo::synchronize();
  gmsh::model::addPhysicalGroup(3, {vol}, 1);
  gmsh::model::setPhysicalName(3, 1, name);
  gmsh::model::addPhysicalGroup(2, tags, kSurfaceTag);
  gmsh::model::setPhysicalName(2, kSurfaceTag, "surface");
  mesh_volume(h / scale, file);
  TetMesh mesh = tet_mesh_from_gmsh_model(file);
  for (auto& x : mesh.nodes)
    for (double& c : x) c *= scale;
  return mesh;
}

namespace {
std::string exact_text(double x) {  // every digit of x, for a gmsh MathEval expression
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", x);
  return text;
}

// The sleeve at sleeve_h, the core at h: a constant restricted to the sleeve, its faces and their
// curves (gmsh 4.8 has no "Constant" field), under a Min with h everywhere.
void size_sleeve(int sleeve, double sleeve_h, double h) {
  gmsh::vectorpair sleeve_faces, sleeve_curves;
  gmsh::model::getBoundary({{3, sleeve}}, sleeve_faces, false, false, false);
  gmsh::model::getBoundary(sleeve_faces, sleeve_curves, false, false, false);
  std::vector<double> face_tags, curve_tags;
  for (const auto& [dim, tag] : sleeve_faces) face_tags.push_back(std::abs(tag));
  for (const auto& [dim, tag] : sleeve_curves) curve_tags.push_back(std::abs(tag));
  namespace field = gmsh::model::mesh::field;
  field::add("MathEval", 1);
  field::setString(1, "F", exact_text(sleeve_h));
  field::add("Restrict", 2);
  field::setNumber(2, "InField", 1);
  field::setNumbers(2, "VolumesList", {static_cast<double>(sleeve)});
  field::setNumbers(2, "SurfacesList", face_tags);
  field::setNumbers(2, "CurvesList", curve_tags);
  field::add("MathEval", 3);
  field::setString(3, "F", exact_text(h));
  field::add("Min", 4);
  field::setNumbers(4, "FieldsList", {2, 3});
  field::setAsBackgroundMesh(4);
  gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
}
}  // namespace

TetMesh mesh_cylinder(const CylinderSpec& c, double max_elements) {
  const double r = c.radius, len = c.length, t = c.sleeve, h = c.element_size;
  if (!(r > 0) || !(r < 10)) throw InputError("cylinder", "radius", "a radius from 0 to 10 m", std::to_string(r));
  if (!(len > 0) || !(len < 100)) throw InputError("cylinder", "length", "a length from 0 to 100 m", std::to_string(len));
  if (!(t >= 0) || !(t < r))
    throw InputError("cylinder", "sleeve", "a thickness from 0 to less than the radius", std::to_string(t) + " m of " + std::to_string(r));
  if (!(h > 0) || h > 2 * std::max(r, len))
    throw InputError("cylinder", "element size", "a size > 0 m and not larger than the cylinder", std::to_string(h));
  if (c.axis < 0 || c.axis > 2) throw InputError("cylinder", "axis", "x, y or z", std::to_string(c.axis));
  for (double x : c.centre)
    if (!std::isfinite(x) || std::abs(x) > 1e3) throw InputError("cylinder", "centre", "a finite point within 1 km", std::to_string(x));
  const double sleeve_h = t > 0 ? std::min(h, 0.5 * t) : h;
  check_expected_tets(M_PI * r * r * len, h, max_elements, "cylinder");
  if (t > 0) check_expected_tets(M_PI * (r * r - (r - t) * (r - t)) * len, sleeve_h, max_elements, "cylinder sleeve");
  GmshSession session;
  gmsh::model::add("cylinder");
  Vec3 base = c.centre, along{0, 0, 0};
  base[c.axis] -= 0.5 * len, along[c.axis] = len;
  const int outer = gmsh::model::occ::addCylinder(base[0], base[1], base[2], along[0], along[1], along[2], r);
  std::vector<std::pair<int, std::string>> volumes;  // tag, group name
  if (t > 0) {
    // The core cut into the outer cylinder by fragment: one shared interface, so the two
    // volumes' meshes conform there (the sleeve bonded to its core).
    const int core = gmsh::model::occ::addCylinder(base[0], base[1], base[2], along[0], along[1], along[2], r - t);
    gmsh::vectorpair pieces;
    std::vector<gmsh::vectorpair> map;
    gmsh::model::occ::fragment({{3, outer}}, {{3, core}}, pieces, map);
    gmsh::model::occ::synchronize();
    for (const auto& [dim, tag] : pieces) {
      if (dim != 3) continue;
      double mass = 0;
      gmsh::model::occ::getMass(3, tag, mass);
      const bool is_core = std::abs(mass - M_PI * (r - t) * (r - t) * len) < 1e-3 * M_PI * r * r * len;
      volumes.push_back({tag, is_core ? "core" : "sleeve"});
    }
    std::sort(volumes.begin(), volumes.end(), [](const auto& a, const auto& b) { return a.second < b.second; });  // core, sleeve
    if (volumes.size() != 2 || volumes[0].second != "core" || volumes[1].second != "sleeve")
      throw InputError("cylinder", "sleeve", "a core and a sleeve gmsh can build", std::to_string(volumes.size()) + " volumes");
  } else {
    gmsh::model::occ::synchronize();
    volumes.push_back({outer, "object"});
  }
  gmsh::vectorpair all_volumes, outside;
  for (std::size_t g = 0; g < volumes.size(); ++g) {
    gmsh::model::addPhysicalGroup(3, {volumes[g].first}, static_cast<int>(g) + 1);
    gmsh::model::setPhysicalName(3, static_cast<int>(g) + 1, volumes[g].second);
    all_volumes.push_back({3, volumes[g].first});
  }
  gmsh::model::getBoundary(all_volumes, outside, true, false, false);  // combined: the interface drops out
  std::vector<int> faces;
  for (const auto& [dim, tag] : outside) faces.push_back(std::abs(tag));
  gmsh::model::addPhysicalGroup(2, faces, kSurfaceTag);
  gmsh::model::setPhysicalName(2, kSurfaceTag, "surface");
  if (t > 0) size_sleeve(volumes[1].first, sleeve_h, h);
  // Curved faces at about 16 elements around (a polygonal handle's contact pressure peaks at its edges).
  gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 16);
  mesh_volume(h, "cylinder", sleeve_h);
  return tet_mesh_from_gmsh_model("cylinder");
}

}  // namespace tactus::mesher
