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
#include <CGAL/Polygon_mesh_processing/repair_self_intersections.h>
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

// The mask smoothed by [1 2 1] / 4 along each axis: the iso-surface at 0.5 of it no longer
// follows one-voxel steps, pinches and bridges (a label's hardest places to extract).
void smooth_mask(vtkImageData* image) {
  int dims[3];
  image->GetDimensions(dims);
  auto* values = vtkFloatArray::SafeDownCast(image->GetPointData()->GetScalars());
  std::vector<float> a(static_cast<std::size_t>(values->GetNumberOfTuples())), b(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) a[i] = values->GetValue(static_cast<vtkIdType>(i));
  const std::size_t stride[3] = {1, static_cast<std::size_t>(dims[0]), static_cast<std::size_t>(dims[0]) * static_cast<std::size_t>(dims[1])};
  for (int axis = 0; axis < 3; ++axis) {
    for (int z = 0; z < dims[2]; ++z)
      for (int y = 0; y < dims[1]; ++y)
        for (int x = 0; x < dims[0]; ++x) {
          const int p[3] = {x, y, z};
          const std::size_t i = static_cast<std::size_t>(x) + stride[1] * static_cast<std::size_t>(y) + stride[2] * static_cast<std::size_t>(z);
          const float lo = p[axis] > 0 ? a[i - stride[axis]] : 0.0f, hi = p[axis] + 1 < dims[axis] ? a[i + stride[axis]] : 0.0f;
          b[i] = 0.25f * lo + 0.5f * a[i] + 0.25f * hi;
        }
    std::swap(a, b);
  }
  for (std::size_t i = 0; i < a.size(); ++i) values->SetValue(static_cast<vtkIdType>(i), a[i]);
  values->Modified();
}

// Marching cubes (flying edges) at 0.5 and windowed-sinc smoothing of a mask image.
Mesh extract_iso_surface(vtkImageData* image, const SurfaceParams& p) {
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
  return to_cgal(smooth->GetOutput());
}

// The checks (closed, 2-manifold, no self-intersection) and the measures of a candidate surface.
bool check_surface(Mesh& mesh, SurfaceReport& r) {
  r.closed = CGAL::is_closed(mesh);
  r.manifold = CGAL::is_valid_polygon_mesh(mesh) && CGAL::is_triangle_mesh(mesh);
  r.self_intersecting = r.manifold && PMP::does_self_intersect(mesh);
  if (r.closed && r.manifold) PMP::orient_to_bound_a_volume(mesh);
  r.surface_volume_m3 = r.closed && r.manifold ? PMP::volume(mesh) : 0.0;
  r.area_m2 = PMP::area(mesh);
  r.vertices = mesh.number_of_vertices();
  r.triangles = mesh.number_of_faces();
  r.min_angle_deg = min_angle_deg(mesh);
  return r.closed && r.manifold && !r.self_intersecting;
}

// Remeshed to edge h, its volume restored to the label's. Marching cubes on a binary mask chamfers
// every convex edge, so the enclosed volume comes out 1-3 % below the voxel count for bone-sized
// objects; one uniform offset along the vertex normals, delta = (V_label - V_surface) / area (a
// few hundredths of a voxel), restores it.
Mesh remeshed(const Mesh& extracted, double h, const SurfaceParams& p, double label_volume) {
  Mesh mesh = extracted;
  PMP::isotropic_remeshing(faces(mesh), h, mesh, CGAL::parameters::number_of_iterations(static_cast<unsigned>(p.remeshing_iterations)));
  mesh.collect_garbage();
  if (CGAL::is_closed(mesh)) {
    PMP::orient_to_bound_a_volume(mesh);
    const double delta = (label_volume - PMP::volume(mesh)) / PMP::area(mesh);
    std::vector<std::pair<Mesh::Vertex_index, Kernel::Vector_3>> moves;
    for (auto v : mesh.vertices()) moves.emplace_back(v, delta * PMP::compute_vertex_normal(v, mesh));
    for (const auto& [v, d] : moves) mesh.point(v) = mesh.point(v) + d;
  }
  return mesh;
}

// Where a surface that failed its checks fails: its self-intersecting triangle pairs, and the
// place the most of them crowd around (the midpoint of the pair with the most other pairs'
// midpoints within 3 edge lengths; the first 2,000 pairs), in the volume's frame.
void locate_self_intersections(const Mesh& mesh, double h, SurfaceReport& r) {
  if (!r.manifold) return;
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  PMP::self_intersections(mesh, std::back_inserter(pairs));
  r.intersecting_pairs = pairs.size();
  if (pairs.size() > 2000) pairs.resize(2000);
  std::vector<Point> mid;
  for (const auto& [f, g] : pairs) {
    std::vector<Point> q;
    for (auto face : {f, g})
      for (auto v : CGAL::vertices_around_face(mesh.halfedge(face), mesh)) q.push_back(mesh.point(v));
    mid.push_back(CGAL::centroid(q.begin(), q.end()));
  }
  std::size_t best = 0, most = 0;
  for (std::size_t i = 0; i < mid.size(); ++i) {
    std::size_t near = 0;
    for (const Point& m : mid) near += CGAL::squared_distance(mid[i], m) < 9 * h * h;
    if (near > most) most = near, best = i;
  }
  if (!mid.empty()) r.worst_self_intersection = {mid[best].x(), mid[best].y(), mid[best].z()};
}

SurfaceReport make_surface(const Volume<std::uint8_t>& L, const std::vector<char>& select, const std::string& name, const fs::path& folder,
                           const SurfaceParams& p) {
  SurfaceReport r;
  r.name = name;
  std::size_t count = 0;
  auto image = cropped_mask(L, select, count);
  r.label_volume_m3 = static_cast<double>(count) * L.voxel_volume();
  if (count == 0) throw InputError("labels", name, "at least one voxel", "none");
  const Mesh extracted = extract_iso_surface(image, p);
  const double h = p.target_edge_voxels * std::cbrt(L.voxel_volume());
  {  // bounded before remeshing: an edge far below the voxel asks for gigabytes of triangles
    const double estimate = PMP::area(extracted) / (0.433 * h * h);  // an equilateral triangle of edge h covers sqrt(3)/4 h^2
    constexpr double kMaxTriangles = 2e7;
    if (estimate > kMaxTriangles)
      throw InputError("command line", "--edge-voxels",
                       "a remeshing edge giving at most 20 million triangles per surface (this one would need about " +
                           std::to_string(static_cast<long long>(estimate)) + ")",
                       std::to_string(p.target_edge_voxels));
  }
  // Repairs, in order, until the checks pass (p.repair false: the first remeshing alone):
  //  - remeshed again at 1.5x and 2.25x the edge: a coarser edge cannot fold into a thin gap (a
  //    self-intersection where two thin parts nearly touch, seen with 0.5 x 0.5 x 2.5 mm voxels);
  //  - CGAL's local removal of self-intersections (remove and refill the faces around them);
  //  - extracted again from the mask smoothed by [1 2 1] / 4 per axis, which opens one-voxel
  //    pinches and bridges (a self-touching fold), at the target edge.
  Mesh mesh = remeshed(extracted, h, p, r.label_volume_m3);
  bool passed = check_surface(mesh, r);
  for (const double factor : {1.5, 2.25}) {
    if (passed || !p.repair) break;
    r.repairs.push_back("remeshed at " + std::to_string(factor).substr(0, 4) + "x the target edge");
    mesh = remeshed(extracted, factor * h, p, r.label_volume_m3);
    passed = check_surface(mesh, r);
    r.edge_factor = factor;
  }
  if (!passed && p.repair && r.manifold) {
    r.repairs.push_back("self-intersections removed locally (CGAL remove_self_intersections)");
    mesh = remeshed(extracted, h, p, r.label_volume_m3);
    r.edge_factor = 1;
    PMP::experimental::remove_self_intersections(mesh);
    mesh.collect_garbage();
    passed = check_surface(mesh, r);
  }
  if (!passed && p.repair) {
    r.repairs.push_back("extracted from the label smoothed by [1 2 1] / 4 per axis");
    smooth_mask(image);
    mesh = remeshed(extract_iso_surface(image, p), h, p, r.label_volume_m3);
    passed = check_surface(mesh, r);
  }
  if (passed && !r.repairs.empty()) log::info() << "surface '" << name << "': passed its checks after: " << r.repairs.back();
  r.passed = passed;
  if (!passed) locate_self_intersections(mesh, r.edge_factor * h, r);
  // Extracted in the volume's axis-aligned frame; written in the world frame (a reflection in
  // the scanner's axes flips the triangles' turn, so they are turned back to face outwards).
  if (!is_identity(L.direction)) {
    for (auto v : mesh.vertices()) {
      const Point& q = mesh.point(v);
      const auto w = L.to_world({q.x(), q.y(), q.z()});
      mesh.point(v) = Point(w[0], w[1], w[2]);
    }
    if (determinant(L.direction) < 0) PMP::reverse_face_orientations(mesh);
    if (r.intersecting_pairs > 0) r.worst_self_intersection = L.to_world(r.worst_self_intersection);
  }
  // A surface that failed its checks is kept for a look, under a name no reader takes for a
  // checked one; segment.json says what failed and where.
  const std::string file = passed ? name : name + "_failed_checks";
  if (!passed) {
    std::ostringstream o;
    o << "surface '" << name << "' failed its checks " << (p.repair ? "after every repair" : "(repairs off)") << " (closed " << r.closed
      << ", 2-manifold " << r.manifold << ", self-intersecting " << r.self_intersecting;
    if (r.intersecting_pairs > 0)
      o << ": " << r.intersecting_pairs << " triangle pairs, the most around (" << 1e3 * r.worst_self_intersection[0] << ", "
        << 1e3 * r.worst_self_intersection[1] << ", " << 1e3 * r.worst_self_intersection[2] << ") mm";
    o << "); written as " << file << ".stl for a look, the labels are unaffected";
    r.failure = o.str();
    log::warn(r.failure);
  }
  r.stl = folder / (file + ".stl");
  r.ply = folder / (file + ".ply");
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
