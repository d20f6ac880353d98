#include "tactus/mesher/thickness.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"

namespace tactus::mesher {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// One line of the transform: out[q] = min_p (h2 (q - p)^2 + f[p]), the lower envelope of the
// parabolas rooted at the finite f[p] (Felzenszwalb and Huttenlocher 2012, "Distance transforms
// of sampled functions"). v, z: scratch of n and n + 1.
void envelope_line(const double* f, double* out, int n, double h2, std::vector<int>& v, std::vector<double>& z) {
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (f[q] == kInf) continue;
    if (k < 0) {
      k = 0, v[0] = q, z[0] = -kInf, z[1] = kInf;
      continue;
    }
    double s = 0;
    for (;;) {  // z[0] is -inf, so k never drops below 0
      const int p = v[static_cast<std::size_t>(k)];
      s = ((f[q] + h2 * q * q) - (f[p] + h2 * p * p)) / (2 * h2 * (q - p));
      if (s > z[static_cast<std::size_t>(k)]) break;
      --k;
    }
    ++k;
    v[static_cast<std::size_t>(k)] = q, z[static_cast<std::size_t>(k)] = s, z[static_cast<std::size_t>(k) + 1] = kInf;
  }
  if (k < 0) {
    std::fill(out, out + n, kInf);
    return;
  }
  int j = 0;
  for (int q = 0; q < n; ++q) {
    while (z[static_cast<std::size_t>(j) + 1] < q) ++j;
    const int p = v[static_cast<std::size_t>(j)];
    out[q] = h2 * (q - p) * (q - p) + f[p];
  }
}

struct Box {
  std::array<int, 3> lo{0, 0, 0}, hi{-1, -1, -1};  // inclusive
  std::array<int, 3> dims() const { return {hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1}; }
};

// Each non-zero label's bounding box grown by one voxel (within the volume).
std::map<int, Box> label_boxes(const Volume<std::uint8_t>& labels) {
  std::map<int, Box> box;
  for (int k = 0; k < labels.dims[2]; ++k)
    for (int j = 0; j < labels.dims[1]; ++j)
      for (int i = 0; i < labels.dims[0]; ++i)
        if (const int l = labels.at(i, j, k)) {
          auto [it, fresh] = box.try_emplace(l);
          const int x[3] = {i, j, k};
          for (std::size_t a = 0; a < 3; ++a) {
            it->second.lo[a] = fresh ? x[a] : std::min(it->second.lo[a], x[a]);
            it->second.hi[a] = fresh ? x[a] : std::max(it->second.hi[a], x[a]);
          }
        }
  for (auto& [l, b] : box)
    for (std::size_t a = 0; a < 3; ++a) b.lo[a] = std::max(0, b.lo[a] - 1), b.hi[a] = std::min(labels.dims[a] - 1, b.hi[a] + 1);
  return box;
}

// Within `b`: 1 where the label is `l`, and the squared distance from each voxel to the nearest
// voxel of l's boundary (a face neighbour of another label, or the volume's edge).
struct LabelField {
  std::array<int, 3> d{};
  std::vector<std::uint8_t> inside;
  std::vector<double> d2;
  std::size_t at(int i, int j, int k) const {
    return static_cast<std::size_t>(i) + static_cast<std::size_t>(d[0]) * (static_cast<std::size_t>(j) + static_cast<std::size_t>(d[1]) * k);
  }
};

LabelField boundary_distance(const Volume<std::uint8_t>& labels, int l, const Box& b) {
  LabelField f;
  f.d = b.dims();
  const std::size_t n = static_cast<std::size_t>(f.d[0]) * f.d[1] * f.d[2];
  f.inside.assign(n, 0);
  std::vector<std::uint8_t> site(n, 0);
  for (int k = 0; k < f.d[2]; ++k)
    for (int j = 0; j < f.d[1]; ++j)
      for (int i = 0; i < f.d[0]; ++i) {
        const int x[3] = {b.lo[0] + i, b.lo[1] + j, b.lo[2] + k};
        if (labels.at(x[0], x[1], x[2]) != l) continue;
        f.inside[f.at(i, j, k)] = 1;
        bool edge = false;
        for (int a = 0; a < 3 && !edge; ++a)
          for (int s = -1; s <= 1 && !edge; s += 2) {
            int y[3] = {x[0], x[1], x[2]};
            y[a] += s;
            edge = y[a] < 0 || y[a] >= labels.dims[static_cast<std::size_t>(a)] || labels.at(y[0], y[1], y[2]) != l;
          }
        site[f.at(i, j, k)] = edge;
      }
  f.d2 = squared_distance_to_sites(site, f.d, labels.spacing);
  return f;
}

double max_spacing(const Volume<std::uint8_t>& labels) { return std::max({labels.spacing[0], labels.spacing[1], labels.spacing[2]}); }
double min_spacing(const Volume<std::uint8_t>& labels) { return std::min({labels.spacing[0], labels.spacing[1], labels.spacing[2]}); }

}  // namespace

std::vector<double> squared_distance_to_sites(const std::vector<std::uint8_t>& site, const std::array<int, 3>& d, const std::array<double, 3>& h) {
  const std::size_t n = static_cast<std::size_t>(d[0]) * d[1] * d[2];
  std::vector<double> g(n);
  for (std::size_t i = 0; i < n; ++i) g[i] = site[i] ? 0.0 : kInf;
  const int longest = std::max({d[0], d[1], d[2]});
  std::vector<int> v(static_cast<std::size_t>(longest));
  std::vector<double> z(static_cast<std::size_t>(longest) + 1), in(static_cast<std::size_t>(longest)), out(static_cast<std::size_t>(longest));
  const std::size_t stride[3] = {1, static_cast<std::size_t>(d[0]), static_cast<std::size_t>(d[0]) * d[1]};
  for (int a = 0; a < 3; ++a) {  // one pass per axis over every line along it
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    const double h2 = h[static_cast<std::size_t>(a)] * h[static_cast<std::size_t>(a)];
    for (int u = 0; u < d[static_cast<std::size_t>(c)]; ++u)
      for (int w = 0; w < d[static_cast<std::size_t>(b)]; ++w) {
        const std::size_t start = static_cast<std::size_t>(u) * stride[c] + static_cast<std::size_t>(w) * stride[b];
        const int m = d[static_cast<std::size_t>(a)];
        for (int q = 0; q < m; ++q) in[static_cast<std::size_t>(q)] = g[start + static_cast<std::size_t>(q) * stride[a]];
        envelope_line(in.data(), out.data(), m, h2, v, z);
        for (int q = 0; q < m; ++q) g[start + static_cast<std::size_t>(q) * stride[a]] = out[static_cast<std::size_t>(q)];
      }
  }
  return g;
}

std::map<int, LabelThickness> label_thickness(const Volume<std::uint8_t>& labels) {
  std::map<int, LabelThickness> out;
  for (const auto& [l, b] : label_boxes(labels)) {
    const LabelField f = boundary_distance(labels, l, b);
    LabelThickness& t = out[l];
    double deepest = -1;
    for (int k = 0; k < f.d[2]; ++k)
      for (int j = 0; j < f.d[1]; ++j)
        for (int i = 0; i < f.d[0]; ++i) {
          const std::size_t x = f.at(i, j, k);
          if (!f.inside[x]) continue;
          ++t.voxels;
          if (f.d2[x] > deepest) {
            deepest = f.d2[x];
            t.thickest_at = labels.voxel_world(labels.index(b.lo[0] + i, b.lo[1] + j, b.lo[2] + k));
          }
        }
    t.thickness_m = 2 * std::sqrt(std::max(0.0, deepest)) + min_spacing(labels);
  }
  return out;
}

namespace {

// The voxels of label l (in its box) where no ball of radius rho fits: l less its opening.
std::vector<std::size_t> thin_voxels(const Volume<std::uint8_t>& labels, int l, const Box& b, double rho) {
  const LabelField f = boundary_distance(labels, l, b);
  std::vector<std::uint8_t> core(f.inside.size(), 0);
  const double tol = 1e-9 * rho * rho;
  for (std::size_t x = 0; x < core.size(); ++x) core[x] = f.inside[x] && f.d2[x] >= rho * rho - tol;
  const std::vector<double> to_core = squared_distance_to_sites(core, f.d, labels.spacing);
  // A voxel is in the opening when a ball's centre lies within rho plus 3/4 voxel of its centre: the
  // ball then covers part of it. Without the 3/4 voxel the opening would strip a box's edges and
  // corners (sqrt 2 and sqrt 3 voxels from its core) as if they were thin.
  const double reach = rho + 0.75 * max_spacing(labels);
  std::vector<std::size_t> thin;
  for (int k = 0; k < f.d[2]; ++k)
    for (int j = 0; j < f.d[1]; ++j)
      for (int i = 0; i < f.d[0]; ++i) {
        const std::size_t x = f.at(i, j, k);
        if (f.inside[x] && !(to_core[x] <= reach * reach)) thin.push_back(labels.index(b.lo[0] + i, b.lo[1] + j, b.lo[2] + k));
      }
  return thin;
}

}  // namespace

std::vector<ThinPart> absorb_thin_parts(Volume<std::uint8_t>& labels, double min_thickness_m) {
  std::vector<ThinPart> parts;
  const double rho = 0.5 * (min_thickness_m - min_spacing(labels));  // thickness 2 d + h >= T
  if (!(rho > 0)) return parts;
  const std::size_t nx = static_cast<std::size_t>(labels.dims[0]), ny = static_cast<std::size_t>(labels.dims[1]);
  for (const auto& [l, b] : label_boxes(labels)) {
    std::vector<std::size_t> pending = thin_voxels(labels, l, b, rho);
    if (pending.empty()) continue;
    ThinPart part;
    part.label = l;
    part.at = labels.voxel_world(pending.front());
    // Sweeps from the outside in: each pending voxel takes the label (not l) most of its settled
    // face neighbours have, a non-zero one before the background; decided from the sweep's start.
    std::vector<std::uint8_t> is_pending(labels.size(), 0);
    for (std::size_t x : pending) is_pending[x] = 1;
    for (bool changed = true; changed && !pending.empty();) {
      changed = false;
      std::vector<std::pair<std::size_t, int>> moves;
      std::vector<std::size_t> still;
      for (std::size_t x : pending) {
        const int i = static_cast<int>(x % nx), j = static_cast<int>(x / nx % ny), k = static_cast<int>(x / (nx * ny));
        std::map<int, int> votes;
        for (int a = 0; a < 3; ++a)
          for (int s = -1; s <= 1; s += 2) {
            int y[3] = {i, j, k};
            y[a] += s;
            if (y[a] < 0 || y[a] >= labels.dims[static_cast<std::size_t>(a)]) continue;
            const std::size_t yi = labels.index(y[0], y[1], y[2]);
            if (!is_pending[yi] && labels.data[yi] != l) ++votes[labels.data[yi]];
          }
        int best = -1, best_votes = 0;
        for (const auto& [label, n] : votes)
          if ((label != 0 && (best <= 0 || n > best_votes)) || (best < 0 && label == 0)) best = label, best_votes = n;
        if (best < 0)
          still.push_back(x);
        else
          moves.emplace_back(x, best);
      }
      for (const auto& [x, to] : moves) {
        labels.data[x] = static_cast<std::uint8_t>(to), is_pending[x] = 0;
        ++part.into[to], ++part.voxels;
        changed = true;
      }
      pending.swap(still);
    }
    // What is left touches only l's own thick part (a root of a fin): it stays l.
    if (part.voxels) parts.push_back(part);
  }
  return parts;
}

nlohmann::json fit_thin_labels(Volume<std::uint8_t>& labels, const LabelTable& table, ImageMeshParams& p, double min_thickness_mm,
                               const std::string& file) {
  const auto name = [&](int id) { return label_name(table, id); };
  nlohmann::json absorbed = nlohmann::json::array();
  for (const auto& part : absorb_thin_parts(labels, min_thickness_mm * 1e-3)) {
    nlohmann::json into = nlohmann::json::object();
    for (const auto& [to, n] : part.into) into[name(to)] = n;
    const double moved = static_cast<double>(part.voxels) * labels.voxel_volume();
    std::ostringstream m;
    m << "mesher: " << part.voxels << " voxel(s) (" << moved * 1e9 << " mm^3) of " << name(part.label) << " thinner than " << min_thickness_mm
      << " mm (--min-thickness-mm) given to their neighbours " << into.dump() << ", e.g. at (" << part.at[0] << ", " << part.at[1] << ", "
      << part.at[2] << ") m";
    log::warn(m.str());
    absorbed.push_back(
        {{"label", part.label}, {"name", name(part.label)}, {"voxels", part.voxels}, {"volume_moved_m3", moved}, {"into", into}, {"at_m", part.at}});
  }
  const double voxel_mm = 1e3 * min_spacing(labels);
  nlohmann::json per_label = nlohmann::json::array();
  std::map<int, double> fitted;
  std::ostringstream thin;
  const auto thickness = label_thickness(labels);
  for (const auto& [id, t] : thickness) {
    const double cell = id == contracts::kSoftTissueLabel ? p.cell_size_mm : p.bone_cell_size_mm;
    const double t_mm = t.thickness_m * 1e3;
    nlohmann::json entry = {
        {"label", id}, {"name", name(id)}, {"thickness_m", t.thickness_m}, {"cell_size_m", cell * 1e-3}, {"thickest_at_m", t.thickest_at}};
    if (t_mm < cell) {
      fitted[id] = std::max(t_mm / 3, voxel_mm);
      entry["fitted_cell_size_m"] = fitted[id] * 1e-3;
      thin << (fitted.size() > 1 ? ", " : "") << "'" << name(id) << "' " << t_mm << " mm (cells " << cell << " mm)";
    }
    per_label.push_back(entry);
  }
  if (!thickness.empty() && fitted.size() == thickness.size())
    throw InputError(file, "/labels", "at least one label thicker than its cells (a smaller --cell-size / --bone-cell-size)",
                     "every label thinner than one element: " + thin.str());
  if (!fitted.empty())
    log::warn("mesher: label(s) thinner than their cells, meshed with a third of their thickness (at least a voxel): " + thin.str());
  p.label_cell_size_mm = fitted;
  return {{"min_thickness_m", min_thickness_mm * 1e-3}, {"absorbed", absorbed}, {"labels", per_label}};
}

}  // namespace tactus::mesher
