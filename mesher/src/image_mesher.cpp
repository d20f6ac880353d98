#include "tactus/mesher/image_mesher.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Image_3.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_3/initialize_triangulation_from_labeled_image.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_constant_domain_field_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/make_mesh_3.h>
#include <CGAL/refine_mesh_3.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <type_traits>

#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/stable_step.hpp"
#include "tactus/mesher/post_passes.hpp"
#include "tactus/mesher/quality.hpp"
#include "tactus/mesher/well_composed.hpp"

namespace tactus::mesher {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Domain = CGAL::Labeled_mesh_domain_3<K>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;
using SizeField = CGAL::Mesh_constant_domain_field_3<Domain::R, Domain::Index>;

// Whether a world point (m) is inside the refined box (none while refine_size_mm is 0 or the box
// is empty).
bool in_refine_box(const ImageMeshParams& p, const std::array<double, 3>& x) {
  const auto& b = p.refine_box_m;
  return p.refine_size_mm > 0 && b[3] > b[0] && x[0] >= b[0] && x[1] >= b[1] && x[2] >= b[2] && x[0] <= b[3] && x[1] <= b[4] && x[2] <= b[5];
}

// The refined region: the box, and the joints' voxels (joint_gap_mask) when refine_joints_mm > 0.
struct RefinedRegion {
  const ImageMeshParams* p = nullptr;
  const Volume<std::uint8_t>* labels = nullptr;
  std::vector<std::uint8_t> joints;
  // `aligned`: a point in the labels' axis-aligned frame, m (origin + index * spacing).
  bool contains(const std::array<double, 3>& aligned) const {
    if (in_refine_box(*p, labels->to_world(aligned))) return true;
    if (joints.empty()) return false;
    std::array<int, 3> v{};
    for (int d = 0; d < 3; ++d) {
      v[d] = static_cast<int>(std::lround((aligned[d] - labels->origin[d]) / labels->spacing[d]));
      if (v[d] < 0 || v[d] >= labels->dims[d]) return false;
    }
    return joints[labels->index(v[0], v[1], v[2])] != 0;
  }
};

// A CGAL sizing field: `outer` (a size per subdomain or surface patch, or one number) outside the
// refined box, at most `inner` (mm) inside it. CGAL's points are millimetres from the labels'
// origin in their axis-aligned frame (extract() below), turned to world metres for the test.
template <class Outer>
struct RefinedField {
  const Outer* outer = nullptr;
  const RefinedRegion* region = nullptr;
  double inner = 0;
  [[gnu::noinline]] double operator()(const Domain::Point_3& q, int dim, const Domain::Index& index) const {
    double o;
    if constexpr (std::is_arithmetic_v<Outer>)
      o = *outer;
    else
      o = (*outer)(q, dim, index);
    if (!(inner > 0) || o <= inner) return o;
    const auto& g = region->labels->origin;
    return region->contains({g[0] + q.x() * 1e-3, g[1] + q.y() * 1e-3, g[2] + q.z() * 1e-3}) ? inner : o;
  }
};

// 1 where any voxel of `line` (n values, `stride` apart) within r of it is 1: a running count.
void dilate_line(std::uint8_t* line, std::size_t stride, int n, int r, std::vector<int>& prefix) {
  prefix.assign(static_cast<std::size_t>(n) + 1, 0);
  for (int i = 0; i < n; ++i)
    prefix[static_cast<std::size_t>(i) + 1] = prefix[static_cast<std::size_t>(i)] + (line[static_cast<std::size_t>(i) * stride] ? 1 : 0);
  for (int i = 0; i < n; ++i)
    line[static_cast<std::size_t>(i) * stride] =
        prefix[static_cast<std::size_t>(std::min(n, i + r + 1))] > prefix[static_cast<std::size_t>(std::max(0, i - r))];
}

void check(bool ok, const std::string& field, const std::string& expected, double value) {
  if (!ok) {
    std::ostringstream f;
    f << value;
    throw InputError("mesh criteria", field, expected, f.str());
  }
}

}  // namespace

// Each bone dilated by a box of half-side `mm` within its bounding box grown by as much
// (separable: three passes of running counts); a voxel two different bones' dilations reach is
// in the mask. The bones' voxels themselves count, so the bone surfaces facing the gap are in it.
std::vector<std::uint8_t> joint_gap_mask(const Volume<std::uint8_t>& labels, double mm) {
  if (!(mm > 0)) return {};
  std::array<int, 3> r{};
  for (int d = 0; d < 3; ++d) r[d] = std::max(1, static_cast<int>(std::ceil(mm * 1e-3 / labels.spacing[d])));
  std::map<int, std::array<int, 6>> boxes;  // bone label -> lo, hi voxel
  for (int k = 0; k < labels.dims[2]; ++k)
    for (int j = 0; j < labels.dims[1]; ++j)
      for (int i = 0; i < labels.dims[0]; ++i) {
        const int l = labels.at(i, j, k);
        if (l < contracts::kFirstBoneLabel) continue;
        auto [it, fresh] = boxes.try_emplace(l, std::array<int, 6>{i, j, k, i, j, k});
        auto& b = it->second;
        if (!fresh) b = {std::min(b[0], i), std::min(b[1], j), std::min(b[2], k), std::max(b[3], i), std::max(b[4], j), std::max(b[5], k)};
      }
  std::vector<std::uint8_t> first(labels.size(), 0), mask(labels.size(), 0), box;
  std::vector<int> prefix;
  for (const auto& [l, b] : boxes) {
    std::array<int, 3> lo{}, n{};
    for (int d = 0; d < 3; ++d) lo[d] = std::max(0, b[d] - r[d]), n[d] = std::min(labels.dims[d] - 1, b[d + 3] + r[d]) - lo[d] + 1;
    const std::array<std::size_t, 3> stride{1, static_cast<std::size_t>(n[0]), static_cast<std::size_t>(n[0]) * static_cast<std::size_t>(n[1])};
    box.assign(stride[2] * static_cast<std::size_t>(n[2]), 0);
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i) box[i + stride[1] * j + stride[2] * k] = labels.at(lo[0] + i, lo[1] + j, lo[2] + k) == l;
    for (int d = 0; d < 3; ++d) {  // every line along axis d
      const int a = (d + 1) % 3, c = (d + 2) % 3;
      for (int v = 0; v < n[c]; ++v)
        for (int u = 0; u < n[a]; ++u) dilate_line(&box[stride[a] * u + stride[c] * v], stride[d], n[d], r[d], prefix);
    }
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i) {
          if (!box[i + stride[1] * j + stride[2] * k]) continue;
          const std::size_t at = labels.index(lo[0] + i, lo[1] + j, lo[2] + k);
          if (first[at] == 0)
            first[at] = static_cast<std::uint8_t>(l);
          else if (first[at] != l)
            mask[at] = 1;
        }
  }
  return mask;
}

namespace {
// expected_tets with the joints' mask already made (mesh_label_volume makes it once for this
// runaway guard and the sizing fields).
double expected_tets_in(const Volume<std::uint8_t>& labels, const ImageMeshParams& p, std::vector<std::uint8_t> joints) {
  const double voxel_mm3 = labels.voxel_volume() * 1e9;
  auto tets = [&](double size_mm) { return voxel_mm3 / (0.1 * size_mm * size_mm * size_mm); };
  const double soft = tets(p.cell_size_mm), bone = tets(p.bone_cell_size_mm);
  const double refined = p.refine_cell_size_mm > 0 ? tets(p.refine_cell_size_mm) : 0;
  const RefinedRegion region{&p, &labels, std::move(joints)};
  double n = 0;
  for (int k = 0; k < labels.dims[2]; ++k)
    for (int j = 0; j < labels.dims[1]; ++j)
      for (int i = 0; i < labels.dims[0]; ++i) {
        const auto v = labels.at(i, j, k);
        if (v == 0) continue;
        const auto fitted = p.label_cell_size_mm.find(v);
        const double own = fitted != p.label_cell_size_mm.end() ? tets(fitted->second)
                           : v == contracts::kSoftTissueLabel   ? soft
                           : v >= contracts::kFirstBoneLabel    ? bone
                                                                : 0.0;
        const std::array<double, 3> aligned{labels.origin[0] + i * labels.spacing[0], labels.origin[1] + j * labels.spacing[1],
                                            labels.origin[2] + k * labels.spacing[2]};
        n += refined > own && region.contains(aligned) ? refined : own;
      }
  return n;
}

// The refined region's joints: none without a refined size.
std::vector<std::uint8_t> refined_joints(const Volume<std::uint8_t>& labels, const ImageMeshParams& p) {
  return joint_gap_mask(labels, p.refine_size_mm > 0 ? p.refine_joints_mm : 0);
}

}  // namespace

double expected_tets(const Volume<std::uint8_t>& labels, const ImageMeshParams& p) { return expected_tets_in(labels, p, refined_joints(labels, p)); }

namespace {

// The criteria and the labels: refused when they cannot give a mesh (or a sane one).
void validate(const Volume<std::uint8_t>& labels, const ImageMeshParams& p, const std::vector<std::uint8_t>& joints) {
  check(p.facet_angle_deg > 0 && p.facet_angle_deg <= 30, "facet_angle", "an angle in (0, 30] degrees", p.facet_angle_deg);
  check(p.facet_size_mm > 0, "facet_size", "a size > 0 mm", p.facet_size_mm);
  check(p.facet_distance_mm > 0, "facet_distance", "a distance > 0 mm", p.facet_distance_mm);
  check(p.cell_radius_edge >= 2, "cell_radius_edge", "a ratio >= 2", p.cell_radius_edge);
  check(p.cell_size_mm > 0, "cell_size", "a size > 0 mm", p.cell_size_mm);
  check(p.bone_cell_size_mm > 0, "bone_cell_size", "a size > 0 mm", p.bone_cell_size_mm);
  check(p.bone_facet_size_mm > 0, "bone_facet_size", "a size > 0 mm", p.bone_facet_size_mm);
  check(p.boundary_smoothing_voxels >= 0 && p.boundary_smoothing_voxels <= 3, "boundary_smoothing", "a sigma in [0, 3] voxels",
        p.boundary_smoothing_voxels);
  check(p.refine_size_mm >= 0, "refine_size", "a size >= 0 mm (0: no refined region)", p.refine_size_mm);
  check(p.refine_distance_mm >= 0, "refine_distance", "a distance >= 0 mm (0: the facet distance)", p.refine_distance_mm);
  const bool has_box = std::any_of(p.refine_box_m.begin(), p.refine_box_m.end(), [](double x) { return x != 0; });
  check(p.refine_joints_mm >= 0 && p.refine_joints_mm <= 50, "refine_joints", "a distance from 0 to 50 mm", p.refine_joints_mm);
  if (p.refine_size_mm > 0 && has_box)  // (refine_joints_mm alone refines no box)
    for (int a = 0; a < 3; ++a)
      check(p.refine_box_m[static_cast<std::size_t>(a)] < p.refine_box_m[static_cast<std::size_t>(a + 3)], std::string("refine_box ") + "xyz"[a],
            "a box whose lower corner is below its upper one",
            p.refine_box_m[static_cast<std::size_t>(a + 3)] - p.refine_box_m[static_cast<std::size_t>(a)]);
  validate_volume_geometry(labels.dims, labels.spacing, labels.origin, 1, "labels", "/labels");
  std::size_t tissue = 0, nonzero = 0;
  for (auto v : labels.data) tissue += v == contracts::kSoftTissueLabel, nonzero += v != 0;
  if (nonzero == 0) throw InputError("labels", "/labels", "a label volume with tissue (labels >= 1)", "only background");
  if (tissue == 0) throw InputError("labels", "/labels", "soft tissue (label 1) around the bones", "no soft-tissue voxel");
  {  // CGAL's initial sampling never ends on a body one voxel thick: at least 3 voxels along every axis.
    std::array<int, 3> lo{labels.dims}, hi{-1, -1, -1};
    for (int k = 0; k < labels.dims[2]; ++k)
      for (int j = 0; j < labels.dims[1]; ++j)
        for (int i = 0; i < labels.dims[0]; ++i)
          if (labels.at(i, j, k)) {
            const int x[3] = {i, j, k};
            for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], x[a]), hi[a] = std::max(hi[a], x[a]);
          }
    for (int a = 0; a < 3; ++a)
      if (hi[a] - lo[a] + 1 < 3)
        throw InputError("labels", "/labels", "a labelled body at least 3 voxels thick along every axis (a volume to mesh)",
                         std::to_string(hi[a] - lo[a] + 1) + " voxel(s) along " + std::string(1, "xyz"[a]));
  }
  check(p.max_elements > 0, "max_elements", "a count > 0", p.max_elements);
  if (const double n = expected_tets_in(labels, p, joints); n > p.max_elements) {
    std::ostringstream f;
    f << "about " << n << " tets at cell size " << p.cell_size_mm << " mm (bone " << p.bone_cell_size_mm << " mm)";
    throw InputError("labels", "cell size",
                     "a mesh of at most " + std::to_string(static_cast<long long>(p.max_elements)) +
                         " tets (coarser --cell-size / --bone-cell-size, or raise --max-elements)",
                     f.str());
  }
}

// Smoothed boundaries between labels: per voxel, the Gaussian-weighted share (sigma in voxels,
// truncated at 3 sigma) of its neighbourhood that has its own label, as 0-255. CGAL's weighted
// labelled-image domain interpolates, for each label, w at the voxels of that label and 255 - w
// at the others, and a point takes the label that interpolates highest: the boundaries follow the
// smoothed indicators' crossing between voxel centres instead of the voxels' faces. Without it a
// surface at a shallow angle to the grid is a staircase of one-voxel terraces, which a fine
// facet distance follows; contact then concentrates on the terraces (README, the hand-block mesh
// study). (CGAL's own generate_label_weights needs ITK.) Each label's indicator is blurred in its
// bounding box grown by the kernel, axis by axis; the voxels away from any boundary get 255.
CGAL::Image_3 boundary_weights(const Volume<std::uint8_t>& labels, double sigma) {
  const std::size_t nx = static_cast<std::size_t>(labels.dims[0]), ny = static_cast<std::size_t>(labels.dims[1]),
                    nz = static_cast<std::size_t>(labels.dims[2]);
  _image* im = _createImage(nx, ny, nz, 1, labels.spacing[0] * 1e3, labels.spacing[1] * 1e3, labels.spacing[2] * 1e3, 1, WK_FIXED, SGN_UNSIGNED);
  auto* w = static_cast<std::uint8_t*>(im->data);
  std::fill(w, w + labels.size(), std::uint8_t{255});
  const int r = static_cast<int>(std::ceil(3 * sigma));
  std::vector<double> kernel(static_cast<std::size_t>(2 * r + 1));
  double sum = 0;
  for (int i = -r; i <= r; ++i) sum += kernel[static_cast<std::size_t>(i + r)] = std::exp(-0.5 * i * i / (sigma * sigma));
  for (double& k : kernel) k /= sum;
  // Bounding boxes of the labels (voxel index ranges), indexed by the 8-bit label.
  std::array<std::array<std::size_t, 6>, 256> box;
  std::array<bool, 256> present{};
  for (std::size_t z = 0, at = 0; z < nz; ++z)
    for (std::size_t y = 0; y < ny; ++y)
      for (std::size_t x = 0; x < nx; ++x, ++at) {
        const std::uint8_t v = labels.data[at];
        auto& b = box[v];
        if (!present[v])
          b = {x, y, z, x, y, z}, present[v] = true;
        else
          b = {std::min(b[0], x), std::min(b[1], y), std::min(b[2], z), std::max(b[3], x), std::max(b[4], y), std::max(b[5], z)};
      }
  std::vector<float> f, g;
  for (int label = 0; label < 256; ++label) {
    if (!present[static_cast<std::size_t>(label)]) continue;
    const auto& b = box[static_cast<std::size_t>(label)];
    const std::size_t lo[3] = {b[0] > static_cast<std::size_t>(r) ? b[0] - r : 0, b[1] > static_cast<std::size_t>(r) ? b[1] - r : 0,
                               b[2] > static_cast<std::size_t>(r) ? b[2] - r : 0};
    const std::size_t hi[3] = {std::min(nx, b[3] + r + 1), std::min(ny, b[4] + r + 1), std::min(nz, b[5] + r + 1)};
    const std::size_t n[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    f.assign(n[0] * n[1] * n[2], 0.0f);
    for (std::size_t z = 0; z < n[2]; ++z)
      for (std::size_t y = 0; y < n[1]; ++y)
        for (std::size_t x = 0; x < n[0]; ++x)
          f[(z * n[1] + y) * n[0] + x] = labels.data[((z + lo[2]) * ny + y + lo[1]) * nx + x + lo[0]] == label ? 1.0f : 0.0f;
    // Axis by axis; outside the image the indicator is its edge voxel's (clamped).
    const std::size_t stride[3] = {1, n[0], n[0] * n[1]};
    for (int axis = 0; axis < 3; ++axis) {
      g.assign(f.size(), 0.0f);
      const std::size_t len = n[axis], s = stride[axis];
      for (std::size_t at = 0; at < f.size(); ++at) {
        const std::size_t i = (at / s) % len, base = at - i * s;
        double v = 0;
        for (int k = -r; k <= r; ++k) {
          const auto j = static_cast<std::size_t>(std::clamp<long>(static_cast<long>(i) + k, 0, static_cast<long>(len) - 1));
          v += kernel[static_cast<std::size_t>(k + r)] * f[base + j * s];
        }
        g[at] = static_cast<float>(v);
      }
      f.swap(g);
    }
    for (std::size_t z = 0; z < n[2]; ++z)
      for (std::size_t y = 0; y < n[1]; ++y)
        for (std::size_t x = 0; x < n[0]; ++x) {
          const std::size_t at = ((z + lo[2]) * ny + y + lo[1]) * nx + x + lo[0];
          if (labels.data[at] == label) w[at] = static_cast<std::uint8_t>(std::lround(255 * std::clamp(f[(z * n[1] + y) * n[0] + x], 0.0f, 1.0f)));
        }
  }
  return CGAL::Image_3(im);
}

// CGAL's labelled-image mesher on the labels (in millimetres: CGAL's criteria are absolute
// lengths), the steps of mesh_label_volume.
class CgalImageMesher {
 public:
  CgalImageMesher(const Volume<std::uint8_t>& labels, const LabelTable& table, const ImageMeshParams& p, std::vector<std::uint8_t> joints)
      : labels_(labels),
        table_(table),
        p_(p),
        image_(make_image(labels)),
        weights_(p.boundary_smoothing_voxels > 0 ? boundary_weights(labels, p.boundary_smoothing_voxels) : CGAL::Image_3()),
        seed_(reseed(p.seed)),
        domain_(Domain::create_labeled_image_mesh_domain(image_, CGAL::parameters::relative_error_bound = 1e-6, CGAL::parameters::weights = weights_,
                                                         CGAL::parameters::value_outside = 0)),
        size_(p.cell_size_mm),
        facet_size_(p.facet_size_mm) {
    // Finer cells in bone, and finer facets on the bone surfaces: facets are chords of the
    // boundary, so a convex bone meshed with the skin's facet size loses ~13 % of its volume.
    for (const auto& [id, name] : table)
      if (id >= contracts::kFirstBoneLabel) {
        size_.set_size(p.bone_cell_size_mm, 3, domain_.index_from_subdomain_index(id));
        facet_size_.set_size(p.bone_facet_size_mm, 2, domain_.index_from_surface_patch_index(Domain::Surface_patch_index(1, id)));
      }
    // A thin label's own size, in its cells and on every surface patch it bounds (patches are
    // (smaller label, larger label) pairs).
    for (const auto& [id, size] : p.label_cell_size_mm) {
      size_.set_size(size, 3, domain_.index_from_subdomain_index(id));
      for (int other = 0; other < 256; ++other)
        if (other != id && (other == 0 || table.count(other)))
          facet_size_.set_size(size, 2,
                               domain_.index_from_surface_patch_index(Domain::Surface_patch_index(std::min(id, other), std::max(id, other))));
    }
    if (p.refine_size_mm > 0) {  // the refined region's fields (RefinedField); CGAL keeps references to them
      region_ = {&p_, &labels_, std::move(joints)};
      refined_facet_size_ = {&facet_size_, &region_, p.refine_size_mm};
      refined_cell_size_ = {&size_, &region_, p.refine_cell_size_mm};
      refined_distance_ = {&p_.facet_distance_mm, &region_, p.refine_distance_mm};
      criteria_ =
          std::make_unique<Criteria>(CGAL::parameters::facet_angle = p.facet_angle_deg, CGAL::parameters::facet_size = refined_facet_size_,
                                     CGAL::parameters::facet_distance = refined_distance_,
                                     CGAL::parameters::cell_radius_edge_ratio = p.cell_radius_edge, CGAL::parameters::cell_size = refined_cell_size_);
    } else {
      criteria_ = std::make_unique<Criteria>(CGAL::parameters::facet_angle = p.facet_angle_deg, CGAL::parameters::facet_size = facet_size_,
                                             CGAL::parameters::facet_distance = p.facet_distance_mm,
                                             CGAL::parameters::cell_radius_edge_ratio = p.cell_radius_edge, CGAL::parameters::cell_size = size_);
    }
    for (auto v : labels.data)
      if (v) wanted_.insert(v);
  }

  // Default initialisation (random surface sampling) gives the better elements; labels it missed
  // get surface points of their own, and as a last resort CGAL seeds every component of every label.
  //
  // The mesh is made with CGAL's manifold criterion: the surface facets are refined until each
  // edge has two facets on a surface sheet and each vertex one fan, so a neck thinner than the
  // facets (a label pinched to one voxel) is resolved rather than left touching at a vertex. The
  // labels are well-composed by then (well_composed.hpp), but a sheet thinner than a voxel can keep
  // asking for smaller facets (a 1.2-voxel shell took 20 GB), so that run is bounded: at most 40
  // vertices per cube of the smallest cell size in the labelled volume (plus 50,000; the phantom
  // hand needs a tenth of it). If it reaches the bound, the mesh is made again without the
  // criterion and quality.json's boundary_manifold guarantee says what is left.
  void refine() {
    // (CGAL's defaults are non_manifold() and no vertex bound, so one call serves both.)
    const auto make = [&](bool manifold, std::size_t bound, CGAL::Mesh_error_code* code) {
      c3t3_ = CGAL::make_mesh_3<C3t3>(
          domain_, *criteria_, CGAL::parameters::no_odt(), CGAL::parameters::no_lloyd(), CGAL::parameters::no_perturb(), CGAL::parameters::no_exude(),
          manifold ? CGAL::parameters::manifold() : CGAL::parameters::non_manifold(),
          CGAL::parameters::mesh_3_options(CGAL::parameters::maximal_number_of_vertices = bound, CGAL::parameters::pointer_to_error_code = code));
      std::set<int> missing = missing_labels();
      for (int attempt = 0; attempt < 4 && !missing_labels().empty(); ++attempt) {
        for (int l : missing_labels()) missing.insert(l);
        seed_missed(missing);
      }
      if (const std::set<int> still = missing_labels(); !still.empty()) seed_everything(still);
    };
    std::size_t labelled = 0;
    for (auto v : labels_.data) labelled += v != 0;
    const double cell = std::min(p_.cell_size_mm, p_.bone_cell_size_mm);
    const double cells = static_cast<double>(labelled) * labels_.voxel_volume() * 1e9 / (cell * cell * cell);
    const std::size_t bound = 50000 + static_cast<std::size_t>(40 * cells);
    CGAL::Mesh_error_code code = CGAL::CGAL_MESH_3_NO_ERROR;
    make(true, bound, &code);
    manifold_pass_capped_ = code != CGAL::CGAL_MESH_3_NO_ERROR;
    if (manifold_pass_capped_) {
      log::info() << "mesher: the manifold criterion reached its bound of " << bound
                  << " vertices; the mesh is made without it (quality.json's boundary_manifold says what is left)";
      make(false, 0, nullptr);
    }
  }

  void optimise() {
    const double limit = p_.optimiser_time_limit_s;
    CGAL::refine_mesh_3(
        c3t3_, domain_, *criteria_, p_.odt ? CGAL::parameters::odt(CGAL::parameters::time_limit = limit) : CGAL::parameters::no_odt(),
        p_.lloyd ? CGAL::parameters::lloyd(CGAL::parameters::time_limit = limit) : CGAL::parameters::no_lloyd(),
        p_.perturb ? CGAL::parameters::perturb(CGAL::parameters::time_limit = limit, CGAL::parameters::sliver_bound = p_.exude_sliver_bound_deg)
                   : CGAL::parameters::no_perturb(),
        p_.exude ? CGAL::parameters::exude(CGAL::parameters::time_limit = limit, CGAL::parameters::sliver_bound = p_.exude_sliver_bound_deg)
                 : CGAL::parameters::no_exude());
  }

  bool manifold_pass_capped() const { return manifold_pass_capped_; }

  // The complex as a TetMesh in metres: tets by label, skin and bone-interface triangles oriented
  // out of their inner material; triangle_inner: that material (0 for the outer skin).
  TetMesh extract(std::vector<int>& triangle_inner, std::map<int, std::size_t>& per_label) const;

 private:
  // CGAL's random sampling restarts from the seed once the image exists, before the domain (a
  // reproducible mesh).
  static unsigned reseed(unsigned seed) {
    CGAL::get_default_random() = CGAL::Random(seed);
    return seed;
  }

  static CGAL::Image_3 make_image(const Volume<std::uint8_t>& labels) {
    _image* im =
        _createImage(static_cast<std::size_t>(labels.dims[0]), static_cast<std::size_t>(labels.dims[1]), static_cast<std::size_t>(labels.dims[2]), 1,
                     labels.spacing[0] * 1e3, labels.spacing[1] * 1e3, labels.spacing[2] * 1e3, 1, WK_FIXED, SGN_UNSIGNED);
    std::memcpy(im->data, labels.data.data(), labels.size());
    return CGAL::Image_3(im);
  }

  std::set<int> missing_labels() const {
    std::set<int> seen, missing;
    for (auto cell = c3t3_.cells_in_complex_begin(); cell != c3t3_.cells_in_complex_end(); ++cell)
      seen.insert(static_cast<int>(c3t3_.subdomain_index(cell)));
    for (int l : wanted_)
      if (!seen.count(l)) missing.insert(l);
    return missing;
  }

  std::string names(const std::set<int>& labels) const {
    std::string out;
    for (int l : labels) out += (out.empty() ? "" : ", ") + (table_.count(l) ? table_.at(l) : std::to_string(l));
    return out;
  }

  // A small subdomain was missed: the same random sampling plus a few surface points on each
  // missed label only (seeding every component of every label, as CGAL's
  // initialize_triangulation_from_labeled_image does, clusters tiny tets along all surfaces).
  void seed_missed(const std::set<int>& missing) {
    log::verbose() << "mesher: the initial sampling missed " << names(missing) << "; adding surface points on them";
    const auto& labels = labels_;
    const auto& domain = domain_;
    const auto& p = p_;
    auto& c3t3 = c3t3_;
    c3t3 = C3t3();
    CGAL::get_default_random() = CGAL::Random(p.seed);
    std::vector<std::pair<Domain::Point_3, Domain::Index>> points;
    domain.construct_initial_points_object()(std::back_inserter(points));
    const double sp[3] = {labels.spacing[0] * 1e3, labels.spacing[1] * 1e3, labels.spacing[2] * 1e3};
    auto label_at = [&](const double q[3]) {
      long idx[3];
      for (int a = 0; a < 3; ++a) {
        idx[a] = std::lround(q[a] / sp[a]);
        if (idx[a] < 0 || idx[a] >= labels.dims[a]) return -1;
      }
      return static_cast<int>(labels.at(static_cast<int>(idx[0]), static_cast<int>(idx[1]), static_cast<int>(idx[2])));
    };
    for (int l : missing) {
      double sum[3] = {0, 0, 0};
      std::size_t n = 0;
      for (int k = 0; k < labels.dims[2]; ++k)
        for (int j = 0; j < labels.dims[1]; ++j)
          for (int i = 0; i < labels.dims[0]; ++i)
            if (labels.at(i, j, k) == l) sum[0] += static_cast<double>(i), sum[1] += static_cast<double>(j), sum[2] += static_cast<double>(k), ++n;
      double c[3] = {0, 0, 0}, best = 1e300;  // the label's voxel nearest to its centroid
      for (int k = 0; k < labels.dims[2]; ++k)
        for (int j = 0; j < labels.dims[1]; ++j)
          for (int i = 0; i < labels.dims[0]; ++i)
            if (labels.at(i, j, k) == l) {
              const double d = std::pow(static_cast<double>(i) - sum[0] / static_cast<double>(n), 2) +
                               std::pow(static_cast<double>(j) - sum[1] / static_cast<double>(n), 2) +
                               std::pow(static_cast<double>(k) - sum[2] / static_cast<double>(n), 2);
              if (d < best)
                best = d, c[0] = static_cast<double>(i) * sp[0], c[1] = static_cast<double>(j) * sp[1], c[2] = static_cast<double>(k) * sp[2];
            }
      // Rays along the axes and the diagonals, each cut at its first voxel outside the label.
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            if (dx == 0 && dy == 0 && dz == 0) continue;
            const double len = std::sqrt(static_cast<double>(dx * dx + dy * dy + dz * dz));
            const double d[3] = {dx / len, dy / len, dz / len};
            const double step = 0.5 * std::min({sp[0], sp[1], sp[2]});
            double q[3] = {c[0], c[1], c[2]};
            int steps = 0;
            while (label_at(q) == l && steps < 10000) {
              for (int a = 0; a < 3; ++a) q[a] += step * d[a];
              ++steps;
            }
            for (int a = 0; a < 3; ++a) q[a] += 2 * step * d[a];
            const auto hit =
                domain.construct_intersection_object()(Domain::Segment_3(Domain::Point_3(c[0], c[1], c[2]), Domain::Point_3(q[0], q[1], q[2])));
            if (std::get<2>(hit) == 2) points.emplace_back(std::get<0>(hit), std::get<1>(hit));
            log::debug() << "mesher: label " << l << " ray from (" << c[0] << ", " << c[1] << ", " << c[2] << ") mm, " << steps
                         << " steps inside, hit dimension " << std::get<2>(hit);
          }
    }
    auto cwp = c3t3.triangulation().geom_traits().construct_weighted_point_3_object();
    for (const auto& [point, idx] : points) {
      const auto v = c3t3.triangulation().insert(cwp(point));
      if (v != Tr::Vertex_handle()) c3t3.set_dimension(v, 2), c3t3.set_index(v, idx);
    }
    CGAL::refine_mesh_3(c3t3, domain_, *criteria_, CGAL::parameters::no_odt(), CGAL::parameters::no_lloyd(), CGAL::parameters::no_perturb(),
                        CGAL::parameters::no_exude());
  }

  void seed_everything(const std::set<int>& still) {
    log::verbose() << "mesher: still missing " << names(still) << "; seeding every component of every label";
    c3t3_ = C3t3();
    {
      // CGAL 5.5 prints its progress to std::cout here; keep our stdout for our own output.
      std::ostringstream sink;
      std::streambuf* saved = std::cout.rdbuf(sink.rdbuf());
      ::initialize_triangulation_from_labeled_image(c3t3_, domain_, image_, *criteria_, static_cast<unsigned char>(0));
      std::cout.rdbuf(saved);
    }
    CGAL::refine_mesh_3(c3t3_, domain_, *criteria_, CGAL::parameters::no_odt(), CGAL::parameters::no_lloyd(), CGAL::parameters::no_perturb(),
                        CGAL::parameters::no_exude());
  }

  const Volume<std::uint8_t>& labels_;
  const LabelTable& table_;
  const ImageMeshParams& p_;
  CGAL::Image_3 image_;
  CGAL::Image_3 weights_;  // invalid unless boundary_smoothing_voxels > 0; the domain reads it (declared before it)
  unsigned seed_;
  Domain domain_;
  SizeField size_, facet_size_;
  RefinedRegion region_;                                            // the refined box and joints
  RefinedField<SizeField> refined_facet_size_, refined_cell_size_;  // with refine_size_mm > 0: the fields above, finer in the region
  RefinedField<double> refined_distance_;
  std::unique_ptr<Criteria> criteria_;
  std::set<int> wanted_;
  C3t3 c3t3_;
  bool manifold_pass_capped_ = false;  // the manifold criterion reached its vertex bound: made without it
};

TetMesh CgalImageMesher::extract(std::vector<int>& triangle_inner, std::map<int, std::size_t>& per_label) const {
  const auto& labels = labels_;
  const auto& c3t3 = c3t3_;
  TetMesh mesh;
  std::map<Tr::Vertex_handle, int> index;
  const Vec3 origin = labels.origin;
  auto node = [&](Tr::Vertex_handle v) {
    auto [it, fresh] = index.emplace(v, static_cast<int>(mesh.nodes.size()));
    if (fresh) {
      const auto& q = v->point().point();
      mesh.nodes.push_back({origin[0] + q.x() * 1e-3, origin[1] + q.y() * 1e-3, origin[2] + q.z() * 1e-3});
    }
    return it->second;
  };
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
    std::array<int, 4> t = {node(c->vertex(0)), node(c->vertex(1)), node(c->vertex(2)), node(c->vertex(3))};
    if (tet_volume(mesh.nodes[static_cast<std::size_t>(t[0])], mesh.nodes[static_cast<std::size_t>(t[1])], mesh.nodes[static_cast<std::size_t>(t[2])],
                   mesh.nodes[static_cast<std::size_t>(t[3])]) < 0)
      std::swap(t[2], t[3]);
    mesh.tets.push_back(t);
    const int label = static_cast<int>(c3t3.subdomain_index(c));
    mesh.tet_group.push_back(label);
    ++per_label[label];
  }
  for (auto f = c3t3.facets_in_complex_begin(); f != c3t3.facets_in_complex_end(); ++f) {
    const auto [a, b] = c3t3.surface_patch_index(*f);
    const int lo = std::min(a, b), hi = std::max(a, b);
    if (lo == hi) continue;
    // Orient outward from the inner material: soft tissue for the skin, bone for interfaces.
    Tr::Cell_handle cell = f->first;
    int i = f->second;
    const int inner = hi;  // soft tissue under the skin (0 | 1), the bone at an interface (1 | b)
    if (!c3t3.is_in_complex(cell) || static_cast<int>(c3t3.subdomain_index(cell)) != inner) {
      const auto mirror = c3t3.triangulation().mirror_facet(*f);
      cell = mirror.first, i = mirror.second;
    }
    std::array<int, 3> tri{};
    int k = 0;
    for (int j = 0; j < 4; ++j)
      if (j != i) tri[static_cast<std::size_t>(k++)] = node(cell->vertex(j));
    const Vec3 apex = mesh.nodes[static_cast<std::size_t>(node(cell->vertex(i)))];
    if (tet_volume(mesh.nodes[static_cast<std::size_t>(tri[0])], mesh.nodes[static_cast<std::size_t>(tri[1])],
                   mesh.nodes[static_cast<std::size_t>(tri[2])], apex) > 0)
      std::swap(tri[1], tri[2]);
    mesh.triangles.push_back(tri);
    mesh.triangle_group.push_back(lo == 0 ? contracts::kSkinTag : contracts::kBoneInterfaceTag);
    triangle_inner.push_back(lo == 0 ? 0 : inner);  // 0: the outer skin
  }
  return mesh;
}

// Every label got tets, or a clear error naming it.
void check_every_label_meshed(const Volume<std::uint8_t>& labels, const LabelTable& table, const std::map<int, std::size_t>& per_label) {
  std::map<int, std::size_t> voxels;
  for (auto v : labels.data)
    if (v) ++voxels[v];
  for (const auto& [label, n] : voxels)
    if (!per_label.count(label)) {
      auto it = table.find(label);
      throw NumericalError("mesher: label " + std::to_string(label) + " (" + (it != table.end() ? it->second : "?") + ", " + std::to_string(n) +
                           " voxels) received no tetrahedra; refine --bone-cell-size/--bone-facet-size");
    }
}

// The last post-pass (boundary_pinches.cpp), said in the log when it had anything to do.
BoundaryPinchReport resolve_pinches_logged(TetMesh& mesh, const PostPassParams& post) {
  const auto start = std::chrono::steady_clock::now();
  const BoundaryPinchReport r = resolve_boundary_pinches(mesh, post);
  log::verbose() << "mesher: the boundary pinch pass took " << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
                 << " s";
  if (r.defects_before > 0)
    log::info() << "mesher: " << r.defects_before << " non-manifold boundary edge(s) and vertex(es) after meshing; " << r.tets_relabelled
                << " tet(s) relabelled and " << r.tets_removed << " removed (" << r.volume_moved_m3 * 1e9 << " mm^3), " << r.defects_after << " left";
  return r;
}

}  // namespace

TetMesh mesh_label_volume(const Volume<std::uint8_t>& labels, const LabelTable& table, const ImageMeshParams& p, ImageMeshReport* report) {
  std::vector<std::uint8_t> joints = refined_joints(labels, p);
  validate(labels, p, joints);
  CgalImageMesher cgal(labels, table, p, std::move(joints));
  cgal.refine();
  cgal.optimise();
  std::vector<int> triangle_inner;
  std::map<int, std::size_t> per_label;
  TetMesh mesh = cgal.extract(triangle_inner, per_label);
  // The post-passes (post_passes.hpp), CGAL-free.
  PostPassParams post = p.post;
  // How far a post-pass may move a surface node: the facet distance, the refined region's where
  // there is one (one bound for the whole mesh: the finer surface keeps its accuracy).
  const double surface_move =
      1e-3 * (p.refine_size_mm > 0 && p.refine_distance_mm > 0 ? std::min(p.facet_distance_mm, p.refine_distance_mm) : p.facet_distance_mm);
  post.relocate_passes = p.relocate_passes;
  // At debug level (-vv), the boundary defects after each pass: which pass makes a boundary
  // non-manifold (each count walks every face; not paid otherwise).
  const auto trace_defects = [&](const char* after) {
    if (log::level() < log::Level::debug) return;
    std::size_t n = 0;
    for (const auto& [name, t] : boundary_topology(mesh)) n += t.non_manifold_edges + t.non_manifold_vertices;
    log::debug() << "mesher: " << n << " boundary defects (non-manifold edges + vertices) after " << after;
  };
  trace_defects("CGAL");
  if (p.restore_volumes) {
    restore_volumes(mesh, labels, triangle_inner, post);
    trace_defects("volume restore");
  }
  if (p.relocate_passes > 0) {
    relocate_short_tets(mesh, surface_move, post);
    trace_defects("short-tet relocation");
  }
  if (p.peel_skin_slivers) {
    // Sweeps until nothing changes: peeling one sliver can put its neighbour flat on the skin.
    std::size_t peeled = 0;
    for (int sweep = 0; sweep < post.peel_sweeps; ++sweep) {
      const std::size_t n = peel_skin_slivers(mesh, post);
      peeled += n;
      if (n == 0) break;
    }
    log::verbose() << "mesher: peeled " << peeled << " soft-tissue slivers lying on the skin";
    trace_defects("sliver peeling");
    if (peeled > 0 && p.relocate_passes > 0) relocate_short_tets(mesh, surface_move, post);
  }
  if (p.relocate_passes > 0) {
    // The guarantees: relocation and interior edge splits, then short surface edges collapsed
    // where those could not help, and relocation again around them.
    std::size_t left = relocate_poor_tets(mesh, surface_move, post);
    for (int round = 0; round < post.split_rounds && left > 0; ++round) {
      const std::size_t merged = collapse_poor_surface_edges(mesh, surface_move, post);
      log::verbose() << "mesher: " << left << " tets below the guarantees; " << merged << " surface edges collapsed";
      if (merged == 0) break;
      left = relocate_poor_tets(mesh, surface_move, post);
    }
    if (left > 0) {
      const std::size_t flipped = flip_poor_tets(mesh, post);
      log::verbose() << "mesher: " << left << " tets below the guarantees; " << flipped << " flips (2-3 and edge removal)";
      if (flipped > 0) left = relocate_poor_tets(mesh, surface_move, post);
    }
    if (left > 0) {
      const std::size_t given = give_wedges_to_bone(mesh, post);
      log::verbose() << "mesher: " << given << " soft-tissue wedges between bone faces given to the bone";
      if (given > 0) left = relocate_poor_tets(mesh, surface_move, post);
    }
    log::verbose() << "mesher: " << left << " tets below the guarantees after the post-passes";
    trace_defects("the guarantee passes");
  }
  ImageMeshReport done;
  done.manifold_criterion_capped = cgal.manifold_pass_capped();
  if (p.resolve_boundary_pinches) done.pinches = resolve_pinches_logged(mesh, post);
  if (report) *report = done;
  check_every_label_meshed(labels, table, per_label);
  // Meshed and improved in the voxels' axis-aligned frame (the relocation pass tries moves along
  // its axes); now placed where the voxels are in the world. A reflection turns every tet and
  // triangle inside out, so their node order is turned back.
  if (!is_identity(labels.direction)) {
    for (Vec3& x : mesh.nodes) {
      const auto w = labels.to_world({x[0], x[1], x[2]});
      x = {w[0], w[1], w[2]};
    }
    if (determinant(labels.direction) < 0) {
      for (auto& t : mesh.tets) std::swap(t[2], t[3]);
      for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
    }
  }
  for (const auto& [label, count] : per_label) {
    auto it = table.find(label);
    mesh.groups.push_back({3, label, it != table.end() ? it->second : "label_" + std::to_string(label)});
  }
  mesh.groups.push_back({2, contracts::kSkinTag, contracts::kSkinGroup});
  mesh.groups.push_back({2, contracts::kBoneInterfaceTag, contracts::kBoneInterfaceGroup});
  log::verbose() << "mesher: " << mesh.nodes.size() << " nodes, " << mesh.tets.size() << " tets, " << mesh.triangles.size() << " boundary triangles";
  return mesh;
}

}  // namespace tactus::mesher
