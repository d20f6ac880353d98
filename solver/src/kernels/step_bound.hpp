#pragma once
// The nodal step bound's rows, per tet in the stress pass (design.md, "Stable step"): the
// critical time step of the central difference scheme (paper eq. 35) is 2 / omega_max, and
// omega_max^2 <= max_a (row sum a of the stiffness's absolute values) / m_a (Gershgorin). Each tet
// adds its share of those row sums to its nodes, scattered with its forces (element_loop.hpp);
// InternalForces reduces them per node chunk (step_bound.cpp). ANP tets take their volumetric rows
// from constant per-tet factors (anp_step_bound_factors) and, for the bound's second form, record
// how far their volume-rate vectors have moved from the reference ones (the tile maxima c^2).
#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

#include "lanes.hpp"
#include "tactus/solver/material.hpp"

namespace tactus::solver {

// What an ANP tet group needs for its rows: its constant volumetric factors q_e (from the group's
// first tet), the block's small-strain bulk modulus (taken out of the P-wave modulus, its
// volumetric rows being q's), and the tile receiving the group's largest c^2 (nullptr: the second
// form is off).
struct AnpBoundLanes {
  const double* factor = nullptr;
  double bulk = 0;
  double* tile = nullptr;
};

// Node b of the tet gets |d_b| (M / J + q_e) t_e / V0, d_b = dv_e/dx_b = V0 cg[b],
// t_e = sum_b |d_b|; M the P-wave modulus (ANP: its deviatoric part) and q_e the ANP tet's
// constant volumetric factor (else 0). cg[b] = cof F grad_X N_b (element_loop.hpp).
template <bool kAnp, class T>
TACTUS_KERNEL_INLINE void nodal_bound_rows(const lanes::M3<T>& cof, const T& J, const T cg[4][3], const T& modulus, const T& V0,
                                           const AnpBoundLanes& anp, T bound[4]) {
  T t = lanes::splat<T>(0.0);
  for (int k = 0; k < 4; ++k) bound[k] = lanes::sqrt_of(cg[k][0] * cg[k][0] + cg[k][1] * cg[k][1] + cg[k][2] * cg[k][2]), t += bound[k];
  T row = (kAnp ? modulus - anp.bulk : modulus) * t / J;
  if constexpr (kAnp) {
    const T q = lanes::make_lanes<T>([&](int l) { return anp.factor[l]; });
    row += q * t;
    if (anp.tile) {
      // c^2 >= |cof F - I|_2^2, the smaller of its Frobenius norm's square and the product of its
      // largest column and row sums (|A|_2^2 <= |A|_1 |A|_inf), its largest over the lanes into the
      // tile: |cof F grad_X N_b - grad_X N_b| <= c |grad_X N_b|.
      T frobenius = lanes::splat<T>(0.0), column_sum[3], row_sum[3];
      for (int i = 0; i < 3; ++i) column_sum[i] = row_sum[i] = frobenius;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const T moved = i == j ? cof(i, j) - 1.0 : cof(i, j), size = lanes::abs_of(moved);
          frobenius += moved * moved, row_sum[i] += size, column_sum[j] += size;
        }
      const T max_column = lanes::max_of(column_sum[0], lanes::max_of(column_sum[1], column_sum[2])),
              max_row = lanes::max_of(row_sum[0], lanes::max_of(row_sum[1], row_sum[2]));
      const T c2 = lanes::min_of(frobenius, max_column * max_row);
      double largest = lanes::lane(c2, 0);
      for (int l = 1; l < lanes::lanes_of<T>; ++l) largest = std::max(largest, lanes::lane(c2, l));
      *anp.tile = std::max(*anp.tile, largest);
    }
  }
  row *= V0;
  for (int k = 0; k < 4; ++k) bound[k] *= row;
}

struct Model;
struct MaterialBlock;

// The block's tets at each node, in element order: node a's are tets[first[a] .. first[a + 1])
// (the ANP rest rows here and the pressure averaging, internal_force.cpp).
std::pair<std::vector<std::size_t>, std::vector<std::size_t>> block_node_tets(const Model& model, const MaterialBlock& block);

// Per node, the ANP block's volumetric rows of the bound's first form at the reference state,
// from the tets' factors q (anp_step_bound_factors, internal_force.hpp).
std::vector<double> anp_reference_rows(const Model& model, const MaterialBlock& block, const std::vector<double>& q);

}  // namespace tactus::solver
