#include "tactus/mesher/objects.hpp"

#include <gmsh.h>
#include <vtkFeatureEdges.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkSTLReader.h>

#include <algorithm>
#include <cmath>

#include "tactus/core/error.hpp"
#include "tactus/core/gmsh_session.hpp"

namespace tactus::mesher {

namespace {

constexpr int kSurfaceTag = 20;

void mesh_volume(double element_size, const std::string& source) {
  gmsh::option::setNumber("Mesh.MeshSizeMax", element_size);
  gmsh::option::setNumber("Mesh.MeshSizeMin", 0.3 * element_size);
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

TetMesh mesh_box(const Vec3& size, const Vec3& origin, double h, const std::string& name) {
  for (int a = 0; a < 3; ++a)
    if (!(size[a] > 0)) throw InputError("box", "size", "positive edge lengths in m", std::to_string(size[a]));
  if (!(h > 0) || h > 2 * std::max({size[0], size[1], size[2]}))
    throw InputError("box", "element size", "a size > 0 m and not larger than the box", std::to_string(h));
  GmshSession session;
  gmsh::model::add(name);
  const int vol = gmsh::model::occ::addBox(origin[0], origin[1], origin[2], size[0], size[1], size[2]);
  gmsh::model::occ::synchronize();
  gmsh::model::addPhysicalGroup(3, {vol}, 1);
  gmsh::model::setPhysicalName(3, 1, name);
  gmsh::vectorpair faces;
  gmsh::model::getBoundary({{3, vol}}, faces, false, false, false);
  std::vector<int> all;
  const char* names[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  for (const auto& [dim, tag] : faces) {
    double b[6];
    gmsh::model::getBoundingBox(dim, tag, b[0], b[1], b[2], b[3], b[4], b[5]);
    all.push_back(tag);
    // OCC pads bounding boxes by its tolerance (~1e-7): compare at 1e-4 of the box size.
    const double tol = 1e-4 * std::min({size[0], size[1], size[2]});
    for (int axis = 0; axis < 3; ++axis) {
      if (std::abs(b[axis + 3] - b[axis]) > tol) continue;  // not flat along this axis
      const int side = std::abs(0.5 * (b[axis] + b[axis + 3]) - origin[axis]) < tol ? 0 : 1;
      gmsh::model::addPhysicalGroup(2, {tag}, 11 + 2 * axis + side);
      gmsh::model::setPhysicalName(2, 11 + 2 * axis + side, names[2 * axis + side]);
    }
  }
  gmsh::model::addPhysicalGroup(2, all, kSurfaceTag);
  gmsh::model::setPhysicalName(2, kSurfaceTag, "surface");
  mesh_volume(h, "box");
  return tet_mesh_from_gmsh_model("box");
}

TetMesh mesh_stl_object(const std::filesystem::path& stl, double h, double scale, const std::string& name) {
  const std::string file = stl.string();
  if (!std::filesystem::exists(stl)) throw InputError(file, "", "an existing STL file", "no such file");
  {  // Closed and readable? (VTK reads ASCII and binary STL.)
    vtkNew<vtkSTLReader> reader;
    reader->SetFileName(file.c_str());
    reader->Update();
    if (reader->GetErrorCode() != 0 || reader->GetOutput()->GetNumberOfCells() == 0)
      throw InputError(file, "", "a readable STL surface", "unreadable or empty");
    vtkNew<vtkFeatureEdges> edges;
    edges->SetInputConnection(reader->GetOutputPort());
    edges->BoundaryEdgesOn();
    edges->NonManifoldEdgesOn();
    edges->FeatureEdgesOff();
    edges->ManifoldEdgesOff();
    edges->Update();
    if (const auto n = edges->GetOutput()->GetNumberOfCells(); n > 0)
      throw InputError(file, "", "a closed 2-manifold surface", std::to_string(n) + " open or non-manifold edges");
  }
  if (!(h > 0)) throw InputError(file, "element size", "a size > 0 m", std::to_string(h));
  if (!(scale > 0)) throw InputError(file, "scale", "a factor > 0", std::to_string(scale));
  GmshSession session;
  gmsh::model::add(name);
  try {
    gmsh::merge(file);
  } catch (...) {
    throw InputError(file, "", "an STL gmsh can read", GmshSession::last_error());
  }
  gmsh::model::mesh::classifySurfaces(40.0 * M_PI / 180.0, true, false, M_PI);
  gmsh::model::mesh::createGeometry();
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

}  // namespace tactus::mesher
