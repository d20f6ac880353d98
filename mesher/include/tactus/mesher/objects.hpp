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

TetMesh mesh_box(const Vec3& size, const Vec3& origin, double element_size, const std::string& name = "block");

// Meshes the volume bounded by a closed, 2-manifold STL surface (units as in the file, scaled
// by `scale` to metres). An open STL (boundary edges) is refused with their count.
TetMesh mesh_stl_object(const std::filesystem::path& stl, double element_size, double scale, const std::string& name = "object");

}  // namespace tactus::mesher
