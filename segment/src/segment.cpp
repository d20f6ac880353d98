#include "tactus/segment/segment.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <numeric>
#include <sstream>

#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/volume_filters.hpp"

namespace tactus::segment {

double otsu_threshold(const std::vector<float>& values, const std::vector<std::uint8_t>* mask, double lo, double hi) {
  constexpr int kBins = 256;
  std::vector<double> hist(kBins, 0.0);
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (mask && !(*mask)[i]) continue;
    const double t = (values[i] - lo) / (hi - lo);
    hist[static_cast<std::size_t>(std::clamp(static_cast<int>(t * kBins), 0, kBins - 1))] += 1;
  }
  const double total = std::accumulate(hist.begin(), hist.end(), 0.0);
  double sum_all = 0;
  for (int b = 0; b < kBins; ++b) sum_all += b * hist[static_cast<std::size_t>(b)];
  double w0 = 0, sum0 = 0, best = -1;
  int best_bin = kBins / 2;
  for (int b = 0; b < kBins - 1; ++b) {
    w0 += hist[static_cast<std::size_t>(b)];
    sum0 += b * hist[static_cast<std::size_t>(b)];
    const double w1 = total - w0;
    if (w0 <= 0 || w1 <= 0) continue;
    const double m0 = sum0 / w0, m1 = (sum_all - sum0) / w1;
    const double between = w0 * w1 * (m0 - m1) * (m0 - m1);
    if (between > best) best = between, best_bin = b;
  }
  return lo + (hi - lo) * (best_bin + 1.0) / kBins;
}

namespace {

Volume<std::uint8_t> mask_like(const Volume<float>& v) { return v.like<std::uint8_t>(0); }

// 6-neighbour erosion repeated `n` times.
Volume<std::uint8_t> erode(const Volume<std::uint8_t>& m, int n) {
  Volume<std::uint8_t> cur = m;
  for (int it = 0; it < n; ++it) {
    Volume<std::uint8_t> next = cur;
    const auto& d = cur.dims;
#pragma omp parallel for schedule(static)
    for (int z = 0; z < d[2]; ++z)
      for (int y = 0; y < d[1]; ++y)
        for (int x = 0; x < d[0]; ++x) {
          if (!cur.at(x, y, z)) continue;
          const bool keep = x > 0 && y > 0 && z > 0 && x < d[0] - 1 && y < d[1] - 1 && z < d[2] - 1 && cur.at(x - 1, y, z) && cur.at(x + 1, y, z) &&
                            cur.at(x, y - 1, z) && cur.at(x, y + 1, z) && cur.at(x, y, z - 1) && cur.at(x, y, z + 1);
          if (!keep) next.at(x, y, z) = 0;
        }
    cur = std::move(next);
  }
  return cur;
}

// 2-D hole filling in every plane across each axis (4-connected background reached from the
// plane's border).
void fill_slice_holes(Volume<std::uint8_t>& m) {
  // Planes normal to each axis in turn: a tubular bone (a phalanx lying in the slice plane, cut
  // by thick slices) has its marrow enclosed only in the planes across it. Only the mask's
  // bounding box is searched (everything outside it is background, connected to the outside), and
  // each plane is copied into a contiguous buffer first (planes across x and y are strided).
  std::array<int, 3> lo{m.dims[0], m.dims[1], m.dims[2]}, hi{-1, -1, -1};
  for (int z = 0; z < m.dims[2]; ++z)
    for (int y = 0; y < m.dims[1]; ++y)
      for (int x = 0; x < m.dims[0]; ++x)
        if (m.at(x, y, z))
          lo = {std::min(lo[0], x), std::min(lo[1], y), std::min(lo[2], z)}, hi = {std::max(hi[0], x), std::max(hi[1], y), std::max(hi[2], z)};
  if (hi[0] < 0) return;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const std::size_t ua = axis == 0 ? 1 : 0, va = axis == 2 ? 1 : 2;
    const int nu = hi[ua] - lo[ua] + 1, nv = hi[va] - lo[va] + 1;
    auto voxel = [&](int w, int u, int v) -> std::uint8_t& {
      std::array<int, 3> c{};
      c[axis] = w, c[ua] = u + lo[ua], c[va] = v + lo[va];
      return m.at(c[0], c[1], c[2]);
    };
#pragma omp parallel for schedule(dynamic)
    for (int w = lo[axis]; w <= hi[axis]; ++w) {
      const std::size_t n = static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv);
      std::vector<std::uint8_t> plane(n);  // 0 background, 1 mask, 2 background reached from the border
      for (int v = 0; v < nv; ++v)
        for (int u = 0; u < nu; ++u) plane[static_cast<std::size_t>(u) + static_cast<std::size_t>(nu) * static_cast<std::size_t>(v)] = voxel(w, u, v);
      std::vector<int> stack;
      auto push = [&](int u, int v) {
        const std::size_t i = static_cast<std::size_t>(u) + static_cast<std::size_t>(nu) * static_cast<std::size_t>(v);
        if (plane[i] == 0) plane[i] = 2, stack.push_back(static_cast<int>(i));
      };
      for (int u = 0; u < nu; ++u) push(u, 0), push(u, nv - 1);
      for (int v = 0; v < nv; ++v) push(0, v), push(nu - 1, v);
      while (!stack.empty()) {
        const int i = stack.back();
        stack.pop_back();
        const int u = i % nu, v = i / nu;
        if (u > 0) push(u - 1, v);
        if (u + 1 < nu) push(u + 1, v);
        if (v > 0) push(u, v - 1);
        if (v + 1 < nv) push(u, v + 1);
      }
      for (int v = 0; v < nv; ++v)
        for (int u = 0; u < nu; ++u)
          if (plane[static_cast<std::size_t>(u) + static_cast<std::size_t>(nu) * static_cast<std::size_t>(v)] == 0) voxel(w, u, v) = 1;
    }
  }
}

}  // namespace

namespace {

// Body: threshold (given or Otsu), the largest 3-D component, holes filled.
Volume<std::uint8_t> find_body(const Volume<float>& hu, const SegmentParams& p, Segmentation& s) {
  s.body_threshold_source = p.body_threshold_hu ? "given" : "otsu";
  s.body_threshold_hu = p.body_threshold_hu ? *p.body_threshold_hu : otsu_threshold(hu.data, nullptr, -1100, 600);
  Volume<std::uint8_t> body = mask_like(hu);
  for (std::size_t i = 0; i < hu.size(); ++i) body.data[i] = hu.data[i] > s.body_threshold_hu;
  {
    std::vector<std::size_t> sizes;
    const auto comp = connected_components(body, sizes);
    if (sizes.size() <= 1) {
      std::ostringstream o;
      o << "a body brighter than the body threshold " << s.body_threshold_hu << " HU (" << s.body_threshold_source
        << "); set it with --body-threshold";
      throw InputError("CT", "body", o.str(), "no voxel above it");
    }
    const auto largest = static_cast<std::int32_t>(std::max_element(sizes.begin() + 1, sizes.end()) - sizes.begin());
    for (std::size_t i = 0; i < body.size(); ++i) body.data[i] = comp[i] == largest;
  }
  fill_holes(body);
  return body;
}

// The bone mask inside the body, its marrow filled; `no_contrast` when the body has none.
Volume<std::uint8_t> find_bone(Volume<float>& hu, const Volume<std::uint8_t>& body, const SegmentParams& p, Segmentation& s, bool& no_contrast) {
  // Bone threshold: halfway between the soft-tissue level (the body's median: soft tissue is most
  // of a hand's volume) and the cortical level (the body's 99th percentile), which puts the bone
  // surface where the blurred edge crosses its midpoint. An Otsu threshold over the body (~400 HU
  // here) sits low on that edge and inflates every bone by ~0.7 sigma of the blur (bone Dice 0.90
  // instead of 0.98 on the phantom). The trabecular marrow below the midpoint is filled as holes.
  const std::vector<std::uint8_t>& in_body = body.data;
  std::vector<float> body_hu;
  body_hu.reserve(hu.size() / 4);
  for (std::size_t i = 0; i < hu.size(); ++i)
    if (in_body[i]) body_hu.push_back(hu.data[i]);
  auto percentile = [&](double q) {
    const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(body_hu.size() - 1));
    std::nth_element(body_hu.begin(), body_hu.begin() + k, body_hu.end());
    return static_cast<double>(body_hu[static_cast<std::size_t>(k)]);
  };
  s.soft_tissue_hu = percentile(0.5);
  s.cortical_hu = percentile(0.99);
  s.bone_threshold_source = p.bone_threshold_hu ? "given" : "midpoint of soft tissue and cortical levels";
  s.bone_threshold_hu = p.bone_threshold_hu ? *p.bone_threshold_hu : 0.5 * (s.soft_tissue_hu + s.cortical_hu);
  no_contrast = !p.bone_threshold_hu && s.cortical_hu - s.soft_tissue_hu < 200.0;
  Volume<std::uint8_t> bone = mask_like(hu);
  if (!no_contrast)
    for (std::size_t i = 0; i < hu.size(); ++i) bone.data[i] = in_body[i] && hu.data[i] > s.bone_threshold_hu;
  // Marrow: holes of the bone mask in 3-D, and in each slice (where a thin cortex may leak in 3-D).
  fill_holes(bone);
  fill_slice_holes(bone);
  for (std::size_t i = 0; i < bone.size(); ++i) bone.data[i] = bone.data[i] && in_body[i];
  if (!p.bone_threshold_hu && !no_contrast) {
    // Refine on the outer bone edge: the |grad|^2-weighted mean HU over a band two voxels deep
    // inside the filled mask's surface is the midpoint of the tissue-cortex step as actually
    // blurred; the band is re-thresholded there and the marrow filled again.
    const Volume<std::uint8_t> inner = erode(bone, 2);
    const int nx = hu.dims[0], ny = hu.dims[1], nz = hu.dims[2];
    double wsum = 0, whu = 0;
    for (int z = 1; z < nz - 1; ++z)
      for (int y = 1; y < ny - 1; ++y)
        for (int x = 1; x < nx - 1; ++x) {
          const std::size_t i = hu.index(x, y, z);
          const bool band = bone.data[i] && !inner.data[i];
          const bool outside_ring = !bone.data[i] && in_body[i] &&
                                    (bone.at(x - 1, y, z) || bone.at(x + 1, y, z) || bone.at(x, y - 1, z) || bone.at(x, y + 1, z) ||
                                     bone.at(x, y, z - 1) || bone.at(x, y, z + 1));
          if (!band && !outside_ring) continue;
          const double gx = hu.at(x + 1, y, z) - hu.at(x - 1, y, z), gy = hu.at(x, y + 1, z) - hu.at(x, y - 1, z),
                       gz = hu.at(x, y, z + 1) - hu.at(x, y, z - 1);
          const double w = gx * gx + gy * gy + gz * gz;
          wsum += w, whu += w * hu.data[i];
        }
    if (wsum > 0) {
      s.bone_threshold_hu = whu / wsum;
      s.bone_threshold_source = "gradient-weighted midpoint of the outer bone edge";
      for (std::size_t i = 0; i < bone.size(); ++i)
        if (bone.data[i] && !inner.data[i] && hu.data[i] <= s.bone_threshold_hu) bone.data[i] = 0;
      fill_holes(bone);
      fill_slice_holes(bone);
      for (std::size_t i = 0; i < bone.size(); ++i) bone.data[i] = bone.data[i] && in_body[i];
    }
  }

  return bone;
}

// Joins the grown pieces of the split whose shared voxel faces reach p.split_neck_ratio times the
// smaller piece's V^(2/3) (its cross-section): the erosion cut through a bone, not through a joint;
// and touching pieces of which the erosion left less than p.split_min_core_fraction as a core.
// Relabels the pieces 1..kept.
void merge_broad_contacts(const std::array<int, 3>& d, std::vector<std::int32_t>& comp, std::int32_t& kept,
                          const std::vector<std::size_t>& core_voxels, const SegmentParams& p) {
  const double ratio = p.split_neck_ratio;
  if (kept < 2 || ratio <= 0) return;
  std::vector<std::size_t> volume(static_cast<std::size_t>(kept) + 1, 0);
  for (auto c : comp) ++volume[static_cast<std::size_t>(c)];
  std::map<std::pair<std::int32_t, std::int32_t>, std::size_t> contact;
  const std::size_t nx = static_cast<std::size_t>(d[0]), nxy = nx * static_cast<std::size_t>(d[1]);
  for (std::size_t v = 0; v < comp.size(); ++v) {
    const std::int32_t a = comp[v];
    if (!a) continue;
    const std::size_t x = v % nx, y = (v / nx) % static_cast<std::size_t>(d[1]), z = v / nxy;
    const std::size_t nb[3] = {x + 1 < nx ? v + 1 : v, y + 1 < static_cast<std::size_t>(d[1]) ? v + nx : v,
                               z + 1 < static_cast<std::size_t>(d[2]) ? v + nxy : v};
    for (std::size_t w : nb)
      if (const std::int32_t b = comp[w]; b && b != a) ++contact[{std::min(a, b), std::max(a, b)}];
  }
  std::vector<std::int32_t> root(static_cast<std::size_t>(kept) + 1);
  for (std::size_t c = 0; c < root.size(); ++c) root[c] = static_cast<std::int32_t>(c);
  auto find = [&](std::int32_t c) {
    while (root[static_cast<std::size_t>(c)] != c)
      c = root[static_cast<std::size_t>(c)] = root[static_cast<std::size_t>(root[static_cast<std::size_t>(c)])];
    return c;
  };
  for (const auto& [pair, faces] : contact) {
    const double section = std::pow(
        static_cast<double>(std::min(volume[static_cast<std::size_t>(pair.first)], volume[static_cast<std::size_t>(pair.second)])), 2.0 / 3.0);
    // The erosion resolves a joint only where it leaves most of each piece: a piece whose core is a
    // small part of it is a few voxels across, and its cut falls wherever it is thinnest.
    const auto core_of = [&](std::int32_t c) {
      return static_cast<double>(core_voxels[static_cast<std::size_t>(c)]) / static_cast<double>(volume[static_cast<std::size_t>(c)]);
    };
    const double core_fraction = std::min(core_of(pair.first), core_of(pair.second));
    log::debug() << "split: pieces " << pair.first << " and " << pair.second << " touch across " << static_cast<double>(faces) / section
                 << " of the smaller's section; smaller core fraction " << core_fraction;
    if (static_cast<double>(faces) >= ratio * section || core_fraction < p.split_min_core_fraction)
      root[static_cast<std::size_t>(find(pair.second))] = find(pair.first);
  }
  std::vector<std::int32_t> id(root.size(), 0);
  std::int32_t n = 0;
  for (std::int32_t c = 1; c <= kept; ++c)
    if (find(c) == c) id[static_cast<std::size_t>(c)] = ++n;
  for (auto& c : comp)
    if (c) c = id[static_cast<std::size_t>(find(c))];
  kept = n;
}

// Split at joints: components of the eroded mask, cores too small dropped, labels grown back
// into the mask (each voxel joins the nearest core), pieces touching across their whole section
// joined again. Returns the core id of every voxel (0: none) and the number of cores kept.
std::vector<std::int32_t> split_bones(const Volume<float>& hu, const Volume<std::uint8_t>& bone, const SegmentParams& p, std::size_t min_voxels,
                                      std::int32_t& kept) {
  const Volume<std::uint8_t> core = erode(bone, p.split_erosion_voxels);
  std::vector<std::size_t> sizes;
  std::vector<std::int32_t> comp = connected_components(core, sizes);
  // Keep cores whose size suggests a bone (the eroded core of the smallest bone is well above
  // min_voxels / 4); relabel kept cores 1..n.
  std::vector<std::int32_t> keep(sizes.size(), 0);
  kept = 0;
  std::vector<std::size_t> core_voxels{0};
  for (std::size_t c = 1; c < sizes.size(); ++c)
    if (sizes[c] >= std::max<std::size_t>(1, min_voxels / 4)) keep[c] = ++kept, core_voxels.push_back(sizes[c]);
  for (auto& c : comp) c = keep[static_cast<std::size_t>(c)];
  // Grow back into the bone mask, breadth first (each voxel joins the nearest core).
  std::vector<std::size_t> frontier, next;
  for (std::size_t i = 0; i < comp.size(); ++i)
    if (comp[i]) frontier.push_back(i);
  const std::size_t nx = static_cast<std::size_t>(hu.dims[0]), nxy = nx * static_cast<std::size_t>(hu.dims[1]);
  while (!frontier.empty()) {
    next.clear();
    for (std::size_t v : frontier) {
      const std::size_t x = v % nx, y = (v / nx) % static_cast<std::size_t>(hu.dims[1]), z = v / nxy;
      const std::size_t nb[6] = {x > 0 ? v - 1 : v,   x + 1 < nx ? v + 1 : v,
                                 y > 0 ? v - nx : v,  y + 1 < static_cast<std::size_t>(hu.dims[1]) ? v + nx : v,
                                 z > 0 ? v - nxy : v, z + 1 < static_cast<std::size_t>(hu.dims[2]) ? v + nxy : v};
      for (std::size_t w : nb)
        if (bone.data[w] && !comp[w]) comp[w] = comp[v], next.push_back(w);
    }
    frontier.swap(next);
  }
  merge_broad_contacts(hu.dims, comp, kept, core_voxels, p);
  return comp;
}

// Closes each bone by a box of half-width marrow_closing_mm (per axis in voxels, at least one
// where the spacing allows it): the marrow of a bone whose cortex partial volume opened (thick
// slices across a thin shell) is filled. Voxels are added only inside the body, where no bone is,
// and not next to another bone (so a joint gap of one voxel stays).
void close_bone_marrow(const Volume<std::uint8_t>& body, std::vector<std::int32_t>& comp, std::int32_t kept, double radius_mm) {
  if (radius_mm <= 0 || kept < 1) return;
  const std::array<int, 3> d = body.dims;
  std::array<int, 3> r{};
  for (std::size_t a = 0; a < 3; ++a) r[a] = static_cast<int>(std::floor(radius_mm * 1e-3 / body.spacing[a] + 0.5));
  if (r[0] + r[1] + r[2] == 0) return;
  const auto idx = [&](int x, int y, int z) {
    return static_cast<std::size_t>(x) +
           static_cast<std::size_t>(d[0]) * (static_cast<std::size_t>(y) + static_cast<std::size_t>(d[1]) * static_cast<std::size_t>(z));
  };
  std::vector<std::array<int, 6>> box(static_cast<std::size_t>(kept) + 1, {d[0], d[1], d[2], -1, -1, -1});
  for (int z = 0; z < d[2]; ++z)
    for (int y = 0; y < d[1]; ++y)
      for (int x = 0; x < d[0]; ++x)
        if (const std::int32_t c = comp[idx(x, y, z)]) {
          auto& b = box[static_cast<std::size_t>(c)];
          b = {std::min(b[0], x), std::min(b[1], y), std::min(b[2], z), std::max(b[3], x), std::max(b[4], y), std::max(b[5], z)};
        }
  std::vector<std::pair<std::size_t, std::int32_t>> added;
#pragma omp parallel for schedule(dynamic)
  for (std::int32_t c = 1; c <= kept; ++c) {
    const auto& b = box[static_cast<std::size_t>(c)];
    if (b[3] < 0) continue;
    // The bone's box grown by twice the radius (the dilation must not be cut by the box's edge).
    std::array<int, 3> lo{}, n{};
    for (std::size_t a = 0; a < 3; ++a) {
      lo[a] = b[a] - 2 * r[a];
      n[a] = b[a + 3] + 2 * r[a] - lo[a] + 1;
    }
    const auto local = [&](int x, int y, int z) {
      return static_cast<std::size_t>(x) +
             static_cast<std::size_t>(n[0]) * (static_cast<std::size_t>(y) + static_cast<std::size_t>(n[1]) * static_cast<std::size_t>(z));
    };
    std::vector<std::uint8_t> m(static_cast<std::size_t>(n[0]) * static_cast<std::size_t>(n[1]) * static_cast<std::size_t>(n[2]), 0), tmp;
    for (int z = 0; z < n[2]; ++z)
      for (int y = 0; y < n[1]; ++y)
        for (int x = 0; x < n[0]; ++x) {
          const int gx = x + lo[0], gy = y + lo[1], gz = z + lo[2];
          if (gx >= 0 && gy >= 0 && gz >= 0 && gx < d[0] && gy < d[1] && gz < d[2]) m[local(x, y, z)] = comp[idx(gx, gy, gz)] == c;
        }
    // Separable box filter along each axis: max (dilate) then min (erode).
    const auto filter = [&](bool dilate) {
      for (std::size_t a = 0; a < 3; ++a) {
        if (r[a] == 0) continue;
        tmp = m;
        for (int z = 0; z < n[2]; ++z)
          for (int y = 0; y < n[1]; ++y)
            for (int x = 0; x < n[0]; ++x) {
              std::array<int, 3> p{x, y, z};
              std::uint8_t v = dilate ? 0 : 1;
              for (int k = -r[a]; k <= r[a]; ++k) {
                std::array<int, 3> q = p;
                q[a] += k;
                const std::uint8_t w = q[a] >= 0 && q[a] < n[a] ? tmp[local(q[0], q[1], q[2])] : 0;
                v = dilate ? std::max(v, w) : std::min(v, w);
              }
              m[local(x, y, z)] = v;
            }
      }
    };
    filter(true);
    filter(false);
    std::vector<std::pair<std::size_t, std::int32_t>> mine;
    for (int z = 0; z < n[2]; ++z)
      for (int y = 0; y < n[1]; ++y)
        for (int x = 0; x < n[0]; ++x) {
          const int gx = x + lo[0], gy = y + lo[1], gz = z + lo[2];
          if (!m[local(x, y, z)] || gx < 0 || gy < 0 || gz < 0 || gx >= d[0] || gy >= d[1] || gz >= d[2]) continue;
          const std::size_t i = idx(gx, gy, gz);
          if (comp[i] || !body.data[i]) continue;
          bool near_other = false;
          for (int k = 0; k < 6 && !near_other; ++k) {
            std::array<int, 3> q{gx, gy, gz};
            q[static_cast<std::size_t>(k / 2)] += k % 2 ? 1 : -1;
            if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= d[0] || q[1] >= d[1] || q[2] >= d[2]) continue;
            const std::int32_t o = comp[idx(q[0], q[1], q[2])];
            near_other = o && o != c;
          }
          if (!near_other) mine.push_back({i, c});
        }
#pragma omp critical
    added.insert(added.end(), mine.begin(), mine.end());
  }
  // Two bones may both claim a voxel between them: it stays soft tissue (a joint gap).
  std::sort(added.begin(), added.end());
  for (std::size_t k = 0; k < added.size(); ++k) {
    const bool shared = (k > 0 && added[k - 1].first == added[k].first) || (k + 1 < added.size() && added[k + 1].first == added[k].first);
    if (!shared) comp[added[k].first] = added[k].second;
  }
}

// Per-bone statistics, specks back to soft tissue, deterministic ids, and the label volume.
void label_bones(const Volume<float>& hu, const Volume<std::uint8_t>& body, const std::vector<std::int32_t>& comp, std::int32_t kept,
                 std::size_t min_voxels, bool no_contrast, const SegmentParams& p, Segmentation& s) {
  const std::vector<std::uint8_t>& in_body = body.data;
  const std::size_t nx = static_cast<std::size_t>(hu.dims[0]), nxy = nx * static_cast<std::size_t>(hu.dims[1]);
  // Per-bone statistics; bones below the minimum volume are specks (back to soft tissue).
  std::vector<BoneInfo> info(static_cast<std::size_t>(kept) + 1);
  for (std::size_t i = 0; i < comp.size(); ++i) {
    if (!comp[i]) continue;
    BoneInfo& b = info[static_cast<std::size_t>(comp[i])];
    ++b.voxels;
    const double pos[3] = {static_cast<double>(i % nx), static_cast<double>((i / nx) % static_cast<std::size_t>(hu.dims[1])),
                           static_cast<double>(i / nxy)};
    for (int a = 0; a < 3; ++a) b.centroid_m[a] += pos[a];
  }
  std::vector<std::int32_t> order;
  for (std::int32_t c = 1; c <= kept; ++c) {
    BoneInfo& b = info[static_cast<std::size_t>(c)];
    if (b.voxels < min_voxels) {
      ++s.specks_removed;
      continue;
    }
    for (int a = 0; a < 3; ++a) b.centroid_m[a] = hu.origin[a] + hu.spacing[a] * b.centroid_m[a] / static_cast<double>(b.voxels);
    b.centroid_m = hu.to_world(b.centroid_m);
    b.volume_m3 = static_cast<double>(b.voxels) * hu.voxel_volume();
    order.push_back(c);
  }
  if (order.empty()) {
    std::ostringstream o;
    o << "bone inside the body: tried body threshold " << s.body_threshold_hu << " HU (" << s.body_threshold_source << ") and bone threshold "
      << s.bone_threshold_hu << " HU (" << s.bone_threshold_source << "; soft tissue at " << s.soft_tissue_hu << " HU, brightest 1 % of the body at "
      << s.cortical_hu << " HU" << (no_contrast ? ", less than 200 HU of contrast" : "") << "), minimum bone volume " << p.min_bone_volume_mm3
      << " mm^3; set --bone-threshold (cortical bone is ~700-2000 HU) or --body-threshold";
    throw InputError("CT", "bones", o.str(), "no bone");
  }
  if (order.size() > 253) throw InputError("CT", "bones", "at most 253 bones (uint8 labels)", std::to_string(order.size()));
  // Deterministic ids: bones ordered along the slice axis, then across.
  std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
    const auto& A = info[static_cast<std::size_t>(a)].centroid_m;
    const auto& B = info[static_cast<std::size_t>(b)].centroid_m;
    return A[2] != B[2] ? A[2] < B[2] : A[0] < B[0];
  });
  std::vector<std::uint8_t> new_id(info.size(), static_cast<std::uint8_t>(contracts::kSoftTissueLabel));  // specks become soft tissue
  s.table[contracts::kBackgroundLabel] = "background";
  s.table[contracts::kSoftTissueLabel] = contracts::kSoftTissueName;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const int label = static_cast<int>(k) + contracts::kFirstBoneLabel;
    new_id[static_cast<std::size_t>(order[k])] = static_cast<std::uint8_t>(label);
    BoneInfo b = info[static_cast<std::size_t>(order[k])];
    b.label = label;
    s.bones.push_back(b);
    std::ostringstream name;
    name << "bone_" << std::setw(2) << std::setfill('0') << label;
    s.table[label] = name.str();
  }
  s.labels = mask_like(hu);
  for (std::size_t i = 0; i < comp.size(); ++i) {
    if (!in_body[i]) continue;
    s.labels.data[i] = comp[i] ? new_id[static_cast<std::size_t>(comp[i])] : static_cast<std::uint8_t>(contracts::kSoftTissueLabel);
    ++s.body_voxels;
    if (s.labels.data[i] >= contracts::kFirstBoneLabel) ++s.bone_voxels;
  }
}

}  // namespace

Segmentation segment_hand(Volume<float> hu, const SegmentParams& p) {
  Segmentation s;
  // Each step's wall time in the verbose log (the 136 M-voxel bench, bench/ct_bench.sh, reads them).
  auto last = std::chrono::steady_clock::now();
  std::ostringstream times;
  const auto lap = [&](const char* step) {
    const auto now = std::chrono::steady_clock::now();
    times << " " << step << " " << std::chrono::duration<double>(now - last).count() << " s;";
    last = now;
  };
  // The kernel (3 sigma each side) must fit the volume: a larger one costs minutes and blurs the
  // hand into the air (--denoise 1e6 ran for minutes on a tiny stack).
  const int largest = std::max({hu.dims[0], hu.dims[1], hu.dims[2]});
  if (3 * p.denoise_sigma_voxels > largest)
    throw InputError("command line", "--denoise",
                     "a sigma whose kernel (3 sigma) fits the volume's largest extent of " + std::to_string(largest) + " voxels (at most " +
                         std::to_string(largest / 3.0) + ")",
                     std::to_string(p.denoise_sigma_voxels));
  gaussian_blur(hu, p.denoise_sigma_voxels);
  lap("denoise");
  const Volume<std::uint8_t> body = find_body(hu, p, s);
  lap("body");
  bool no_contrast = false;
  const Volume<std::uint8_t> bone = find_bone(hu, body, p, s, no_contrast);
  lap("bone");
  const double voxel_mm3 = hu.voxel_volume() * 1e9;
  const std::size_t min_voxels = static_cast<std::size_t>(std::ceil(p.min_bone_volume_mm3 / voxel_mm3));
  std::int32_t kept = 0;
  std::vector<std::int32_t> comp = split_bones(hu, bone, p, min_voxels, kept);
  lap("split");
  close_bone_marrow(body, comp, kept, p.marrow_closing_mm);
  lap("marrow closing");
  label_bones(hu, body, comp, kept, min_voxels, no_contrast, p, s);
  lap("labels");
  log::verbose() << "segment: body threshold " << s.body_threshold_hu << " HU, bone threshold " << s.bone_threshold_hu << " HU, " << s.bones.size()
                 << " bones, " << s.specks_removed << " specks removed; times:" << times.str();
  return s;
}

}  // namespace tactus::segment
