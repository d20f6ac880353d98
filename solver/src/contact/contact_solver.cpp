// The integrator's view of contact: detection by each pair's master kind, then the bi-potential
// solve over the rows, as one velocity correction per step.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>

#include "bipotential.hpp"
#include "detection.hpp"
#include "tactus/core/error.hpp"
#include "tactus/solver/contact.hpp"
#include "tactus/solver/model.hpp"

namespace tactus::solver {

ContactSolver::ContactSolver(const Model& model)
    : model_(model), pairs_(model.contact_pairs), settings_(model.contact_settings), scratch_(pairs_.size()) {
  for (std::size_t p = 0; p < pairs_.size(); ++p) scratch_[p].skin = settings_.verlet_skin * pairs_[p].search_scale;
  x_.resize(3 * model.num_nodes);
  for (const auto& p : pairs_) last_reaction_.reaction.emplace_back(3 * p.slave_nodes.size(), 0.0);
  pair_reports_.resize(pairs_.size());
  step_pressure_.assign(model.num_nodes, 0.0);
  windowed_pressure_.assign(model.num_nodes, 0.0);
  is_pressed_.assign(model.num_nodes, 0);
  for (const ContactPair& p : pairs_) slave_union_.insert(slave_union_.end(), p.slave_nodes.begin(), p.slave_nodes.end());
  std::sort(slave_union_.begin(), slave_union_.end());
  slave_union_.erase(std::unique(slave_union_.begin(), slave_union_.end()), slave_union_.end());
  contact_nodes_ = slave_union_;
  for (const ContactPair& e : pairs_)  // an edge pass reports its load on the nodes of its entry's mortar slave surface
    if (e.edge_pass)
      for (const ContactPair& q : pairs_)
        if (q.entry == e.entry && !q.edge_pass) {
          if (edge_share_area_.empty()) edge_share_area_.assign(model.num_nodes, 0.0);
          for (std::size_t i = 0; i < q.slave_nodes.size(); ++i) edge_share_area_[static_cast<std::size_t>(q.slave_nodes[i])] = q.slave_area[i];
        }
  for (const ContactPair& p : pairs_) contact_nodes_.insert(contact_nodes_.end(), p.master->triangles().begin(), p.master->triangles().end());
  std::sort(contact_nodes_.begin(), contact_nodes_.end());
  contact_nodes_.erase(std::unique(contact_nodes_.begin(), contact_nodes_.end()), contact_nodes_.end());
}

ContactSolver::~ContactSolver() = default;

void ContactSolver::detect(const double* u, double search_factor, ContactRows& rows) {
  rows.clear();
  // Current positions of the nodes the masters read (slave nodes, master triangles' vertices) only,
  // and the farthest any of them moved since the last search: the pairs' searches add it to their
  // bounds on the moves since their builds (BuildSnapshot) and scan their nodes only when those
  // come near the reach.
  const std::size_t n = contact_nodes_.size();
  double farthest2 = 0;
#pragma omp parallel for num_threads(threads_) schedule(static) reduction(max : farthest2) if (n > 30000)
  for (std::size_t i = 0; i < n; ++i) {
    double d2 = 0;
    for (std::size_t d = 0; d < 3; ++d) {
      const std::size_t dof = 3 * static_cast<std::size_t>(contact_nodes_[i]) + d;
      const double x = model_.X[dof] + u[dof], dx = x - x_[dof];
      d2 += dx * dx;
      x_[dof] = x;
    }
    farthest2 = std::max(farthest2, d2);
  }
  const double moved = x_known_ ? std::sqrt(farthest2) : std::numeric_limits<double>::infinity();
  x_known_ = true;
  for (std::size_t pi = 0; pi < pairs_.size(); ++pi) {
    const ContactPair& p = pairs_[pi];
    scratch_[pi].moved = moved;
    p.master->detect(p, static_cast<std::int32_t>(pi), x_.data(), search_factor * p.search_scale, scratch_[pi], rows, threads_);
  }
}

void ContactSolver::detect_ahead(const double* u) {
  if (pairs_.empty()) return;
  detect(u, settings_.search_factor, ahead_rows_);
  ahead_ = true;
}

ContactSolver::SearchCounts ContactSolver::search_counts() const {
  SearchCounts c;
  for (const DetectionScratch& s : scratch_) c.builds += s.builds, c.searches += s.searches;
  return c;
}

void ContactSolver::check_initial_overlap(const double* u) const {
  ContactSolver probe(model_);
  probe.detect(u, std::max(settings_.search_factor, 2.0), probe.rows_);
  const ContactRows& rows = probe.rows_;
  std::size_t worst = rows.size();
  double worst_h = 0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const double tol = 1e-3 * std::max(pairs_[static_cast<std::size_t>(rows.pair[k])].search_scale, 1e-12);
    if (rows.gap[k] < -tol && rows.gap[k] < worst_h) worst = k, worst_h = rows.gap[k];
  }
  if (worst == rows.size()) return;
  const ContactPair& p = pairs_[static_cast<std::size_t>(rows.pair[worst])];
  std::size_t input_node = model_.input_node(static_cast<std::size_t>(rows.slave(worst)));
  const BodyRange& body = model_.bodies[model_.body_of_node(input_node)];
  input_node -= body.node_begin;
  std::ostringstream found, expected;
  found << "node " << input_node + 1 << " of body '" << body.name << "' is " << -worst_h * 1e3 << " mm inside the master surface";
  expected << "bodies apart or touching at t = 0 (overlap < " << 1e-3 * p.search_scale * 1e3 << " mm); move them apart with bodies.translate";
  throw InputError("scenario", p.name, expected.str(), found.str());
}

ContactStepReport ContactSolver::correct_velocities(const double* u, double* v, const double* v_old, const double* inv_mass,
                                                    double velocity_per_force, double dt, double dt_prev, RigidRows* rigid) {
  if (pairs_.empty()) return {};
  if (ahead_) {
    std::swap(rows_, ahead_rows_);
    ahead_ = false;
  } else {
    detect(u, settings_.search_factor, rows_);
  }
  ContactStepReport rep =
      solve_rows(rows_, v, last_reaction_,
                 {&pairs_, &settings_, v_old, inv_mass, velocity_per_force, dt, dt_prev, &pair_reports_, rigid, model_.X.data(), threads_});
  update_windows(rep, 0.5 * (dt + dt_prev));
  return rep;
}

constexpr double kNegligiblePressure = 1e-3;  // Pa

void ContactSolver::update_windows(ContactStepReport& rep, double dtbar) {
  for (std::int32_t s : step_nodes_) step_pressure_[static_cast<std::size_t>(s)] = 0;
  step_nodes_.clear();
  auto add_pressure = [&](std::size_t node, double p) {
    if (step_pressure_[node] == 0) step_nodes_.push_back(static_cast<std::int32_t>(node));
    step_pressure_[node] += p;
  };
  for (std::size_t k = 0; k < rows_.size(); ++k) {
    if (rows_.status[k] == ContactStatus::open) continue;
    const double* r = &rows_.reaction[3 * k];
    const double* n = &rows_.normal[3 * k];
    const double rn = r[0] * n[0] + r[1] * n[1] + r[2] * n[2];
    if (pairs_[static_cast<std::size_t>(rows_.pair[k])].edge_pass) {
      // The reaction on the master side, -w_a r_n at each of its nodes (sum of -w_a = 1), is the
      // slave surface's load there: its pressure over the node's tributary area.
      for (auto a = rows_.start[k] + 1; a < rows_.start[k + 1]; ++a) {
        const auto node = static_cast<std::size_t>(rows_.nodes[static_cast<std::size_t>(a)]);
        if (edge_share_area_[node] > 0) add_pressure(node, -rows_.weights[static_cast<std::size_t>(a)] * rn / edge_share_area_[node]);
      }
      continue;
    }
    add_pressure(static_cast<std::size_t>(rows_.slave(k)), rn / rows_.area[k]);
  }
  // The windows move at the pressed nodes only: a node outside them has p = 0 and no load, so stays 0.
  bool grown = false;
  for (std::int32_t s : step_nodes_)
    if (!is_pressed_[static_cast<std::size_t>(s)]) is_pressed_[static_cast<std::size_t>(s)] = 1, pressed_.push_back(s), grown = true;
  if (grown) std::sort(pressed_.begin(), pressed_.end());  // ascending, as the peak's ties were always taken
  const double w = pressure_window_ > 0 ? std::min(1.0, dtbar / pressure_window_) : 1.0;
  windowed_normal_force_ += w * (rep.normal_force - windowed_normal_force_);
  windowed_area_ += w * (rep.area - windowed_area_);
  rep.windowed_normal_force = windowed_normal_force_, rep.windowed_area = windowed_area_;
  rep.peak_step_pressure = rep.peak_pressure;
  rep.peak_pressure = 0;
  rep.peak_node = -1;
  std::size_t kept = 0;
  for (std::int32_t s : pressed_) {
    double& q = windowed_pressure_[static_cast<std::size_t>(s)];
    q += w * (step_pressure_[static_cast<std::size_t>(s)] - q);
    if (q > rep.peak_pressure) rep.peak_pressure = q, rep.peak_node = s;
    // An unloaded node's window decays geometrically and would take thousands of steps to
    // underflow to 0, showing as pressed (status far, pressure 1e-300) long after it let go.
    // Below kNegligiblePressure it is 0: eight orders below the softest contact this models.
    if (q < kNegligiblePressure && step_pressure_[static_cast<std::size_t>(s)] == 0) q = 0;
    if (q != 0)
      pressed_[kept++] = s;
    else
      is_pressed_[static_cast<std::size_t>(s)] = 0;
  }
  pressed_.resize(kept);
  // No load and no window left: the windowed force and area end with them (else they too would
  // decay for thousands of steps after the bodies part).
  if (pressed_.empty() && rep.normal_force == 0) windowed_normal_force_ = windowed_area_ = 0, rep.windowed_normal_force = rep.windowed_area = 0;
}

void ContactSolver::find_pressed() {
  pressed_.clear();
  std::fill(is_pressed_.begin(), is_pressed_.end(), 0);
  for (std::int32_t s : slave_union_)
    if (windowed_pressure_[static_cast<std::size_t>(s)] != 0) pressed_.push_back(s), is_pressed_[static_cast<std::size_t>(s)] = 1;
}

void ContactSolver::node_fields(NodeFields& f) const {
  const std::size_t N = model_.num_nodes;
  f.pressure.assign(N, 0.0);
  f.traction.assign(3 * N, 0.0);
  f.status.assign(N, -1.0);
  f.gap.assign(N, std::numeric_limits<double>::quiet_NaN());
  f.area.assign(N, 0.0);
  for (std::int32_t s : slave_union_)  // the windowed pressure (set_pressure_window), which outlives a node's rows
    f.pressure[static_cast<std::size_t>(s)] = windowed_pressure_[static_cast<std::size_t>(s)];
  for (std::size_t k = 0; k < rows_.size(); ++k) {
    const std::size_t s = static_cast<std::size_t>(rows_.slave(k));
    const double* r = &rows_.reaction[3 * k];
    const double* n = &rows_.normal[3 * k];
    const double rn = r[0] * n[0] + r[1] * n[1] + r[2] * n[2];
    for (int d = 0; d < 3; ++d) f.traction[3 * s + d] += (r[d] - rn * n[d]) / rows_.area[k];
    f.status[s] = std::max(f.status[s], static_cast<double>(rows_.status[k]));
    if (std::isnan(f.gap[s]) || rows_.gap[k] < f.gap[s]) f.gap[s] = rows_.gap[k];
    if (!pairs_[static_cast<std::size_t>(rows_.pair[k])].edge_pass) {
      f.area[s] = std::max(f.area[s], rows_.area[k]);
      continue;
    }
    // An edge row's pressure sits on the master side's nodes, over their share of the slave surface.
    for (auto a = rows_.start[k] + 1; a < rows_.start[k + 1]; ++a) {
      const auto node = static_cast<std::size_t>(rows_.nodes[static_cast<std::size_t>(a)]);
      f.area[node] = std::max(f.area[node], edge_share_area_[node]);
    }
  }
}

AveragedPressure ContactSolver::averaged_peak_pressure(const double* u, double sensor_area) const {
  std::vector<std::int32_t> centres;
  for (std::int32_t v : slave_union_)
    if (windowed_pressure_[static_cast<std::size_t>(v)] > 0) centres.push_back(v);
  std::vector<std::int32_t> triangles;
  for (const ContactPair& p : pairs_) triangles.insert(triangles.end(), p.slave_triangles.begin(), p.slave_triangles.end());
  return disc_averaged_peak(model_.X.data(), u, triangles, windowed_pressure_.data(), centres, sensor_area);
}

AveragedPressure disc_averaged_peak(const double* X, const double* u, const std::vector<std::int32_t>& surface, const double* nodal_pressure,
                                    const std::vector<std::int32_t>& centres, double sensor_area) {
  AveragedPressure best;
  if (!(sensor_area > 0) || centres.empty()) return best;
  const double radius = std::sqrt(sensor_area / M_PI);
  auto position = [&](std::int32_t node) {
    const std::size_t i = static_cast<std::size_t>(node);
    return Vec3{X[3 * i] + u[3 * i], X[3 * i + 1] + u[3 * i + 1], X[3 * i + 2] + u[3 * i + 2]};
  };
  auto pressure = [&](std::int32_t node) { return nodal_pressure[static_cast<std::size_t>(node)]; };
  // The box around the centres that a disc can reach.
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (std::int32_t c : centres) {
    const Vec3 x = position(c);
    for (std::size_t d = 0; d < 3; ++d) lo[d] = std::min(lo[d], x[d] - radius), hi[d] = std::max(hi[d], x[d] + radius);
  }
  // The surface's triangles there (each once: a self-contact pair shares its surface), cut into
  // kCuts^2 sub-triangles whose centroids carry their area and the interpolated pressure.
  constexpr int kCuts = 8;
  std::vector<std::array<std::int32_t, 3>> triangles;
  for (std::size_t t = 0; t * 3 < surface.size(); ++t) {
    std::array<std::int32_t, 3> tri{surface[3 * t], surface[3 * t + 1], surface[3 * t + 2]};
    bool inside = false;
    for (std::int32_t v : tri) {
      const Vec3 x = position(v);
      inside = inside || (x[0] >= lo[0] && x[0] <= hi[0] && x[1] >= lo[1] && x[1] <= hi[1] && x[2] >= lo[2] && x[2] <= hi[2]);
    }
    if (!inside) continue;
    std::sort(tri.begin(), tri.end());
    triangles.push_back(tri);
  }
  std::sort(triangles.begin(), triangles.end());
  triangles.erase(std::unique(triangles.begin(), triangles.end()), triangles.end());
  struct Sample {
    Vec3 x;
    double area, force;
  };
  std::vector<Sample> samples;
  samples.reserve(triangles.size() * kCuts * kCuts);
  for (const auto& tri : triangles) {
    const Vec3 a = position(tri[0]), b = position(tri[1]), c = position(tri[2]);
    const double pa = pressure(tri[0]), pb = pressure(tri[1]), pc = pressure(tri[2]);
    const double area = 0.5 * norm(cross(sub(b.data(), a.data()), sub(c.data(), a.data()))) / (kCuts * kCuts);
    for (int i = 0; i < kCuts; ++i)
      for (int j = 0; i + j < kCuts; ++j)
        for (int up = 0; up < (i + j + 1 < kCuts ? 2 : 1); ++up) {  // the upright and, inside, the inverted sub-triangle
          const double l1 = (i + (up ? 2.0 : 1.0) / 3.0) / kCuts, l2 = (j + (up ? 2.0 : 1.0) / 3.0) / kCuts, l0 = 1 - l1 - l2;
          Vec3 x;
          for (std::size_t d = 0; d < 3; ++d) x[d] = l0 * a[d] + l1 * b[d] + l2 * c[d];
          samples.push_back({x, area, (l0 * pa + l1 * pb + l2 * pc) * area});
        }
  }
  // The average over the surface inside each disc: force over the sampled area (the same samples
  // in both, so the sampling of the disc's rim cancels), output times only: a direct sum.
  for (std::int32_t c : centres) {
    const Vec3 xc = position(c);
    double force = 0, area = 0;
    for (const Sample& s : samples) {
      const Vec3 d = sub(s.x.data(), xc.data());
      if (dot(d, d) <= radius * radius) force += s.force, area += s.area;
    }
    if (area > 0 && force / area > best.value) best.value = force / area, best.node = c, best.at = xc;
  }
  return best;
}

}  // namespace tactus::solver
