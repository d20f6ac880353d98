#pragma once
// The element loop of the stress pass, compiled once per material law (each law's file
// instantiates it through make_material_type<Law>()): one-point linear tets, total Lagrangian
// (paper eqs. 27-32), F = I + sum_a u_a (x) grad N_a, f_a = -V0 P grad N_a, with the element's
// stable step in the same pass (Laghos' qdata.dt_est idea). No virtual call or branch on the
// material inside the loop.
//
// Vectorised: the loop takes lanes::kLanes consecutive tets at a time, one per SIMD lane (their
// nodes gathered lane by lane, their forces scattered back in element order), and the laws'
// formulas are templates over the lane type (lanes.hpp), so the same source is the scalar kernel
// (T = double: the partition's tail, a group with an inverted tet, and `vectorised = false`) and
// the vector one. Per node the forces are added in element order either way.
//
// Average nodal pressure (ANP) tets (Bonet & Burton 1998; Joldes, Wittek & Miller 2009): for a
// law with an uncoupled volumetric part, W = W_iso(F) + U(J), the volumetric energy is
// sum_a V_a U(J_a) over the nodes of the material's tets, with nodal volumes V_a = sum_e V_e / 4
// and J_a = v_a / V_a (v_a the same sum of current volumes). Its derivative gives each tet the
// pressure p_e = (1/4) sum_{a of e} U'(J_a), so P = P_iso(F) + p_e cof(F): the nodal pressures come
// from a J pass before this loop (internal_force.cpp), the deviatoric part from the element.
#include <algorithm>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "lanes.hpp"
#include "step_bound.hpp"
#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/material.hpp"

namespace tactus::solver {

// A partition's force buffer holds 4 doubles per node: the force, then the nodal step bound's row
// sum (unused when the bound is off), so the two scatters of a tet's node touch one cache line.
inline constexpr std::size_t kForceStride = 4;

// Tets per tile of the ANP blocks' deformation maxima (StressKernelArgs::anp_tiles); a multiple of
// the lanes, so a group of lanes never straddles two tiles.
inline constexpr std::size_t kAnpTile = 16;
static_assert(kAnpTile % lanes::kLanes == 0);

// One partition of one material block (internal_force.hpp).
struct StressKernelArgs {
  // The call's tets' arrays, each from the call's first tet (tet e's at e - begin): a rank reads
  // its atoms' geometry from its own compact copy (InternalForces::hold_own_geometry), one
  // process from the model's.
  const std::int32_t* conn;  // 4 per tet (model numbering)
  const double* grad;        // 9 per tet
  const double* volume;
  const void* law;
  const double* element_data;  // the law's data of the first tet
  std::size_t data_stride;     // doubles per element; 0: every element shares the law's constants
  std::size_t block_begin;     // element index of the block's first tet (anp_bound_factor)
  std::size_t begin, end;      // the elements of this call
  const double* u;
  const double* v;  // for the viscous part (beta > 0)
  // The force buffer of this call's atom: corner k of tet e adds to f[kForceStride f_slot[4 (e - begin) + k]]
  // (f_slot: the slots of the atom's corners, from its first tet's).
  double* f;
  const std::uint16_t* f_slot = nullptr;
  double beta;
  const double* nodal_pressure = nullptr;  // ANP: U'(J_a) per node (model numbering); nullptr: standard tets
  // ANP: the volume floor J0 (0: off) and its barrier's stiffness (material.hpp, volume_floor_barrier).
  double anp_volume_floor = 0, anp_floor_stiffness = 0;
  const char* rigid_node = nullptr;  // ANP: per node, 1 on a rigid piece (a tet with four such has no floor)
  // The nodal step bound (false: off): each tet adds its rows' sums to its nodes, after their forces
  // (f[kForceStride slot + 3]); ANP tets take their volumetric rows from their constant
  // factors anp_bound_factor (per tet from block_begin; anp_step_bound_factors) and their
  // deviatoric ones from the P-wave modulus less anp_bulk.
  bool nodal_bound = false;
  const double* anp_bound_factor = nullptr;
  double anp_bulk = 0;
  // ANP tets with the bound on: the partition's tiles of kAnpTile consecutive tets (from `begin`),
  // each receiving the largest c^2 >= |cof F - I|_2^2 of its tets (the second form of the bound,
  // design.md "Stable step": a tet's volume-rate vectors have moved from the reference ones by at
  // most c times their reference length; InternalForces).
  double* anp_tiles = nullptr;
  // Mass scaling (nullptr: off): per element from the call's first, the factor (rho V + added) /
  // (rho V) its step is computed with, and where its unscaled squared step (no beta) is stored.
  const double* mass_factor = nullptr;
  double* element_dt2 = nullptr;
  bool vectorised = true;  // false: one tet at a time (the reference the vector kernel is tested against)
};

// What a law's evaluation gives for T = double (one tet) or lanes::Pack (one tet per lane).
template <class T>
struct LawStress {
  lanes::M3<T> P;  // first Piola-Kirchhoff stress
  T W;             // stored energy per reference volume
  T modulus;       // P-wave modulus for the stable step
};

// A law whose energy is W_iso(F) + U(J) declares evaluate_isochoric (P, W of W_iso; the modulus
// still the whole P-wave modulus), volumetric_energy U(J) and volumetric_pressure U'(J); its
// standard evaluation is their sum. Such a law can run as ANP tets.
template <class Law>
concept VolumetricSplit = requires(const Law& l, const lanes::M3<double>& F, double J, const double* d) {
  { l.evaluate_isochoric(F, F, J, d) } -> std::same_as<LawStress<double>>;
  { l.volumetric_energy(J) } -> std::same_as<double>;
  { l.volumetric_pressure(J) } -> std::same_as<double>;
};

template <class Law, class T>
TACTUS_KERNEL_INLINE LawStress<T> evaluate_law(const Law& mat, const lanes::M3<T>& F, const lanes::M3<T>& cof, const T& J, const T* data) {
  if constexpr (VolumetricSplit<Law>) {
    LawStress<T> s = mat.evaluate_isochoric(F, cof, J, data);
    s.P += mat.volumetric_pressure(J) * cof;  // dU/dF = U'(J) cof(F)
    s.W += mat.volumetric_energy(J);
    return s;
  } else {
    return mat.evaluate(F, cof, J, data);
  }
}

namespace kernel_detail {

using lanes::M3;
using lanes::Pack;

// Element indices per lane, for the smallest step and Jacobian.
template <class T>
using LaneIndex = std::conditional_t<std::is_same_v<T, Pack>, lanes::PackMask, std::int64_t>;

// One lane type's running results over a partition.
template <class T>
struct LaneResults {
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  T energy = lanes::splat<T>(0.0), viscous_power = lanes::splat<T>(0.0);
  T dt2 = lanes::splat<T>(kInf), dt = lanes::splat<T>(kInf), min_J = lanes::splat<T>(kInf);
  LaneIndex<T> dt_element{}, min_J_element{};

  // Into `acc`, every lane in turn; on equal values the smaller element index wins, which is
  // what a sequential loop with strict < gives.
  void add_to(StressAccumulator& acc, bool viscous) const {
    for (int l = 0; l < lanes::lanes_of<T>; ++l) {
      acc.energy += lanes::lane(energy, l);
      acc.viscous_power += lanes::lane(viscous_power, l);
      const auto take = [](double v, std::size_t e, double& best, std::size_t& best_e) {
        if (v < best || (v == best && e < best_e)) best = v, best_e = e;
      };
      take(lanes::lane(min_J, l), static_cast<std::size_t>(index(min_J_element, l)), acc.min_J, acc.min_J_element);
      take(lanes::lane(viscous ? dt : dt2, l), static_cast<std::size_t>(index(dt_element, l)), viscous ? acc.dt : acc.dt2, acc.dt_element);
    }
  }
  static std::int64_t index(const LaneIndex<T>& i, int l) {
    if constexpr (std::is_same_v<T, Pack>)
      return i[l];
    else
      return i;
  }
};

template <class T>
TACTUS_KERNEL_INLINE LaneIndex<T> lane_indices(std::size_t e) {
  const auto first = static_cast<std::int64_t>(e);
  if constexpr (std::is_same_v<T, Pack>) {
    lanes::PackMask i{};
    for (int l = 0; l < lanes::kLanes; ++l) i[l] = first + l;
    return i;
  } else {
    return first;
  }
}

// `values[stride * l + k]` for each lane l.
template <class T>
TACTUS_KERNEL_INLINE T load_strided(const double* values, std::size_t stride) {
  return lanes::make_lanes<T>([&](int l) { return values[stride * static_cast<std::size_t>(l)]; });
}

// Gradient of a nodal vector field over the lanes' tets (nodal_gradient() for each): conn holds
// 4 nodes per tet for consecutive tets, g their 9 reference gradients as lanes.
template <class T>
TACTUS_KERNEL_INLINE M3<T> nodal_gradient_lanes(const double* __restrict field, const std::int32_t* conn, const T* g) {
  M3<T> G;
  for (int i = 0; i < 3; ++i) {
    T w[4];
    for (int k = 0; k < 4; ++k) w[k] = lanes::make_lanes<T>([&](int l) { return field[3 * static_cast<std::size_t>(conn[4 * l + k]) + i]; });
    const T d1 = w[1] - w[0], d2 = w[2] - w[0], d3 = w[3] - w[0];
    for (int j = 0; j < 3; ++j) G(i, j) = d1 * g[j] + d2 * g[3 + j] + d3 * g[6 + j];
  }
  return G;
}

// The lanes' deformation at u: their reference gradients (as lanes), F, cof F and J = det F
// (row 0 of F against row 0 of cof F). The stress pass and the ANP J pass both start here.
template <class T>
struct LaneDeformation {
  T g[9];
  M3<T> F, cof;
  T J;
};
template <class T>
TACTUS_KERNEL_INLINE LaneDeformation<T> deformation_lanes(const double* grad, const std::int32_t* conn, const double* u, std::size_t e) {
  LaneDeformation<T> d;
  for (int j = 0; j < 9; ++j) d.g[j] = load_strided<T>(grad + 9 * e + static_cast<std::size_t>(j), 9);
  d.F = nodal_gradient_lanes(u, conn + 4 * e, d.g);
  for (int i = 0; i < 3; ++i) d.F(i, i) += 1.0;
  d.cof = cofactor(d.F);
  d.J = d.F(0, 0) * d.cof(0, 0) + d.F(0, 1) * d.cof(0, 1) + d.F(0, 2) * d.cof(0, 2);
  return d;
}

template <class T>
TACTUS_KERNEL_INLINE bool all_positive(const T& J) {
  for (int l = 0; l < lanes::lanes_of<T>; ++l)
    if (!(lanes::lane(J, l) > 0)) return false;
  return true;
}

template <class Law>
inline constexpr std::size_t element_data_size() {
  if constexpr (requires { Law::kElementData; })
    return Law::kElementData;
  else
    return 1;
}

// The lanes' law stress at F: the element data gathered lane by lane, then the law (ANP: its
// isochoric part plus the mean of the tet's nodal pressures times cof F, the J pass's result).
template <class Law, bool kAnp, class T>
TACTUS_KERNEL_INLINE LawStress<T> lane_law_stress(const StressKernelArgs& a, const Law& mat, std::size_t e, const LaneDeformation<T>& d) {
  constexpr std::size_t kData = element_data_size<Law>();
  T data[kData];
  if constexpr (requires { Law::kElementData; }) {
    const double* first = a.element_data + a.data_stride * (e - a.begin);
    for (std::size_t k = 0; k < kData; ++k) data[k] = load_strided<T>(first + k, a.data_stride);
  } else {
    data[0] = lanes::splat<T>(0.0);
  }
  if constexpr (kAnp) {
    LawStress<T> sp = mat.evaluate_isochoric(d.F, d.cof, d.J, data);
    const std::int32_t* c = a.conn + 4 * (e - a.begin);
    const double* np = a.nodal_pressure;  // the mean of the tet's nodal pressures: its energy is the nodes' (J pass)
    T p = lanes::make_lanes<T>([&](int l) {
      const std::int32_t* cl = c + 4 * l;
      return 0.25 * (np[cl[0]] + np[cl[1]] + np[cl[2]] + np[cl[3]]);
    });
    // The volume floor's barrier, lane by lane and only where a tet is below the floor (rare): its
    // terms are exactly zero elsewhere, so the stress, energy and modulus keep their bits.
    bool below = false;
    for (int l = 0; l < lanes::lanes_of<T>; ++l) below |= lanes::lane(d.J, l) < a.anp_volume_floor;
    if (below) {
      VolumeFloorBarrier b[lanes::lanes_of<T>];
      for (int l = 0; l < lanes::lanes_of<T>; ++l) {
        const std::int32_t* cl = c + 4 * l;
        const bool placed = a.rigid_node && a.rigid_node[cl[0]] && a.rigid_node[cl[1]] && a.rigid_node[cl[2]] && a.rigid_node[cl[3]];
        if (!placed) b[l] = volume_floor_barrier(lanes::lane(d.J, l), a.anp_volume_floor, a.anp_floor_stiffness);
      }
      p += lanes::make_lanes<T>([&](int l) { return b[l].pressure; });
      sp.W += lanes::make_lanes<T>([&](int l) { return b[l].energy; });
      sp.modulus += lanes::make_lanes<T>([&](int l) { return b[l].stiffness; });
    }
    sp.P += p * d.cof;
    return sp;
  } else {
    return evaluate_law(mat, d.F, d.cof, d.J, data);
  }
}

// Current shape-function gradients grad_x N_a = F^{-T} grad_X N_a = cof grad_X N_a / J;
// s = sum_a |grad_x N_a|^2 is returned unscaled (J^2 s) to keep divisions out of the loop.
// cg[b] = cof grad_X N_b = J grad_x N_b, node 0's as minus the others' sum.
template <class T>
TACTUS_KERNEL_INLINE T current_gradients(const M3<T>& cof, const T* g, T cg[4][3]) {
  T sJ2 = lanes::splat<T>(0.0);
  for (int i = 0; i < 3; ++i) cg[0][i] = sJ2;
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) {
      const T h = cof(i, 0) * g[3 * k] + cof(i, 1) * g[3 * k + 1] + cof(i, 2) * g[3 * k + 2];
      sJ2 += h * h;
      cg[k + 1][i] = h;
      cg[0][i] -= h;
    }
  sJ2 += cg[0][0] * cg[0][0] + cg[0][1] * cg[0][1] + cg[0][2] * cg[0][2];
  return sJ2;
}

// Rayleigh beta K v as a viscous stress: sigma_v = beta (lambda tr(D) I + 2 mu D),
// D = sym(Fdot F^{-1}); its first Piola stress is J sigma_v F^{-T} = sigma_v cof. Added to P; its
// power Pv : Fdot V0 to the lanes' viscous power.
template <class Law, class T>
TACTUS_KERNEL_INLINE void add_viscous_stress(const StressKernelArgs& a, const Law& mat, std::size_t e, const LaneDeformation<T>& d, const T& V0,
                                             M3<T>& P, LaneResults<T>& out) {
  const double visc_mu = mat.small_strain_shear(), visc_lambda = mat.small_strain_bulk() - 2.0 * visc_mu / 3.0;
  const M3<T>& cof = d.cof;
  const M3<T> Fdot = nodal_gradient_lanes(a.v, a.conn + 4 * (e - a.begin), d.g);
  M3<T> D;
  const T inv_J = 1.0 / d.J;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const T Lij = Fdot(i, 0) * cof(j, 0) + Fdot(i, 1) * cof(j, 1) + Fdot(i, 2) * cof(j, 2);
      const T Lji = Fdot(j, 0) * cof(i, 0) + Fdot(j, 1) * cof(i, 1) + Fdot(j, 2) * cof(i, 2);
      D(i, j) = 0.5 * inv_J * (Lij + Lji);
    }
  const M3<T> sigma_v = a.beta * (2.0 * visc_mu * D + lanes::identity_times<T>(visc_lambda * lanes::trace(D)));
  const M3<T> Pv = sigma_v * cof;
  P += Pv;
  T power = Pv.a[0] * Fdot.a[0];
  for (int k = 1; k < 9; ++k) power += Pv.a[k] * Fdot.a[k];
  out.viscous_power += V0 * power;
}

// The lanes' stable step (paper's critical time step of the central difference scheme, eq. 35):
// dt_e = L_e / c_e with L_e^2 = 1/s and c_e^2 = M J / rho0 (current density rho0 / J), so
// dt_e^2 = rho0 / (s M J) = rho0 J / (sJ2 M); with mass scaling its unscaled square is stored and
// the step lengthened as sqrt(m); with beta > 0 the damped mode's limit. The smallest (and its
// element) kept per lane.
template <bool kViscous, class T>
TACTUS_KERNEL_INLINE void record_element_step(const StressKernelArgs& a, double density, std::size_t e, const T& J, const T& sJ2, const T& modulus,
                                              const LaneIndex<T>& index, LaneResults<T>& out) {
  T dt2 = density * J / (sJ2 * modulus);
  if (a.element_dt2) {  // mass scaling on: the element's added mass lengthens its step as sqrt(m)
    for (int l = 0; l < lanes::lanes_of<T>; ++l) a.element_dt2[e - a.begin + static_cast<std::size_t>(l)] = lanes::lane(dt2, l);
    dt2 *= load_strided<T>(a.mass_factor + (e - a.begin), 1);
  }
  if constexpr (kViscous) {
    const T omega = 2.0 / lanes::sqrt_of(dt2);
    const T xi = 0.5 * a.beta * omega;
    const T dt = 2.0 / omega * (lanes::sqrt_of(1.0 + xi * xi) - xi);
    const auto smaller = dt < out.dt;
    out.dt = smaller ? dt : out.dt;
    out.dt_element = smaller ? index : out.dt_element;
  } else {
    const auto smaller = dt2 < out.dt2;
    out.dt2 = smaller ? dt2 : out.dt2;
    out.dt_element = smaller ? index : out.dt_element;
  }
}

// f_a = -V0 P grad_X N_a (paper eq. 31), node 0's as minus the others' sum, scattered lane by lane
// in element order, node 1, 2, 3 then 0, as the scalar loop always added them; the nodal step
// bound's rows (step_bound.hpp) after each node's force, in the same cache line.
template <class T>
TACTUS_KERNEL_INLINE void scatter_forces(const StressKernelArgs& a, std::size_t e, const M3<T>& P, const T* g, const T& V0, const T bound[4]) {
  const std::uint16_t* s = a.f_slot + 4 * (e - a.begin);
  T h[4][3];
  for (int i = 0; i < 3; ++i) h[0][i] = lanes::splat<T>(0.0);
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) {
      h[k + 1][i] = -V0 * (P(i, 0) * g[3 * k] + P(i, 1) * g[3 * k + 1] + P(i, 2) * g[3 * k + 2]);
      h[0][i] -= h[k + 1][i];
    }
  for (int l = 0; l < lanes::lanes_of<T>; ++l)
    for (int k : {1, 2, 3, 0}) {
      double* fa = a.f + kForceStride * std::size_t{s[4 * l + k]};
      for (int i = 0; i < 3; ++i) fa[i] += lanes::lane(h[k][i], l);
      if (a.nodal_bound) fa[3] += lanes::lane(bound[k], l);
    }
}

// One group of lanes: deformation, stress, energy, step, nodal step bound rows, forces.
template <class Law, bool kViscous, bool kAnp, class T>
TACTUS_KERNEL_INLINE void element_lanes(const StressKernelArgs& a, const Law& mat, std::size_t e, LaneResults<T>& out, LaneResults<double>& scalar) {
  constexpr int L = lanes::lanes_of<T>;
  const LaneDeformation<T> d = deformation_lanes<T>(a.grad, a.conn, a.u, e - a.begin);
  if constexpr (L > 1) {
    if (!all_positive(d.J)) {  // an inverted tet: lane by lane, so it is recorded and skipped as alone
      for (int l = 0; l < L; ++l) element_lanes<Law, kViscous, kAnp, double>(a, mat, e + static_cast<std::size_t>(l), scalar, scalar);
      return;
    }
  }
  const LaneIndex<T> index = lane_indices<T>(e);
  const auto J_smaller = d.J < out.min_J;
  out.min_J = J_smaller ? d.J : out.min_J;
  out.min_J_element = J_smaller ? index : out.min_J_element;
  if constexpr (L == 1)
    if (!(d.J > 0)) return;  // reported by the caller; the step is abandoned

  LawStress<T> sp = lane_law_stress<Law, kAnp, T>(a, mat, e, d);
  const T V0 = load_strided<T>(a.volume + (e - a.begin), 1);
  out.energy += V0 * sp.W;
  T cg[4][3];
  const T sJ2 = current_gradients(d.cof, d.g, cg);
  record_element_step<kViscous, T>(a, mat.density, e, d.J, sJ2, sp.modulus, index, out);
  if constexpr (kViscous) add_viscous_stress(a, mat, e, d, V0, sp.P, out);
  T bound[4]{};  // the nodal step bound's row sums at the tet's nodes, scattered with the forces
  if (a.nodal_bound) {
    AnpBoundLanes anp;
    if constexpr (kAnp) anp = {a.anp_bound_factor + (e - a.block_begin), a.anp_bulk, a.anp_tiles ? &a.anp_tiles[(e - a.begin) / kAnpTile] : nullptr};
    nodal_bound_rows<kAnp, T>(d.cof, d.J, cg, sp.modulus, V0, anp, bound);
  }
  scatter_forces(a, e, sp.P, d.g, V0, bound);
}

}  // namespace kernel_detail

// Tets ahead of the current group whose nodes' u and force entries are prefetched (a gather the
// hardware prefetcher cannot see).
inline constexpr std::size_t kPrefetchAhead = 16;

template <class Law, bool kViscous, bool kAnp = false>
void stress_range(const StressKernelArgs& a, StressAccumulator& acc) {
  using namespace kernel_detail;
  const Law& mat = *static_cast<const Law*>(a.law);
  LaneResults<double> scalar;
  std::size_t e = a.begin;
  if (a.vectorised) {
    LaneResults<Pack> packed;
    for (; e + lanes::kLanes <= a.end; e += lanes::kLanes) {
      if (e + kPrefetchAhead + lanes::kLanes <= a.end)
        for (int k = 0; k < 4 * lanes::kLanes; ++k) {
          const std::size_t corner = 4 * (e + kPrefetchAhead - a.begin) + static_cast<std::size_t>(k);
          const auto node = static_cast<std::size_t>(a.conn[corner]);
          __builtin_prefetch(a.u + 3 * node);
          __builtin_prefetch(a.f + kForceStride * std::size_t{a.f_slot[corner]}, 1);
          if constexpr (kAnp) __builtin_prefetch(a.nodal_pressure + node);
        }
      element_lanes<Law, kViscous, kAnp, Pack>(a, mat, e, packed, scalar);
    }
    packed.add_to(acc, kViscous);
  }
  for (; e < a.end; ++e) element_lanes<Law, kViscous, kAnp, double>(a, mat, e, scalar, scalar);
  scalar.add_to(acc, kViscous);
}

}  // namespace tactus::solver
