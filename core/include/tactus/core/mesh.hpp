#pragma once
// The tetrahedral mesh passed between mesher, solver and postproc: nodes (m), linear tets with a
// physical volume group each (material/subdomain), and tagged boundary triangles (physical
// surface groups: skin, bone interface, contact faces). Indices are 0-based in memory and
// written 1-based in .msh as gmsh expects.
#include <array>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tactus/core/vec3.hpp"

namespace tactus {

struct PhysicalGroup {
  int dim = 3;  // 3: volume (material/subdomain), 2: surface
  int tag = 0;  // gmsh physical tag, > 0
  std::string name;
};

struct TetMesh {
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tets;
  std::vector<int> tet_group;                 // physical volume tag of each tet
  std::vector<std::array<int, 3>> triangles;  // tagged boundary/interface triangles
  std::vector<int> triangle_group;            // physical surface tag of each triangle
  std::vector<PhysicalGroup> groups;

  const PhysicalGroup* find_group(int dim, std::string_view name) const;
  const PhysicalGroup* find_group(int dim, int tag) const;
  // Checks sizes, index ranges and that every element's group is declared; throws InputError
  // naming `source` (the file it came from) and the first offending element.
  void validate(const std::string& source) const;
};

// Signed volume of a tet (positive for the gmsh/VTK orientation).
double tet_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// gmsh MSH 4.1 through the gmsh API. Writing: one discrete entity per physical group; binary by
// default because it round-trips every double exactly (gmsh's ASCII writer keeps 16 digits).
// Reading accepts any MSH file gmsh reads whose tets and triangles belong to physical groups.
void write_msh(const std::filesystem::path& file, const TetMesh& mesh, bool binary = true);
TetMesh read_msh(const std::filesystem::path& file);

// A named field on points or cells for .vtu output (row-major: value[i*components + c]).
struct MeshField {
  std::string name;
  int components = 1;
  std::vector<double> values;
  std::vector<std::string> component_names{};  // (optional) VTK's component names, e.g. xx .. xz
};

// Named strings for a .vtu's field data (VTK string array), e.g. the body names.
struct MeshStrings {
  std::string name;
  std::vector<std::string> values;
};

// VTK XML unstructured grid (.vtu) of the tets, with point data "node_id" and cell data "tet_id"
// (1-based, the numbers messages use) and "group" (the physical tag), the given point and cell
// fields, and field data "units" ("SI (m, kg, s, Pa, J)") and "points" (which configuration the
// points are). Optional `current_nodes` writes the deformed positions (the reference geometry is
// then points - "displacement", and the "points" note says so: a Warp By Vector would apply the
// displacement twice); `time` (s) goes into field data "TimeValue", where ParaView and VTK's
// readers take a state's time from without the .pvd; `strings` are added to the field data.
void write_vtu(const std::filesystem::path& file, const TetMesh& mesh, const std::vector<MeshField>& point_fields = {},
               const std::vector<MeshField>& cell_fields = {}, const std::vector<Vec3>* current_nodes = nullptr,
               std::optional<double> time = std::nullopt, const std::vector<MeshStrings>& strings = {});
// The same with the cells moved in rather than in mesh.tets and the points from current_nodes
// alone, for a writer that keeps no tets or nodes in its mesh (the solver's states: their cells
// come with the stress records, the points are the deformed positions); the cells are freed once
// VTK holds its copy, before it copies the fields, so a writer's peak holds them once. mesh.tet_group
// still holds one tag per tet, and mesh.nodes is not read.
void write_vtu(const std::filesystem::path& file, const TetMesh& mesh, std::vector<std::array<int, 4>>&& cells,
               const std::vector<MeshField>& point_fields, const std::vector<MeshField>& cell_fields, const std::vector<Vec3>& current_nodes,
               std::optional<double> time, const std::vector<MeshStrings>& strings);

struct VtuContents {
  TetMesh mesh;  // nodes, tets, tet_group (no triangles: a .vtu holds the volume cells)
  std::vector<MeshField> point_fields, cell_fields;
  std::optional<double> time;  // field data TimeValue, when the file has it
  const MeshField* point_field(std::string_view name) const;
  const MeshField* cell_field(std::string_view name) const;
};
VtuContents read_vtu(const std::filesystem::path& file);

}  // namespace tactus
