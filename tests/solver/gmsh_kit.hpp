#pragma once
// gmsh OCC helpers for the solver tests' unstructured meshes.
#include <gmsh.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "tactus/core/gmsh_session.hpp"

namespace tactus::testkit {

// Puts each boundary face of OCC volume `volume` that lies in one of the six planes of the box
// [lo, hi] into the physical group samples::make_box_mesh gives that plane ("xmin" .. "zmax",
// 11 .. 16), and returns the tags of the faces in none of them (curved ones).
inline std::vector<int> tag_box_plane_faces(int volume, const double lo[3], const double hi[3]) {
  static const char* names[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  gmsh::vectorpair faces;
  gmsh::model::getBoundary({{3, volume}}, faces, false, false, false);
  std::vector<int> in_plane[6], others;
  for (const auto& f : faces) {
    double a[3], b[3];
    gmsh::model::getBoundingBox(2, f.second, a[0], a[1], a[2], b[0], b[1], b[2]);
    bool placed = false;
    for (int c = 0; c < 3 && !placed; ++c)
      for (int side = 0; side < 2 && !placed; ++side)
        if (b[c] - a[c] < 1e-6 && std::abs(0.5 * (a[c] + b[c]) - (side ? hi[c] : lo[c])) < 1e-6) {  // OCC carries a 1e-7 tolerance
          in_plane[2 * c + side].push_back(f.second);
          placed = true;
        }
    if (!placed) others.push_back(f.second);
  }
  for (int k = 0; k < 6; ++k)
    if (!in_plane[k].empty()) {
      gmsh::model::addPhysicalGroup(2, in_plane[k], 11 + k);
      gmsh::model::setPhysicalName(2, 11 + k, names[k]);
    }
  return others;
}

// A background size field: h_min within fine_radius of `centre`, growing linearly with distance
// by `grading` (size per unit distance) up to h_max.
inline void graded_size_field(const double centre[3], double h_min, double h_max, double fine_radius, double grading) {
  // The distance as a formula: a point entity would stay in the mesh as an isolated node.
  const int distance = gmsh::model::mesh::field::add("MathEval");
  char formula[160];
  std::snprintf(formula, sizeof formula, "sqrt((x - (%.17g))^2 + (y - (%.17g))^2 + (z - (%.17g))^2)", centre[0], centre[1], centre[2]);
  gmsh::model::mesh::field::setString(distance, "F", formula);
  const int size = gmsh::model::mesh::field::add("Threshold");
  gmsh::model::mesh::field::setNumber(size, "InField", distance);
  gmsh::model::mesh::field::setNumber(size, "SizeMin", h_min);
  gmsh::model::mesh::field::setNumber(size, "SizeMax", h_max);
  gmsh::model::mesh::field::setNumber(size, "DistMin", fine_radius);
  gmsh::model::mesh::field::setNumber(size, "DistMax", fine_radius + (h_max - h_min) / grading);
  gmsh::model::mesh::field::setAsBackgroundMesh(size);
  gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
  gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
  gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
}

// Meshes the current gmsh model in 3-D reproducibly (Delaunay, optimised, seed 1) and returns
// it as a TetMesh.
inline TetMesh generate_tet_mesh(const std::string& model) {
  gmsh::option::setNumber("Mesh.Algorithm3D", 1);
  gmsh::option::setNumber("Mesh.Optimize", 1);
  gmsh::option::setNumber("Mesh.RandomSeed", 1);
  gmsh::model::mesh::generate(3);
  return tet_mesh_from_gmsh_model(model);
}

// A U-shaped strip, W x D x H, its arms and base t thick (a slot of W - 2t), meshed at size h:
// one volume group "strip" (1) and its whole boundary as the surface group "surface" (20). The
// self-contact tests swing its arms into each other.
inline TetMesh u_strip_mesh(double W, double D, double H, double t, double h) {
  GmshSession session;
  gmsh::model::add("u_strip");
  const int outer = gmsh::model::occ::addBox(0, 0, 0, W, D, H);
  const int slot = gmsh::model::occ::addBox(t, -D, t, W - 2 * t, 3 * D, H);
  gmsh::vectorpair result;
  std::vector<gmsh::vectorpair> map;
  gmsh::model::occ::cut({{3, outer}}, {{3, slot}}, result, map);
  gmsh::model::occ::synchronize();
  gmsh::model::addPhysicalGroup(3, {result[0].second}, 1);
  gmsh::model::setPhysicalName(3, 1, "strip");
  gmsh::vectorpair faces;
  gmsh::model::getBoundary(result, faces, false, false, false);
  std::vector<int> tags;
  for (const auto& f : faces) tags.push_back(f.second);
  gmsh::model::addPhysicalGroup(2, tags, 20);
  gmsh::model::setPhysicalName(2, 20, "surface");
  gmsh::option::setNumber("Mesh.MeshSizeMin", h);
  gmsh::option::setNumber("Mesh.MeshSizeMax", h);
  gmsh::option::setNumber("Mesh.RandomSeed", 1);
  gmsh::model::mesh::generate(3);
  return tet_mesh_from_gmsh_model("u_strip");
}

}  // namespace tactus::testkit
