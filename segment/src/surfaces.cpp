#include "tactus/segment/surfaces.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/PLY.h>
#include <CGAL/IO/STL.h>
#include <CGAL/Polygon_mesh_processing/compute_normal.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <vtkCellArray.h>
#include <vtkFloatArray.h>
#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkWindowedSincPolyDataFilter.h>

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/progress.hpp"
#include "tactus/core/staged_output.hpp"

namespace fs = std::filesystem;
namespace PMP = CGAL::Polygon_mesh_processing;

namespace tactus::segment {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;

// Binary mask of `select(label)` cropped to its bounding box plus a 2-voxel border of zeros
// (so the iso-surface is closed even where the mask touches the volume's edge).
vtkSmartPointer<vtkImageData> cropped_mask(const Volume<std::uint8_t>& L, const std::vector<char>& select, std::size_t& count) {
  int lo[3] = {L.dims[0], L.dims[1], L.dims[2]}, hi[3] = {-1, -1, -1};
  count = 0;
  for (int z = 0; z < L.dims[2]; ++z)
    for (int y = 0; y < L.dims[1]; ++y)
      for (int x = 0; x < L.dims[0]; ++x)
        if (select[L.at(x, y, z)]) {
          ++count;
          const int p[3] = {x, y, z};
          for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
        }
  auto image = vtkSmartPointer<vtkImageData>::New();
  if (count == 0) return image;
  int dims[3];
  double origin[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] -= 2, hi[a] += 2;
    dims[a] = hi[a] - lo[a] + 1;
    origin[a] = L.origin[a] + L.spacing[a] * lo[a];
  }
  image->SetDimensions(dims);
  image->SetSpacing(L.spacing.data());
  image->SetOrigin(origin);
  vtkNew<vtkFloatArray> values;
  values->SetNumberOfTuples(static_cast<vtkIdType>(dims[0]) * dims[1] * dims[2]);
  vtkIdType k = 0;
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int x = lo[0]; x <= hi[0]; ++x, ++k) {
        const bool inside = x >= 0 && y >= 0 && z >= 0 && x < L.dims[0] && y < L.dims[1] && z < L.dims[2] && select[L.at(x, y, z)];
        values->SetValue(k, inside ? 1.0f : 0.0f);
      }
  image->GetPointData()->SetScalars(values);
  return image;
}

Mesh to_cgal(vtkPolyData* poly) {
  std::vector<Point> points(static_cast<std::size_t>(poly->GetNumberOfPoints()));
  for (vtkIdType i = 0; i < poly->GetNumberOfPoints(); ++i) {
    double p[3];
    poly->GetPoint(i, p);
    points[static_cast<std::size_t>(i)] = Point(p[0], p[1], p[2]);
  }
  std::vector<std::array<std::size_t, 3>> triangles;
  vtkCellArray* polys = poly->GetPolys();
  polys->InitTraversal();
  vtkIdType n;
  const vtkIdType* ids;
  while (polys->GetNextCell(n, ids))
    if (n == 3) triangles.push_back({static_cast<std::size_t>(ids[0]), static_cast<std::size_t>(ids[1]), static_cast<std::size_t>(ids[2])});
  // Marching cubes can leave duplicate points, degenerate triangles and non-manifold vertices:
  // repair the soup, orient it consistently and build a valid halfedge mesh.
  PMP::repair_polygon_soup(points, triangles);
  PMP::orient_polygon_soup(points, triangles);
  Mesh mesh;
  PMP::polygon_soup_to_polygon_mesh(points, triangles, mesh);
  return mesh;
}

double min_angle_deg(const Mesh& m) {
  double best = 180;
  for (auto f : m.faces()) {
    std::array<Point, 3> p;
    int i = 0;
    for (auto v : CGAL::vertices_around_face(m.halfedge(f), m)) p[static_cast<std::size_t>(i++)] = m.point(v);
    for (int k = 0; k < 3; ++k) {
      const auto a = p[static_cast<std::size_t>((k + 1) % 3)] - p[static_cast<std::size_t>(k)];
      const auto b = p[static_cast<std::size_t>((k + 2) % 3)] - p[static_cast<std::size_t>(k)];
      const double c = (a * b) / std::sqrt(a.squared_length() * b.squared_length());
      best = std::min(best, std::acos(std::clamp(c, -1.0, 1.0)) * 180 / M_PI);
    }
  }
  return best;
}

SurfaceReport make_surface(const Volume<std::uint8_t>& L, const std::vector<char>& select, const std::string& name, const fs::path& folder,
                           const SurfaceParams& p) {
  SurfaceReport r;
  r.name = name;
  std::size_t count = 0;
  auto image = cropped_mask(L, select, count);
  r.label_volume_m3 = static_cast<double>(count) * L.voxel_volume();
  if (count == 0) throw InputError("labels", name, "at least one voxel", "none");
  vtkNew<vtkFlyingEdges3D> mc;
  mc->SetInputData(image);
  mc->SetValue(0, 0.5);
  mc->ComputeNormalsOff();
  mc->ComputeGradientsOff();
  mc->ComputeScalarsOff();
  vtkNew<vtkWindowedSincPolyDataFilter> smooth;
  smooth->SetInputConnection(mc->GetOutputPort());
  smooth->SetNumberOfIterations(p.smoothing_iterations);
  smooth->SetPassBand(p.smoothing_passband);
  smooth->NormalizeCoordinatesOn();
  smooth->BoundarySmoothingOff();
  smooth->FeatureEdgeSmoothingOff();
  smooth->NonManifoldSmoothingOn();
  smooth->Update();
  const Mesh extracted = to_cgal(smooth->GetOutput());
  // Remeshed at the target edge; a surface that fails its checks (a self-intersection where two
  // thin parts nearly touch, seen with 0.5 x 0.5 x 2.5 mm voxels) is remeshed again at 1.5x and
  // 2.25x the edge before tactus gives up: a coarser edge cannot fold into the gap.
  // Bounded before remeshing: an edge far below the voxel asks for gigabytes of triangles. An
  // equilateral triangle of edge h covers sqrt(3)/4 h^2.
  {
    const double h = p.target_edge_voxels * std::cbrt(L.voxel_volume());
    const double estimate = PMP::area(extracted) / (0.433 * h * h);
    constexpr double kMaxTriangles = 2e7;
    if (estimate > kMaxTriangles)
      throw InputError("command line", "--edge-voxels",
                       "a remeshing edge giving at most 20 million triangles per surface (this one would need about " +
                           std::to_string(static_cast<long long>(estimate)) + ")",
                       std::to_string(p.target_edge_voxels));
  }
  Mesh mesh;
  for (const double factor : {1.0, 1.5, 2.25}) {
    mesh = extracted;
    const double h = factor * p.target_edge_voxels * std::cbrt(L.voxel_volume());
    PMP::isotropic_remeshing(faces(mesh), h, mesh, CGAL::parameters::number_of_iterations(static_cast<unsigned>(p.remeshing_iterations)));
    mesh.collect_garbage();
    // Marching cubes on a binary mask chamfers every convex edge, so the enclosed volume comes out
    // 1-3 % below the voxel count for bone-sized objects. Restore it with one uniform offset along
    // the vertex normals, delta = (V_label - V_surface) / area (a few hundredths of a voxel).
    if (CGAL::is_closed(mesh)) {
      PMP::orient_to_bound_a_volume(mesh);
      const double delta = (r.label_volume_m3 - PMP::volume(mesh)) / PMP::area(mesh);
      std::vector<std::pair<Mesh::Vertex_index, Kernel::Vector_3>> moves;
      for (auto v : mesh.vertices()) moves.emplace_back(v, delta * PMP::compute_vertex_normal(v, mesh));
      for (const auto& [v, d] : moves) mesh.point(v) = mesh.point(v) + d;
    }
    r.closed = CGAL::is_closed(mesh);
    r.manifold = CGAL::is_valid_polygon_mesh(mesh) && CGAL::is_triangle_mesh(mesh);
    r.self_intersecting = PMP::does_self_intersect(mesh);
    if (r.closed) PMP::orient_to_bound_a_volume(mesh);
    r.surface_volume_m3 = r.closed ? PMP::volume(mesh) : 0.0;
    r.area_m2 = PMP::area(mesh);
    r.vertices = mesh.number_of_vertices();
    r.triangles = mesh.number_of_faces();
    r.min_angle_deg = min_angle_deg(mesh);
    r.edge_factor = factor;
    if (r.closed && r.manifold && !r.self_intersecting) break;
  }
  if (r.edge_factor > 1) log::info() << "surface '" << name << "': remeshed at " << r.edge_factor << "x the target edge to pass its checks";
  if (!r.closed || !r.manifold || r.self_intersecting) {
    std::ostringstream o;
    o << "surface '" << name << "' failed its checks (closed " << r.closed << ", 2-manifold " << r.manifold << ", self-intersecting "
      << r.self_intersecting << "); not written";
    throw NumericalError(o.str());
  }
  // Extracted in the volume's axis-aligned frame; written in the world frame (a reflection in
  // the scanner's axes flips the triangles' turn, so they are turned back to face outwards).
  if (!is_identity(L.direction)) {
    for (auto v : mesh.vertices()) {
      const Point& q = mesh.point(v);
      const auto w = L.to_world({q.x(), q.y(), q.z()});
      mesh.point(v) = Point(w[0], w[1], w[2]);
    }
    if (determinant(L.direction) < 0) PMP::reverse_face_orientations(mesh);
  }
  r.stl = folder / (name + ".stl");
  r.ply = folder / (name + ".ply");
  {  // through memory: the file itself is written with every write checked (a full disk is an error)
    std::ostringstream os(std::ios::binary);
    CGAL::IO::set_mode(os, CGAL::IO::BINARY);  // (the named parameter alone still writes ASCII in 5.5)
    CGAL::IO::write_STL(os, mesh, CGAL::parameters::use_binary_mode(true));
    write_file(r.stl, os.str());
  }
  {
    std::ostringstream os(std::ios::binary);
    CGAL::IO::set_mode(os, CGAL::IO::BINARY);
    CGAL::IO::write_PLY(os, mesh, CGAL::parameters::use_binary_mode(true));
    write_file(r.ply, os.str());
  }
  return r;
}

}  // namespace

std::vector<SurfaceReport> extract_surfaces(const Volume<std::uint8_t>& labels, const LabelTable& table, const fs::path& folder,
                                            const SurfaceParams& p) {
  // `folder` lies inside the stage's staged output folder: written directly.
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw WriteError(folder.string(), "cannot create the folder (" + ec.message() + ")");
  std::vector<SurfaceReport> out;
  std::vector<int> bone_ids;
  for (const auto& [id, name] : table)
    if (id >= 2) bone_ids.push_back(id);
  Progress progress("surfaces", bone_ids.size() + 1);
  {
    std::vector<char> select(256, 0);
    for (int v = 1; v < 256; ++v) select[static_cast<std::size_t>(v)] = 1;
    out.push_back(make_surface(labels, select, contracts::kSkinGroup, folder, p));
    for (const auto& [id, name] : table)
      if (id >= 1) out.back().labels.push_back(id);
  }
  for (int id : bone_ids) {
    std::vector<char> select(256, 0);
    select[static_cast<std::size_t>(id)] = 1;
    std::ostringstream name;
    name << "bone_" << std::setw(2) << std::setfill('0') << id;
    out.push_back(make_surface(labels, select, name.str(), folder, p));
    out.back().labels = {id};
    progress.update(out.size());
  }
  progress.finish();
  return out;
}

}  // namespace tactus::segment
