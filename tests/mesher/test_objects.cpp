// mesher/objects: gmsh meshes of the block and of closed STL objects: exact volumes of their
// planar-faced domains, the physical groups, and refusal of open or unreadable STL files.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <map>

#include "tactus/core/error.hpp"
#include "tactus/mesher/objects.hpp"
#include "tactus/mesher/quality.hpp"
#include "temp_dir.hpp"

using namespace tactus;

namespace {
double volume(const TetMesh& m) {
  double v = 0;
  for (const auto& t : m.tets)
    v += tet_volume(m.nodes[static_cast<std::size_t>(t[0])], m.nodes[static_cast<std::size_t>(t[1])], m.nodes[static_cast<std::size_t>(t[2])],
                    m.nodes[static_cast<std::size_t>(t[3])]);
  return v;
}
// An ASCII STL of the unit cube scaled by s (12 outward triangles), optionally missing one.
void write_cube_stl(const std::filesystem::path& file, double s, bool open) {
  const double c[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  const int tris[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                           {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  std::ofstream o(file);
  o << "solid cube\n";
  for (int t = 0; t < (open ? 11 : 12); ++t) {
    o << " facet normal 0 0 0\n  outer loop\n";
    for (int v : tris[t]) o << "   vertex " << s * c[v][0] << ' ' << s * c[v][1] << ' ' << s * c[v][2] << '\n';
    o << "  endloop\n endfacet\n";
  }
  o << "endsolid cube\n";
}
}  // namespace

TEST(Objects, BoxVolumeAndGroups) {
  const TetMesh m = mesher::mesh_box({0.1, 0.06, 0.04}, {0.01, -0.03, 0}, 0.01);
  EXPECT_NEAR(volume(m), 0.1 * 0.06 * 0.04, 1e-12);  // planar faces: exact up to round-off
  for (const char* g : {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax", "surface"}) EXPECT_NE(m.find_group(2, g), nullptr) << g;
  ASSERT_NE(m.find_group(3, "block"), nullptr);
  EXPECT_EQ(mesher::quality_report(m, {})["all"]["inverted"].get<std::size_t>(), 0u);
  // The xmax face's triangles lie on x = 0.11 and cover its area.
  double area = 0;
  ASSERT_NE(m.find_group(2, "xmax"), nullptr);
  const int tag = m.find_group(2, "xmax")->tag;
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    if (m.triangle_group[t] != tag) continue;
    const auto& f = m.triangles[t];
    for (int v : f) EXPECT_NEAR(m.nodes[static_cast<std::size_t>(v)][0], 0.11, 1e-12);
    const auto &a = m.nodes[static_cast<std::size_t>(f[0])], &b = m.nodes[static_cast<std::size_t>(f[1])],
               &c = m.nodes[static_cast<std::size_t>(f[2])];
    area += 0.5 * std::abs((b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]));
  }
  EXPECT_NEAR(area, 0.06 * 0.04, 1e-12);
}

// Rounded edges (--edge-radius). Oracle: Steiner's formula for the volume of a box whose edges
// and corners are rounded with radius r (the inner box grown by a ball of radius r); the mesh's
// surface nodes lie on the rounded faces and its chords inside them, so its volume lies just below
// (within a quarter of what the rounding removes), and the flat face groups keep exactly their
// (b - 2r)(c - 2r) areas.
TEST(Objects, BoxWithRoundedEdges) {
  const double a = 0.1, b = 0.06, c = 0.04, r = 0.005;
  const TetMesh m = mesher::mesh_box({a, b, c}, {0.01, -0.03, 0}, 0.01, "block", 1e7, r);
  const double ai = a - 2 * r, bi = b - 2 * r, ci = c - 2 * r, pi = std::acos(-1.0);
  const double steiner = ai * bi * ci + 2 * r * (ai * bi + bi * ci + ci * ai) + pi * r * r * (ai + bi + ci) + 4.0 / 3.0 * pi * r * r * r;
  const double removed = a * b * c - steiner;
  std::printf("rounded box: %zu tets, volume %.6e m^3 (Steiner %.6e, sharp %.6e: %.2f %% of the rounding's %.3e m^3 missing)\n", m.tets.size(),
              volume(m), steiner, a * b * c, 100 * (steiner - volume(m)) / removed, removed);
  EXPECT_LE(volume(m), steiner * (1 + 1e-12));
  EXPECT_GE(volume(m), steiner - 0.25 * removed);
  for (const char* g : {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax", "surface"}) EXPECT_NE(m.find_group(2, g), nullptr) << g;
  EXPECT_EQ(mesher::quality_report(m, {})["all"]["inverted"].get<std::size_t>(), 0u);
  double area = 0;
  const int tag = m.find_group(2, "xmax")->tag;
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    if (m.triangle_group[t] != tag) continue;
    const auto& f = m.triangles[t];
    const auto &p = m.nodes[static_cast<std::size_t>(f[0])], &q = m.nodes[static_cast<std::size_t>(f[1])],
               &s = m.nodes[static_cast<std::size_t>(f[2])];
    for (int v : f) EXPECT_NEAR(m.nodes[static_cast<std::size_t>(v)][0], 0.11, 1e-12);
    area += 0.5 * std::abs((q[1] - p[1]) * (s[2] - p[2]) - (q[2] - p[2]) * (s[1] - p[1]));
  }
  EXPECT_NEAR(area, bi * ci, 1e-12);
  EXPECT_THROW(mesher::mesh_box({a, b, c}, {0, 0, 0}, 0.01, "block", 1e7, 0.5 * c), InputError);  // no flat part left
  EXPECT_THROW(mesher::mesh_box({a, b, c}, {0, 0, 0}, 0.01, "block", 1e7, -1e-3), InputError);
}

TEST(Objects, ClosedStlObject) {
  testkit::TempDir dir;
  write_cube_stl(dir / "cube.stl", 30.0, false);  // a 30 mm cube, in mm
  const TetMesh m = mesher::mesh_stl_object(dir / "cube.stl", 0.008, 1e-3);
  EXPECT_NEAR(volume(m), 0.03 * 0.03 * 0.03, 1e-12);
  EXPECT_NE(m.find_group(2, "surface"), nullptr);
}

TEST(Objects, OpenStlRefused) {
  testkit::TempDir dir;
  write_cube_stl(dir / "open.stl", 30.0, true);
  try {
    mesher::mesh_stl_object(dir / "open.stl", 0.008, 1e-3);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("closed 2-manifold"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("3 open"), std::string::npos) << e.what();
  }
}

TEST(Objects, UnreadableStlRefused) {
  testkit::TempDir dir;
  std::ofstream(dir / "junk.stl") << "\x01\x02 this is not an STL";
  EXPECT_THROW(mesher::mesh_stl_object(dir / "junk.stl", 0.008, 1e-3), InputError);
  EXPECT_THROW(mesher::mesh_stl_object(dir / "missing.stl", 0.008, 1e-3), InputError);
}

TEST(Objects, BadBoxParameters) {
  EXPECT_THROW(mesher::mesh_box({0.1, 0, 0.1}, {0, 0, 0}, 0.01), InputError);
  EXPECT_THROW(mesher::mesh_box({0.1, 0.1, 0.1}, {0, 0, 0}, -1), InputError);
}

// Runaway guard: a 1e12-tet box is refused before gmsh starts (it used to run out of memory).
TEST(Objects, HugeMeshesAreRefusedUpFront) {
  try {
    mesher::mesh_box({1, 1, 1}, {0, 0, 0}, 1e-4);
    FAIL() << "expected a refusal";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--max-elements"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("6e+12 tets"), std::string::npos) << e.what();
  }
}

// tactus's STL reader: binary and ASCII give the same closed surface; a binary header whose
// count does not match the file size is refused (no third-party reader sees it).
TEST(Objects, StlReaderBinaryAndAscii) {
  testkit::TempDir dir;
  write_cube_stl(dir / "a.stl", 2.0, false);
  const auto a = mesher::read_stl(dir / "a.stl");
  EXPECT_EQ(a.vertices.size(), 8u);
  EXPECT_EQ(a.triangles.size(), 12u);
  EXPECT_EQ(a.boundary_edges + a.non_manifold_edges, 0u);
  {
    std::ofstream o(dir / "b.stl", std::ios::binary);
    o << std::string(80, ' ');
    const std::uint32_t n = 12;
    o.write(reinterpret_cast<const char*>(&n), 4);
    for (const auto& t : a.triangles) {
      float rec[12] = {0, 0, 0};
      for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) rec[3 + 3 * k + c] = static_cast<float>(a.vertices[t[k]][c]);
      o.write(reinterpret_cast<const char*>(rec), 48);
      o.write("\0\0", 2);
    }
  }
  const auto b = mesher::read_stl(dir / "b.stl");
  EXPECT_EQ(b.vertices, a.vertices);
  EXPECT_EQ(b.triangles, a.triangles);
  std::filesystem::resize_file(dir / "b.stl", 84 + 50 * 11);
  {
    std::fstream f(dir / "b.stl", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(80);
    const std::uint32_t n = 4000000000u;  // far more than the file holds
    f.write(reinterpret_cast<const char*>(&n), 4);
  }
  EXPECT_THROW(mesher::read_stl(dir / "b.stl"), InputError);
}

// A smooth closed surface (no feature edge: a sphere, a cylinder's rounded end) could not be
// rebuilt for meshing (gmsh threw from its parametrization and the tool aborted). Oracle: the
// volume the facets enclose; gmsh re-meshes the rebuilt surface with chords of its own, which
// lose (h / R)^2 / 8 ~ 0.3 % of the volume at h = 1.5 mm, R = 10 mm: 1 % tolerance.
TEST(Objects, SmoothClosedStlMeshes) {
  testkit::TempDir dir;
  // An icosphere of radius 10 mm, 3 subdivisions (1280 facets), ASCII.
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<std::array<double, 3>> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                          {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                       {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                       {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  auto unit = [](std::array<double, 3> p) {
    const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return std::array<double, 3>{p[0] / n, p[1] / n, p[2] / n};
  };
  for (auto& p : v) p = unit(p);
  for (int level = 0; level < 3; ++level) {
    std::map<std::pair<int, int>, int> mid;
    auto middle = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(unit({v[a][0] + v[b][0], v[a][1] + v[b][1], v[a][2] + v[b][2]}));
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (const auto& [a, b, c] : f) {
      const int ab = middle(a, b), bc = middle(b, c), ca = middle(c, a);
      g.push_back({a, ab, ca}), g.push_back({b, bc, ab}), g.push_back({c, ca, bc}), g.push_back({ab, bc, ca});
    }
    f = g;
  }
  double enclosed = 0;
  {
    std::ofstream o(dir / "sphere.stl");
    o << std::setprecision(17) << "solid sphere\n";
    for (const auto& tri : f) {
      o << " facet normal 0 0 0\n  outer loop\n";
      for (int k : tri) o << "   vertex " << 10 * v[k][0] << ' ' << 10 * v[k][1] << ' ' << 10 * v[k][2] << '\n';
      o << "  endloop\n endfacet\n";
      enclosed += tet_volume({0, 0, 0}, {10 * v[tri[0]][0], 10 * v[tri[0]][1], 10 * v[tri[0]][2]},
                             {10 * v[tri[1]][0], 10 * v[tri[1]][1], 10 * v[tri[1]][2]}, {10 * v[tri[2]][0], 10 * v[tri[2]][1], 10 * v[tri[2]][2]});
    }
    o << "endsolid sphere\n";
  }
  const TetMesh m = mesher::mesh_stl_object(dir / "sphere.stl", 0.0015, 1e-3);
  std::printf("sphere: %zu tets, volume %.6e m^3 (facets enclose %.6e)\n", m.tets.size(), volume(m), enclosed * 1e-9);
  EXPECT_NEAR(volume(m) / (enclosed * 1e-9), 1.0, 0.01);
  for (const auto& tet : m.tets) EXPECT_GT(tet_volume(m.nodes[tet[0]], m.nodes[tet[1]], m.nodes[tet[2]], m.nodes[tet[3]]), 0.0);
}

// tactus-mesh cylinder. Oracle: every surface node lies on the cylinder (radius r or an end
// plane), so the mesh's volume lies between that of the inscribed 16-gon prism (the curvature
// sizing puts at least 16 elements around) and pi r^2 L; with a sleeve the core's volume does the
// same with radius r - t, the two meshes conform (every free face of the union is on the outer
// boundary, none on the interface), and nodes lie inside the sleeve (at least two tets across it).
TEST(Objects, CylinderAndSleevedCylinder) {
  const double r = 0.02, len = 0.06, t = 0.004;
  const double polygon = 8 * std::sin(M_PI / 8) / M_PI;                // 16-gon area / circle area
  auto radial = [](const Vec3& p) { return std::hypot(p[1], p[2]); };  // axis x, centred at 0
  auto on_outside = [&](const Vec3& p) { return std::abs(radial(p) - r) < 1e-9 || std::abs(std::abs(p[0]) - 0.5 * len) < 1e-9; };
  for (const double sleeve : {0.0, t}) {
    mesher::CylinderSpec spec;
    spec.radius = r, spec.length = len, spec.sleeve = sleeve, spec.element_size = 0.008, spec.axis = 0;
    const TetMesh m = mesher::mesh_cylinder(spec);
    const double exact = M_PI * r * r * len;
    std::printf("cylinder, sleeve %g m: %zu tets, volume %.6e m^3 (pi r^2 L %.6e, 16-gon prism %.6e)\n", sleeve, m.tets.size(), volume(m), exact,
                polygon * exact);
    EXPECT_LE(volume(m), exact * (1 + 1e-12));
    EXPECT_GE(volume(m), polygon * exact);
    ASSERT_NE(m.find_group(2, "surface"), nullptr);
    const int surface = m.find_group(2, "surface")->tag;
    std::size_t surface_triangles = 0;
    for (std::size_t f = 0; f < m.triangles.size(); ++f) {
      if (m.triangle_group[f] != surface) continue;
      ++surface_triangles;
      for (int v : m.triangles[f]) EXPECT_TRUE(on_outside(m.nodes[static_cast<std::size_t>(v)]));
    }
    // The free faces of the tets (on one tet only) are exactly the surface group's.
    std::map<std::array<int, 3>, int> faces;
    for (const auto& tet : m.tets)
      for (int k = 0; k < 4; ++k) {
        std::array<int, 3> f{tet[(k + 1) % 4], tet[(k + 2) % 4], tet[(k + 3) % 4]};
        std::sort(f.begin(), f.end());
        ++faces[f];
      }
    std::size_t free_faces = 0;
    for (const auto& [f, n] : faces) {
      if (n != 1) continue;
      ++free_faces;
      for (int v : f) EXPECT_TRUE(on_outside(m.nodes[static_cast<std::size_t>(v)])) << "a free face inside the cylinder";
    }
    EXPECT_EQ(free_faces, surface_triangles);
    if (sleeve == 0) {
      ASSERT_NE(m.find_group(3, "object"), nullptr);
      continue;
    }
    ASSERT_NE(m.find_group(3, "core"), nullptr);
    ASSERT_NE(m.find_group(3, "sleeve"), nullptr);
    const int core = m.find_group(3, "core")->tag;
    double core_volume = 0;
    std::size_t inside_sleeve = 0;
    for (std::size_t e = 0; e < m.tets.size(); ++e) {
      const auto& tet = m.tets[e];
      const double v = tet_volume(m.nodes[tet[0]], m.nodes[tet[1]], m.nodes[tet[2]], m.nodes[tet[3]]);
      for (int k : tet) {
        const double rho = radial(m.nodes[static_cast<std::size_t>(k)]);
        if (m.tet_group[e] == core)
          EXPECT_LE(rho, r - sleeve + 1e-9);
        else
          EXPECT_GE(rho, r - sleeve - 1e-9);
        if (rho > r - sleeve + 0.2 * sleeve && rho < r - 0.2 * sleeve) ++inside_sleeve;
      }
      if (m.tet_group[e] == core) core_volume += v;
    }
    const double core_exact = M_PI * (r - sleeve) * (r - sleeve) * len;
    std::printf("  core volume %.6e m^3 (pi (r-t)^2 L %.6e); node visits inside the sleeve: %zu\n", core_volume, core_exact, inside_sleeve);
    EXPECT_LE(core_volume, core_exact * (1 + 1e-12));
    EXPECT_GE(core_volume, polygon * core_exact);
    EXPECT_GT(inside_sleeve, 0u);
  }
  mesher::CylinderSpec bad;
  bad.radius = 0.01, bad.sleeve = 0.01;
  EXPECT_THROW(mesher::mesh_cylinder(bad), InputError);
}
