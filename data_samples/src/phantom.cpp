// The synthetic hand CT. Geometry is a set of signed distance functions in millimetres:
// bones are capsules (segment + radius) whose outer shell of thickness t is cortical bone,
// the soft-tissue envelope is a smooth union of a wrist, a palm and capsules around each finger.
#include "tactus/data_samples/phantom.hpp"

#include <omp.h>
#include <exception>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sstream>

#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/staged_output.hpp"
#include "tactus/core/volume_filters.hpp"

namespace tactus::samples {

namespace {

struct V3 {
  double x = 0, y = 0, z = 0;
};
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
double norm(V3 a) { return std::sqrt(dot(a, a)); }
V3 unit(V3 a) { return (1.0 / norm(a)) * a; }

struct Capsule {
  V3 a, b;
  double r;
  double distance(V3 p) const {
    const V3 ab = b - a, ap = p - a;
    const double t = std::clamp(dot(ap, ab) / dot(ab, ab), 0.0, 1.0);
    return norm(ap - t * ab) - r;
  }
  double zmin() const { return std::min(a.z, b.z) - r; }
  double zmax() const { return std::max(a.z, b.z) + r; }
};

struct Bone {
  std::string name;
  Capsule shape;
  double cortex;  // shell thickness, mm
};

struct RoundedBox {
  V3 centre, half;
  double round;
  double distance(V3 p) const {
    const double qx = std::abs(p.x - centre.x) - half.x, qy = std::abs(p.y - centre.y) - half.y, qz = std::abs(p.z - centre.z) - half.z;
    const double ox = std::max(qx, 0.0), oy = std::max(qy, 0.0), oz = std::max(qz, 0.0);
    return std::sqrt(ox * ox + oy * oy + oz * oz) + std::min(std::max({qx, qy, qz}), 0.0) - round;
  }
};

// Polynomial smooth minimum (blend width k), for a soft-tissue envelope without creases.
double smin(double a, double b, double k) {
  const double h = std::max(k - std::abs(a - b), 0.0) / k;
  return std::min(a, b) - h * h * k * 0.25;
}

V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

// Turns direction d by angle (radians) about the unit axis a (Rodrigues).
V3 rotate(V3 d, V3 a, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return c * d + s * cross(a, d) + ((1 - c) * dot(a, d)) * a;
}

// The palm faces -y: fingers flex towards it.
constexpr V3 kPalmNormal{0, -1, 0};

struct Anatomy {
  std::vector<Bone> bones;
  std::vector<std::string> parents;   // per bone; empty for the carpals (the roots)
  std::vector<SkeletonJoint> joints;  // in mm
  std::vector<Capsule> envelope;      // finger and thumb sleeves
  RoundedBox wrist, palm;
};

double cortex_for(double r) { return std::clamp(0.32 * r, 1.0, 1.8); }

Vec3 vec3(V3 v) { return {v.x, v.y, v.z}; }

// One finger or the thumb, from its carpal outwards.
struct Chain {
  std::string carpal, digit;  // the carpal its metacarpal sits on; "index", ..., "thumb"
  V3 base, dir;               // the metacarpal's base centre and its direction
  std::vector<double> length, radius;
  std::vector<std::string> bones, joints;  // bone and joint names without the digit
  double flexion = 0;                      // of each joint after the first, radians
  double sleeve = 0;                       // soft tissue around each bone's radius, mm
  bool sleeve_on_metacarpal = false;       // the thumb's metacarpal stands out of the palm
};

// Each joint after the first turns by `flexion` about the chain's own flexion axis
// a = d x n / |d x n| (in the palm's plane, across the digit) through the proximal bone's head
// centre (its capsule's end), so a flexed phantom is the straight one with each joint turned.
// Records the bones' parents and the joints' truth; the carpometacarpal joint's centre is the
// metacarpal's base centre (the carpal has no head facing it).
void add_chain(Anatomy& h, const Chain& c, double gap) {
  const V3 axis = unit(cross(c.dir, kPalmNormal));
  V3 head = c.base, start = c.base, dir = c.dir;
  for (std::size_t s = 0; s < c.length.size(); ++s) {
    if (s > 0) {
      dir = rotate(c.dir, axis, static_cast<double>(s) * c.flexion);
      start = head + (c.radius[s - 1] + gap + c.radius[s]) * dir;
    }
    const V3 end = start + c.length[s] * dir;
    const std::string name = c.bones[s] + "_" + c.digit;
    const std::string parent = s == 0 ? c.carpal : h.bones.back().name;
    h.joints.push_back({c.joints[s] + "_" + c.digit, parent, name, vec3(s == 0 ? start : head), vec3(axis), vec3(unit(cross(axis, dir)))});
    h.bones.push_back({name, {start, end, c.radius[s]}, cortex_for(c.radius[s])});
    h.parents.push_back(parent);
    if (s > 0 || c.sleeve_on_metacarpal) h.envelope.push_back({start - (s == 0 ? 0.0 : c.radius[s] + 1.0) * dir, end, c.radius[s] + c.sleeve});
    head = end;
  }
}

Anatomy build_anatomy(double flexion) {
  Anatomy h;
  constexpr double gap = 2.2;  // joint gap between bone surfaces, mm
  // Carpals: two rows of four short capsules across the wrist.
  const char* proximal[4] = {"scaphoid", "lunate", "triquetrum", "pisiform"};
  const char* distal[4] = {"trapezium", "trapezoid", "capitate", "hamate"};
  const double carpal_r = 4.6, carpal_half = 1.6, row_dz = 2 * carpal_r + gap + 0.4;
  for (int i = 0; i < 4; ++i) {
    const double x = -21.0 + 14.0 * i;
    const double y = i == 3 ? -3.0 : 0.0;
    h.bones.push_back({proximal[i], {{x - carpal_half, y, 34}, {x + carpal_half, y, 34}, carpal_r}, cortex_for(carpal_r)});
    h.bones.push_back({distal[i], {{x - carpal_half, 0, 34 + row_dz}, {x + carpal_half, 0, 34 + row_dz}, carpal_r}, cortex_for(carpal_r)});
    h.parents.insert(h.parents.end(), 2, std::string());
  }
  const double carpal_top = 34 + row_dz + carpal_r;
  // The distal-row carpal a metacarpal's base sits on.
  auto carpal_under = [&](double x) { return std::string(distal[std::clamp(static_cast<int>(std::lround((x + 21.0) / 14.0)), 0, 3)]); };
  // Fingers 2-5: metacarpal, proximal, middle, distal phalanx; fanned in x, flexed towards -y.
  const char* finger[4] = {"index", "middle", "ring", "little"};
  const double base_x[4] = {-22, -7.5, 7.5, 22}, fan_deg[4] = {-7, -2, 3, 7};
  const std::vector<std::vector<double>> len = {{62, 37, 22, 16}, {60, 40, 25, 17}, {55, 38, 24, 17}, {50, 31, 18, 15}};
  const std::vector<std::vector<double>> rad = {{4.6, 4.1, 3.5, 3.1}, {4.7, 4.3, 3.6, 3.2}, {4.4, 4.0, 3.4, 3.0}, {4.0, 3.6, 3.1, 2.8}};
  for (int f = 0; f < 4; ++f) {
    const double fan = fan_deg[f] * M_PI / 180;
    add_chain(h,
              {carpal_under(base_x[f]),
               finger[f],
               {base_x[f], 0, carpal_top + gap + rad[f][0]},
               unit({std::sin(fan), 0, std::cos(fan)}),
               len[f],
               rad[f],
               {"metacarpal", "proximal_phalanx", "middle_phalanx", "distal_phalanx"},
               {"cmc", "mcp", "pip", "dip"},
               flexion,
               5.6,
               false},
              gap);
  }
  // Thumb: metacarpal from the trapezium outwards and palmwards (its direction chosen so the hand
  // keeps the paper's width and thickness at the default flexion), then two phalanges; its joints
  // flex by 0.8 of the fingers' angle about its own axis.
  add_chain(h,
            {"trapezium",
             "thumb",
             {-31, -6, carpal_top + 1.5},
             unit({-0.60, -0.18, 0.76}),
             {40, 32, 24},
             {4.6, 4.2, 3.5},
             {"metacarpal", "proximal_phalanx", "distal_phalanx"},
             {"cmc", "mcp", "ip"},
             0.8 * flexion,
             6.5,
             true},
            gap);
  h.wrist = {{0, 0, 14}, {22, 10, 20}, 9};
  h.palm = {{2, 0, 80}, {30, 12, 42}, 9};
  return h;
}

// The truth in the mesh frame (metres): capsule bones have their centroid at the axis' midpoint.
Skeleton skeleton_of(const Anatomy& h) {
  auto metres = [](const Vec3& v) { return Vec3{v[0] * 1e-3, v[1] * 1e-3, v[2] * 1e-3}; };
  Skeleton sk;
  sk.source = "tactus-phantom (the truth it builds the bones from)";
  sk.palm_normal = vec3(kPalmNormal);
  for (std::size_t b = 0; b < h.bones.size(); ++b) {
    const Capsule& c = h.bones[b].shape;
    sk.bones.push_back({h.bones[b].name, h.parents[b], static_cast<int>(b) + contracts::kFirstBoneLabel, metres(vec3(0.5 * (c.a + c.b))),
                        vec3(unit(c.b - c.a)), (norm(c.b - c.a) + 2 * c.r) * 1e-3});
  }
  for (SkeletonJoint j : h.joints) {
    j.centre = metres(j.centre);
    sk.joints.push_back(j);
  }
  validate_skeleton(sk, "tactus-phantom");
  return sk;
}

struct EnvelopeBounds {
  double lo[3] = {1e9, 1e9, 0}, hi[3] = {-1e9, -1e9, -1e9};  // mm; the wrist is cut at z = 0
};

// Bounding box of the soft-tissue envelope, sampled on a 1.5 mm lattice over the primitives' own
// bounds (the smooth union reaches at most k/4 = 2 mm past them), so no posture is clipped.
EnvelopeBounds envelope_bounds(const Anatomy& h) {
  auto envelope = [&](V3 q) {
    double d = smin(h.wrist.distance(q), h.palm.distance(q), 8.0);
    for (const auto& c : h.envelope) d = smin(d, c.distance(q), 7.0);
    return d;
  };
  double reach_lo[3] = {1e9, 1e9, 0}, reach_hi[3] = {-1e9, -1e9, -1e9};
  auto reach = [&](V3 lo_corner, V3 hi_corner) {
    const double l[3] = {lo_corner.x, lo_corner.y, lo_corner.z}, u[3] = {hi_corner.x, hi_corner.y, hi_corner.z};
    for (int a = 0; a < 3; ++a) reach_lo[a] = std::min(reach_lo[a], l[a] - 3), reach_hi[a] = std::max(reach_hi[a], u[a] + 3);
  };
  for (const RoundedBox& box : {h.wrist, h.palm})
    reach(box.centre - box.half - V3{box.round, box.round, box.round}, box.centre + box.half + V3{box.round, box.round, box.round});
  for (const auto& c : h.envelope)
    reach({std::min(c.a.x, c.b.x) - c.r, std::min(c.a.y, c.b.y) - c.r, std::min(c.a.z, c.b.z) - c.r},
          {std::max(c.a.x, c.b.x) + c.r, std::max(c.a.y, c.b.y) + c.r, std::max(c.a.z, c.b.z) + c.r});
  auto lattice = [](double anchor, double v) { return anchor + 1.5 * std::floor((v - anchor) / 1.5); };  // the lattice point below v
  EnvelopeBounds out;
  for (double x = lattice(-120, reach_lo[0]); x <= reach_hi[0]; x += 1.5)
    for (double y = lattice(-80, reach_lo[1]); y <= reach_hi[1]; y += 1.5)
      for (double z = 0; z <= reach_hi[2]; z += 1.5)
        if (envelope({x, y, z}) <= 0) {
          out.lo[0] = std::min(out.lo[0], x), out.hi[0] = std::max(out.hi[0], x);
          out.lo[1] = std::min(out.lo[1], y), out.hi[1] = std::max(out.hi[1], y);
          out.hi[2] = std::max(out.hi[2], z);
        }
  return out;
}

}  // namespace

Phantom make_hand_phantom(const PhantomParams& p) {
  for (double v : {p.voxel_mm, p.slice_mm})
    if (!(v >= 0.05 && v <= 50)) throw InputError("phantom parameters", "--voxel-mm/--slice-mm", "voxel sizes from 0.05 to 50 mm", std::to_string(v));
  if (!(std::abs(p.bias_hu) <= 1000)) throw InputError("phantom parameters", "--bias", "a bias amplitude within 1000 HU", std::to_string(p.bias_hu));
  if (!(p.noise_hu >= 0 && p.noise_hu <= 5000) || !(p.blur_voxels >= 0 && p.blur_voxels <= 20))
    throw InputError("phantom parameters", "--noise/--blur", "noise 0..5000 HU and blur 0..20 voxels");
  if (!(std::abs(p.flexion_deg) <= 90))
    throw InputError("phantom parameters", "--flexion", "an angle within +-90 degrees", std::to_string(p.flexion_deg));
  const Anatomy h = build_anatomy(p.flexion_deg * M_PI / 180);

  const EnvelopeBounds bounds = envelope_bounds(h);
  const double* lo = bounds.lo;
  const double* hi = bounds.hi;
  const double step[3] = {p.voxel_mm, p.voxel_mm, p.slice_mm};
  std::array<int, 3> dims{};
  std::array<double, 3> origin_mm{};
  for (int a = 0; a < 3; ++a) {
    const double start = a == 2 ? 0.0 : lo[a] - 1.5 - p.margin_mm;  // the wrist is cut at z = 0
    const double end = hi[a] + 1.5 + p.margin_mm;
    origin_mm[a] = start;
    dims[a] = static_cast<int>(std::ceil((end - start) / step[a])) + 1;
  }
  Phantom out;
  const std::array<double, 3> spacing_m{step[0] * 1e-3, step[1] * 1e-3, step[2] * 1e-3};
  const std::array<double, 3> origin_m{origin_mm[0] * 1e-3, origin_mm[1] * 1e-3, origin_mm[2] * 1e-3};
  // 1 (truth) + 2 (CT) + 4 + 4 (HU and its blur buffer) bytes per voxel: refused before allocating.
  validate_volume_geometry(dims, spacing_m, origin_m, 11, "phantom parameters", "--voxel-mm/--slice-mm");
  out.truth = Volume<std::uint8_t>(dims, spacing_m, origin_m, 0);
  out.ct = Volume<std::int16_t>(dims, spacing_m, origin_m, 0);
  out.labels[contracts::kBackgroundLabel] = "background";
  out.labels[contracts::kSoftTissueLabel] = contracts::kSoftTissueName;
  for (std::size_t b = 0; b < h.bones.size(); ++b) out.labels[static_cast<int>(b) + contracts::kFirstBoneLabel] = h.bones[b].name;
  out.skeleton = skeleton_of(h);

  Volume<float> hu_volume(dims, spacing_m, origin_m, 0.0f);
  std::vector<float>& hu = hu_volume.data;
#pragma omp parallel for schedule(dynamic)
  for (int k = 0; k < dims[2]; ++k) {
    const double z = origin_mm[2] + k * step[2];
    std::vector<std::size_t> bones_here, sleeves_here;  // primitives that reach this slice
    for (std::size_t b = 0; b < h.bones.size(); ++b)
      if (z >= h.bones[b].shape.zmin() - 1 && z <= h.bones[b].shape.zmax() + 1) bones_here.push_back(b);
    for (std::size_t c = 0; c < h.envelope.size(); ++c)
      if (z >= h.envelope[c].zmin() - 8 && z <= h.envelope[c].zmax() + 8) sleeves_here.push_back(c);
    for (int j = 0; j < dims[1]; ++j)
      for (int i = 0; i < dims[0]; ++i) {
        const V3 q{origin_mm[0] + i * step[0], origin_mm[1] + j * step[1], z};
        double d = smin(h.wrist.distance(q), h.palm.distance(q), 8.0);
        for (std::size_t c : sleeves_here) d = smin(d, h.envelope[c].distance(q), 7.0);
        const std::size_t idx = out.ct.index(i, j, k);
        if (d > 0) {
          hu[idx] = PhantomHu::air;
          continue;
        }
        std::uint8_t label = 1;
        double value = d > -1.5 ? PhantomHu::skin : PhantomHu::soft_tissue;
        for (std::size_t b : bones_here) {
          const double db = h.bones[b].shape.distance(q);
          if (db <= 0) {
            label = static_cast<std::uint8_t>(b + 2);
            value = db > -h.bones[b].cortex ? PhantomHu::cortical : PhantomHu::trabecular;
            break;
          }
        }
        out.truth.data[idx] = label;
        hu[idx] = static_cast<float>(value);
      }
  }
  gaussian_blur(hu_volume, p.blur_voxels);
  // Noise: one generator per slice, seeded from (seed, slice), so results do not depend on threads.
#pragma omp parallel for schedule(static)
  for (int k = 0; k < dims[2]; ++k) {
    std::mt19937_64 rng(p.seed * 1000003ULL + static_cast<std::uint64_t>(k));
    std::normal_distribution<float> noise(0.0f, static_cast<float>(p.noise_hu));
    const std::size_t begin = out.ct.index(0, 0, k), end = begin + static_cast<std::size_t>(dims[0]) * dims[1];
    for (std::size_t idx = begin; idx < end; ++idx) {
      float v = hu[idx] + (p.noise_hu > 0 ? noise(rng) : 0.0f);
      if (p.bias_hu != 0) {  // a smooth additive field: +-bias_hu from one end of the slice axis to the other, and across x
        const double sz = dims[2] > 1 ? static_cast<double>(k) / (dims[2] - 1) : 0.5;
        const double sx = static_cast<double>((idx - begin) % static_cast<std::size_t>(dims[0])) / std::max(1, dims[0] - 1);
        v += static_cast<float>(p.bias_hu * (std::sin(M_PI * (sz - 0.5)) + 0.5 * std::cos(M_PI * sx)));
      }
      out.ct.data[idx] = static_cast<std::int16_t>(std::lround(std::clamp(v, -1024.0f, 3071.0f)));
    }
  }
  return out;
}

void write_slice_stack(const Volume<std::int16_t>& ct, const std::filesystem::path& folder) {
  constexpr int kIntercept = -1024;  // stored = HU - intercept, in 16-bit
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec) throw WriteError(folder.string(), "cannot create the folder (" + ec.message() + ")");
  const int nx = ct.dims[0], ny = ct.dims[1], nz = ct.dims[2];
  const int width = std::max(4, static_cast<int>(std::to_string(nz - 1).size()));
  bool ok = true;
  std::exception_ptr failure;  // the first slice that could not be written (a full disk, say)
#pragma omp parallel for schedule(dynamic) reduction(&& : ok)
  for (int k = 0; k < nz; ++k) {
    cv::Mat slice(ny, nx, CV_16UC1);
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) slice.at<std::uint16_t>(j, i) = static_cast<std::uint16_t>(ct.at(i, j, k) - kIntercept);
    std::ostringstream name;
    name << "slice_" << std::setw(width) << std::setfill('0') << k << ".png";
    // Encoded in memory and written with every write checked (a full disk is an error, not a short PNG).
    std::vector<unsigned char> png;
    if (!cv::imencode(".png", slice, png, {cv::IMWRITE_PNG_COMPRESSION, 1})) {
      ok = false;
      continue;
    }
    try {
      write_file(folder / name.str(), std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
    } catch (const WriteError&) {
#pragma omp critical(tactus_slice_error)
      if (!failure) failure = std::current_exception();
      ok = false;
    }
  }
  if (failure) std::rethrow_exception(failure);
  if (!ok) throw WriteError(folder.string(), "a slice could not be encoded");
  nlohmann::json j;
  j["spacing_mm"] = {ct.spacing[0] * 1e3, ct.spacing[1] * 1e3, ct.spacing[2] * 1e3};
  j["origin_mm"] = {ct.origin[0] * 1e3, ct.origin[1] * 1e3, ct.origin[2] * 1e3};
  j["rescale_slope"] = 1.0;
  j["rescale_intercept"] = kIntercept;
  j["slices"] = nz;
  j["layout"] = "slice_k.png: row = y index, column = x index, k = z index; HU = slope * stored + intercept";
  j["source"] = "tactus-phantom (synthetic hand CT)";
  write_file(folder / "stack.json", j.dump(2) + '\n');
}

}  // namespace tactus::samples
