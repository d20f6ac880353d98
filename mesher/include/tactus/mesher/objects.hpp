#pragma once
// Object meshes with gmsh, in the same .msh form as the anatomy: the paper's parallelepiped
// block (§3.2, Fig. 8) and closed STL objects (e.g. a tool handle). Physical groups: volume 1
// (named after the object), surfaces 11..16 "xmin".."zmax" for a box, and 20 "surface", the
// whole boundary, for contact.
#include <array>
#include <filesystem>
#include <string>

#include "tactus/core/mesh.hpp"

namespace tactus::mesher {

// About this many tets for a volume V meshed at element size h: 6 V / h^3 (gmsh's Delaunay gives
// 5-6); meshes expected above `max_elements` are refused before gmsh starts. `edge_radius` > 0
// rounds all twelve edges (and so the corners) with that radius, meshed at about half of it;
// the face groups "xmin".."zmax" are then the flat parts.
TetMesh mesh_box(const Vec3& size, const Vec3& origin, double element_size, const std::string& name = "block", double max_elements = 1e7,
                 double edge_radius = 0);

// A triangle surface read from STL (ASCII or binary) by tactus's own reader: vertices merged
// where their coordinates are equal, every value checked.
struct StlSurface {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;
  std::size_t boundary_edges = 0, non_manifold_edges = 0;  // edges with one, or more than two, triangles
};
StlSurface read_stl(const std::filesystem::path& file);

// Meshes the volume bounded by a closed, 2-manifold STL surface (units as in the file, scaled
// by `scale` to metres). An open STL (boundary edges) is refused with their count.
// A cylinder (a tool handle), gmsh OpenCASCADE: `radius` and `length` in m along axis 0/1/2
// (x/y/z) about `centre`. With `sleeve` > 0 it is two volumes in one conforming mesh: a core of
// radius - sleeve (volume group 1 "core") inside a sleeve of that thickness (group 2 "sleeve"),
// the sleeve meshed at most sleeve / 2 so at least two tets span it; without, one volume
// (group 1 "object", as an STL object). Surface group 20 "surface" is the outer boundary.
struct CylinderSpec {
  double radius = 0.02, length = 0.13, sleeve = 0, element_size = 0.006;
  int axis = 0;
  Vec3 centre{0, 0, 0};
};
TetMesh mesh_cylinder(const CylinderSpec& cylinder, double max_elements = 1e7);

TetMesh mesh_stl_object(const std::filesystem::path& stl, double element_size, double scale, const std::string& name = "object",
                        double max_elements = 1e7);

}  // namespace tactus::mesher
