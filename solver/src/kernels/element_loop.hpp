#pragma once
// The element loop of the stress pass, compiled once per material law (each law's file
// instantiates it through make_material_type<Law>()): one-point linear tets, total Lagrangian
// (paper eqs. 27-32), F = I + sum_a u_a (x) grad N_a, f_a = -V0 P grad N_a, with the element's
// stable step in the same pass (Laghos' qdata.dt_est idea). No virtual call or branch on the
// material inside the loop.
//
// Average nodal pressure (ANP) tets (Bonet & Burton 1998; Joldes, Wittek & Miller 2009): for a
// law with an uncoupled volumetric part, W = W_iso(F) + U(J), the volumetric energy is
// sum_a V_a U(J_a) over the nodes of the material's tets, with nodal volumes V_a = sum_e V_e / 4
// and J_a = v_a / V_a (v_a the same sum of current volumes). Its derivative gives each tet the
// pressure p_e = (1/4) sum_{a of e} U'(J_a), so P = P_iso(F) + p_e cof(F): the nodal pressures come
// from a J pass before this loop (internal_force.cpp), the deviatoric part from the element.
#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>

#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/material.hpp"

namespace tactus::solver {

// One partition of one material block (internal_force.hpp).
struct StressKernelArgs {
  const std::int32_t* conn;  // 4 per tet (model numbering)
  const double* grad;        // 9 per tet
  const double* volume;
  const void* law;
  const double* element_data;  // the block's data of its first element
  std::size_t data_stride;     // doubles per element; 0: every element shares the law's constants
  std::size_t block_begin;     // element index of element_data
  std::size_t begin, end;      // the elements of this call
  const double* u;
  const double* v;  // for the viscous part (beta > 0)
  double* f;        // the force buffer of this call's partition: node n's force at f[3 (n - f_node_offset)]
  std::size_t f_node_offset = 0;
  double beta;
  const double* nodal_pressure = nullptr;  // ANP: U'(J_a) per node (model numbering); nullptr: standard tets
  // Mass scaling (nullptr: off): per element (model numbering), the factor (rho V + added) / (rho V)
  // its step is computed with, and where its unscaled squared step (no beta) is stored.
  const double* mass_factor = nullptr;
  double* element_dt2 = nullptr;
};

// A law whose energy is W_iso(F) + U(J) declares evaluate_isochoric (P, W of W_iso; the modulus
// still the whole P-wave modulus), volumetric_energy U(J) and volumetric_pressure U'(J); its
// standard evaluation is their sum. Such a law can run as ANP tets.
template <class Law>
concept VolumetricSplit = requires(const Law& l, const Mat3& F, double J, const double* d) {
  { l.evaluate_isochoric(F, F, J, d) } -> std::same_as<StressPoint>;
  { l.volumetric_energy(J) } -> std::same_as<double>;
  { l.volumetric_pressure(J) } -> std::same_as<double>;
};

template <class Law>
TACTUS_KERNEL_INLINE StressPoint evaluate_law(const Law& mat, const Mat3& F, const Mat3& cof, double J, const double* data) {
  if constexpr (VolumetricSplit<Law>) {
    StressPoint s = mat.evaluate_isochoric(F, cof, J, data);
    s.P += mat.volumetric_pressure(J) * cof;  // dU/dF = U'(J) cof(F)
    s.W += mat.volumetric_energy(J);
    return s;
  } else {
    return mat.evaluate(F, cof, J, data);
  }
}

template <class Law, bool kViscous, bool kAnp = false>
void stress_range(const StressKernelArgs& a, StressAccumulator& acc) {
  const Law& mat = *static_cast<const Law*>(a.law);
  const std::int32_t* __restrict conn = a.conn;
  const double* __restrict grad = a.grad;
  const double* __restrict vol = a.volume;
  const double* __restrict u = a.u;
  const double* __restrict v = a.v;
  double* __restrict f = a.f;
  const double rho0 = mat.density;
  const double visc_lambda = mat.small_strain_bulk() - 2.0 * mat.small_strain_shear() / 3.0;
  const double visc_mu = mat.small_strain_shear();
  for (std::size_t e = a.begin; e < a.end; ++e) {
    const std::int32_t* c = conn + 4 * e;
    const double* g = grad + 9 * e;
    Mat3 F = nodal_gradient(u, c, g);
    F(0, 0) += 1.0, F(1, 1) += 1.0, F(2, 2) += 1.0;
    const Mat3 cof = cofactor(F);
    const double J = F(0, 0) * cof(0, 0) + F(0, 1) * cof(0, 1) + F(0, 2) * cof(0, 2);
    if (J < acc.min_J) acc.min_J = J, acc.min_J_element = e;
    if (!(J > 0)) continue;  // reported by the caller; the step is abandoned
    const double* data = a.element_data + a.data_stride * (e - a.block_begin);
    StressPoint sp;
    if constexpr (kAnp) {
      sp = mat.evaluate_isochoric(F, cof, J, data);
      const double* p = a.nodal_pressure;
      sp.P += (0.25 * (p[c[0]] + p[c[1]] + p[c[2]] + p[c[3]])) * cof;  // its energy is the nodes' (J pass)
    } else {
      sp = evaluate_law(mat, F, cof, J, data);
    }
    const double V0 = vol[e];
    acc.energy += V0 * sp.W;

    // Current shape-function gradients grad_x N_a = F^{-T} grad_X N_a = cof grad_X N_a / J;
    // s = sum_a |grad_x N_a|^2 is accumulated unscaled (J^2 s) to keep divisions out of the loop.
    double sJ2 = 0, sum[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k) {
      double h[3];
      for (int i = 0; i < 3; ++i) h[i] = cof(i, 0) * g[3 * k] + cof(i, 1) * g[3 * k + 1] + cof(i, 2) * g[3 * k + 2];
      sJ2 += h[0] * h[0] + h[1] * h[1] + h[2] * h[2];
      sum[0] += h[0], sum[1] += h[1], sum[2] += h[2];
    }
    sJ2 += sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2];
    // dt_e = L_e / c_e with L_e^2 = 1/s and c_e^2 = M J / rho0 (current density rho0 / J):
    // dt_e^2 = rho0 / (s M J) = rho0 J / (sJ2 M).
    double dt2 = rho0 * J / (sJ2 * sp.modulus);
    if (a.element_dt2) {  // mass scaling on: the element's added mass lengthens its step as sqrt(m)
      a.element_dt2[e] = dt2;
      dt2 *= a.mass_factor[e];
    }

    if constexpr (kViscous) {
      // Rayleigh beta K v as a viscous stress: sigma_v = beta (lambda tr(D) I + 2 mu D),
      // D = sym(Fdot F^{-1}); its first Piola stress is J sigma_v F^{-T} = sigma_v cof.
      const Mat3 Fdot = nodal_gradient(v, c, g);
      const Mat3 L = Fdot * cof.transpose() / J;
      const Mat3 D = 0.5 * (L + L.transpose());
      const Mat3 sigma_v = a.beta * (visc_lambda * D.trace() * Mat3::Identity() + 2.0 * visc_mu * D);
      const Mat3 Pv = sigma_v * cof;
      sp.P += Pv;
      acc.viscous_power += V0 * (Pv.cwiseProduct(Fdot)).sum();
      const double omega = 2.0 / std::sqrt(dt2);
      const double xi = 0.5 * a.beta * omega;
      const double dt = 2.0 / omega * (std::sqrt(1.0 + xi * xi) - xi);
      if (dt < acc.dt) acc.dt = dt, acc.dt_element = e;
    } else {
      (void)v;
      if (dt2 < acc.dt2) acc.dt2 = dt2, acc.dt_element = e;
    }

    double f0[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k) {
      double* fa = f + 3 * (static_cast<std::size_t>(c[k + 1]) - a.f_node_offset);
      for (int i = 0; i < 3; ++i) {
        const double h = -V0 * (sp.P(i, 0) * g[3 * k] + sp.P(i, 1) * g[3 * k + 1] + sp.P(i, 2) * g[3 * k + 2]);
        fa[i] += h;
        f0[i] -= h;
      }
    }
    double* fz = f + 3 * (static_cast<std::size_t>(c[0]) - a.f_node_offset);
    fz[0] += f0[0], fz[1] += f0[1], fz[2] += f0[2];
  }
}

}  // namespace tactus::solver
