// The vectorised stress and J passes (kernels/lanes.hpp: four tets per SIMD lane group) against
// the scalar ones (one tet at a time, InternalForces::set_vectorised(false)). Oracles: the scalar
// pass, and for the element forces themselves the law's own evaluation through the registry
// (Material::evaluate), independent of either kernel.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>

#include "../../solver/src/kernels/lanes.hpp"
#include "material_kit.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/model_build.hpp"

using namespace tactus;
using namespace tactus::solver;

namespace {

// A random mesh (nodes moved by up to 30 % of a cell, numbering shuffled; 1,458 tets in two
// partitions of 729: each ends with a scalar tail) and a random deformation:
// a stretch that makes some hgo fibres taut and leaves others slack, plus noise.
struct Case {
  Model model;
  std::vector<double> u, v;
};

Case random_case(const Material& material, bool random_fibres, unsigned seed, double strain = 1.0) {
  TetMesh mesh = samples::make_box_mesh(9, 9, 3, 0.03, 0.03, 0.01);
  samples::perturb_interior_nodes(mesh, 0.01 / 3, 0.3, seed);
  samples::shuffle_numbering(mesh, seed);
  Case c{build_model(mesh, material), {}, {}};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> noise(-1.0, 1.0);
  if (random_fibres) {
    MaterialBlock& b = c.model.blocks[0];
    b.element_data.resize(6 * (b.end - b.begin));
    for (double& d : b.element_data) d = noise(rng);
    for (std::size_t k = 0; k < b.element_data.size(); k += 3) {
      const double n = std::sqrt(b.element_data[k] * b.element_data[k] + b.element_data[k + 1] * b.element_data[k + 1] +
                                 b.element_data[k + 2] * b.element_data[k + 2]);
      for (int j = 0; j < 3; ++j) b.element_data[k + static_cast<std::size_t>(j)] /= n;
    }
  }
  c.u.resize(3 * c.model.num_nodes), c.v.resize(3 * c.model.num_nodes);
  for (std::size_t i = 0; i < c.model.num_nodes; ++i) {
    const double* X = &c.model.X[3 * i];
    c.u[3 * i] = strain * (0.08 * X[0] + 0.03 * X[1] + 5e-5 * noise(rng));
    c.u[3 * i + 1] = strain * (-0.04 * X[1] + 0.02 * X[2] + 5e-5 * noise(rng));
    c.u[3 * i + 2] = strain * (-0.05 * X[2] + 5e-5 * noise(rng));
    for (int k = 0; k < 3; ++k) c.v[3 * i + static_cast<std::size_t>(k)] = noise(rng);
  }
  return c;
}

// max over tets and their nodes of |f_e,a| = |V0 P grad N_a|, from Material::evaluate (ANP: with
// the mean of the tet's nodal pressures from anp_nodal_pressure).
double largest_element_force(const Model& m, const std::vector<double>& u) {
  double largest = 0;
  for (const MaterialBlock& b : m.blocks) {
    const std::vector<double> p = b.material.anp() ? anp_nodal_pressure(m, b, u.data()) : std::vector<double>();
    for (std::size_t e = b.begin; e < b.end; ++e) {
      const std::int32_t* c = &m.conn[4 * e];
      const Mat3 F = Mat3::Identity() + nodal_gradient(u.data(), c, &m.grad[9 * e]);
      const Mat3 P = b.material.anp() ? b.material.evaluate_with_pressure(F, 0.25 * (p[c[0]] + p[c[1]] + p[c[2]] + p[c[3]]), b.data_of(e)).P
                                      : b.material.evaluate(F, b.data_of(e)).P;
      Vec3d f0 = Vec3d::Zero();
      for (int a = 0; a < 3; ++a) {
        const Vec3d f = m.volume[e] * P * Vec3d(&m.grad[9 * e + 3 * static_cast<std::size_t>(a)]);
        largest = std::max(largest, f.norm());
        f0 -= f;
      }
      largest = std::max(largest, f0.norm());
    }
  }
  return largest;
}

struct Pass {
  std::vector<double> f;
  StressPassResult result;
  std::vector<double> element_dt2;
};

Pass stress_pass(const Case& c, double beta, bool vectorised, bool mass_scaling) {
  InternalForces forces(c.model, beta, 2);
  forces.set_vectorised(vectorised);
  if (mass_scaling) {
    forces.enable_mass_scaling();
    std::vector<double> factor(c.model.num_elements);
    for (std::size_t e = 0; e < c.model.num_elements; ++e) factor[e] = 1.0 + static_cast<double>(e % 7);
    forces.set_mass_factors(factor);
  }
  Pass p;
  p.f.resize(c.u.size());
  p.result = forces.compute(c.u.data(), c.v.data(), p.f.data());
  p.element_dt2 = forces.element_dt2();
  return p;
}

}  // namespace

// Every law the issue names (and mooney_rivlin), standard and ANP, with Rayleigh beta and with
// mass scaling on: assembled forces within 1e-12 of the largest element force, energies and
// steps within 1e-12 relative, the same limiting and smallest-Jacobian elements.
TEST(Kernels, VectorisedAndScalarPassesAgree) {
  struct Variant {
    const char* name;
    Material material;
    bool random_fibres;
    double strain = 1.0;  // hgo: a third (fibre stretches up to ~5 %, where its exponential is e^2)
  };
  const std::vector<Variant> variants{
      {"neo_hookean standard", testkit::neo_hookean(3000, 50000, 1000, "standard"), false},
      {"neo_hookean anp", testkit::neo_hookean(3000, 5e6, 1000, "anp"), false},
      {"linear_elastic", testkit::linear_elastic(1e9, 0.3, 2000), false},
      {"hgo standard, random fibres", testkit::paper_hgo(1e8, "standard"), true, 0.33},
      {"hgo anp, random fibres", testkit::paper_hgo(1e8, "anp"), true, 0.33},
      {"hgo anp, the paper's fibres", testkit::paper_hgo(1e8, "anp"), false, 0.33},
      {"mooney_rivlin", testkit::make_law("mooney_rivlin", {{"c10", 2000}, {"c01", 500}, {"bulk", 1e6}, {"density", 1000}}), false},
  };
  for (const Variant& variant : variants)
    for (const double beta : {0.0, 1e-4})
      for (const bool mass_scaling : {false, true}) {
        const Case c = random_case(variant.material, variant.random_fibres, 7, variant.strain);
        const Pass vec = stress_pass(c, beta, true, mass_scaling), sca = stress_pass(c, beta, false, mass_scaling);
        const double scale = largest_element_force(c.model, c.u);
        double df = 0;
        for (std::size_t i = 0; i < vec.f.size(); ++i) df = std::max(df, std::abs(vec.f[i] - sca.f[i]));
        double ddt = 0;
        for (std::size_t e = 0; e < vec.element_dt2.size(); ++e) ddt = std::max(ddt, std::abs(vec.element_dt2[e] / sca.element_dt2[e] - 1));
        const auto rel = [](double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-300); };
        std::printf(
            "%-30s beta %.0e mass scaling %d: %zu tets, max |f_vec - f_scalar| = %.2e of max_e |f_e| (%.3e N); energy %.1e, step %.1e, "
            "viscous power %.1e relative; element steps %.1e; limiting tet %zu / %zu, min J tet %zu / %zu (J %.1e relative)\n",
            variant.name, beta, mass_scaling ? 1 : 0, c.model.num_elements, df / scale, scale,
            rel(vec.result.strain_energy, sca.result.strain_energy), rel(vec.result.critical_step, sca.result.critical_step),
            beta > 0 ? rel(vec.result.viscous_power, sca.result.viscous_power) : 0.0, ddt, vec.result.limiting_element, sca.result.limiting_element,
            vec.result.min_jacobian_element, sca.result.min_jacobian_element, rel(vec.result.min_jacobian, sca.result.min_jacobian));
        EXPECT_LE(df, 1e-12 * scale) << variant.name;
        EXPECT_LE(rel(vec.result.strain_energy, sca.result.strain_energy), 1e-12) << variant.name;
        EXPECT_LE(rel(vec.result.critical_step, sca.result.critical_step), 1e-12) << variant.name;
        if (beta > 0) {
          EXPECT_LE(rel(vec.result.viscous_power, sca.result.viscous_power), 1e-12) << variant.name;
        }
        EXPECT_LE(ddt, 1e-12) << variant.name;
        EXPECT_EQ(vec.result.limiting_element, sca.result.limiting_element) << variant.name;
        EXPECT_EQ(vec.result.min_jacobian_element, sca.result.min_jacobian_element) << variant.name;
        // The value to a few ulps, not bits: with contraction on (the default build) the compiler may
        // fuse det F's products differently in the double and the Pack instantiation.
        EXPECT_LE(rel(vec.result.min_jacobian, sca.result.min_jacobian), 1e-15) << variant.name;
      }
}

// Inverted tets inside lane groups (a node pushed through its neighbour turns the tets around
// it inside out): those groups fall back to one tet at a time, the smallest Jacobian is the
// scalar pass's (same tet, same value) and the other tets' forces still agree.
TEST(Kernels, InvertedTetInALaneGroupIsReportedAsByTheScalarPass) {
  Case c = random_case(testkit::neo_hookean(3000, 50000, 1000, "standard"), false, 3);
  const std::size_t e = 4 * 37 + 2;  // the third lane of a group
  const std::int32_t* n = &c.model.conn[4 * e];
  const Vec3d x0 = Vec3d(&c.model.X[3 * static_cast<std::size_t>(n[0])]) + Vec3d(&c.u[3 * static_cast<std::size_t>(n[0])]);
  const Vec3d x1 = Vec3d(&c.model.X[3 * static_cast<std::size_t>(n[1])]) + Vec3d(&c.u[3 * static_cast<std::size_t>(n[1])]);
  for (int k = 0; k < 3; ++k)  // node 1 pushed through node 0: the tet turns inside out
    c.u[3 * static_cast<std::size_t>(n[1]) + static_cast<std::size_t>(k)] += 2.0 * (x0[k] - x1[k]);
  const Pass vec = stress_pass(c, 0.0, true, false), sca = stress_pass(c, 0.0, false, false);
  std::printf("node pushed through (tet %zu): min J vector %.6f at tet %zu, scalar %.6f at tet %zu\n", e, vec.result.min_jacobian,
              vec.result.min_jacobian_element, sca.result.min_jacobian, sca.result.min_jacobian_element);
  EXPECT_LT(sca.result.min_jacobian, 0.0);
  EXPECT_EQ(vec.result.min_jacobian_element, sca.result.min_jacobian_element);
  EXPECT_EQ(vec.result.min_jacobian, sca.result.min_jacobian);
  double df = 0, fmax = 0;
  for (std::size_t i = 0; i < vec.f.size(); ++i) df = std::max(df, std::abs(vec.f[i] - sca.f[i])), fmax = std::max(fmax, std::abs(sca.f[i]));
  EXPECT_LE(df, 1e-12 * fmax);
}

// The pack exponential (hgo's fibres) against libm over the range the law meets and beyond:
// within 4 ulp, +inf above log(DBL_MAX), and the largest finite results right.
TEST(Kernels, PackExponentialMatchesLibm) {
  using lanes::Pack;
  double worst = 0, worst_x = 0;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> x_of(-745.0, 709.7);
  for (int k = 0; k < 200000; ++k) {
    Pack x;
    for (int l = 0; l < lanes::kLanes; ++l) x[l] = k < 1000 ? 1e-3 * (4 * k + l) : x_of(rng);
    const Pack e = lanes::exp_of(x);
    for (int l = 0; l < lanes::kLanes; ++l) {
      const double exact = std::exp(x[l]);
      if (exact < 1e-300) continue;  // subnormal results: not needed by any law
      const double ulps = std::abs(e[l] - exact) / (std::nextafter(exact, INFINITY) - exact);
      if (ulps > worst) worst = ulps, worst_x = x[l];
    }
  }
  const Pack edge = lanes::exp_of(Pack{709.78, 709.79, 800.0, 0.0});
  std::printf("pack exp vs libm: worst %.2f ulp at x = %.6f; exp(709.78) %.6e (libm %.6e), exp(709.79) %g, exp(800) %g, exp(0) %.17g\n", worst,
              worst_x, edge[0], std::exp(709.78), edge[1], edge[2], edge[3]);
  EXPECT_LE(worst, 4.0);
  EXPECT_NEAR(edge[0] / std::exp(709.78), 1.0, 1e-15);
  EXPECT_TRUE(std::isinf(edge[1]) && std::isinf(edge[2]));
  EXPECT_EQ(edge[3], 1.0);
}

// The locality reorder (reorder_for_locality) moves every per-tet array in place along its
// permutation's cycles. Oracle: the same model not reordered (input numbering), tet by tet through
// input_element and node by node through node_of_input: each reordered tet has the input tet's
// nodes, and bit for bit its reference gradients, volume and per-element data (hgo fibres, random).
TEST(Kernels, LocalityReorderCarriesEveryTetsDataWithIt) {
  TetMesh mesh = samples::make_box_mesh(9, 9, 3, 0.03, 0.03, 0.01);
  samples::perturb_interior_nodes(mesh, 0.01 / 3, 0.3, 11);
  samples::shuffle_numbering(mesh, 11);
  Model plain = build_model(mesh, testkit::paper_hgo(), "material", {0, 0, 0}, false);
  plain.blocks[0].element_data.resize(6 * plain.num_elements);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> noise(-1.0, 1.0);
  for (double& d : plain.blocks[0].element_data) d = noise(rng);
  Model reordered = plain;
  reorder_for_locality(reordered);
  std::size_t moved = 0, differ = 0;
  for (std::size_t k = 0; k < reordered.num_elements; ++k) {
    const auto e = static_cast<std::size_t>(reordered.input_element[k]);
    moved += e != k;
    for (std::size_t a = 0; a < 4; ++a)
      differ += reordered.conn[4 * k + a] != reordered.node_of_input[static_cast<std::size_t>(plain.conn[4 * e + a])];
    differ += std::memcmp(&reordered.grad[9 * k], &plain.grad[9 * e], 9 * sizeof(double)) != 0;
    differ += std::memcmp(&reordered.volume[k], &plain.volume[e], sizeof(double)) != 0;
    differ += std::memcmp(reordered.blocks[0].data_of(k), plain.blocks[0].data_of(e), 6 * sizeof(double)) != 0;
  }
  std::printf("locality reorder: %zu of %zu tets moved, %zu mismatches against the model not reordered\n", moved, reordered.num_elements, differ);
  EXPECT_GT(moved, reordered.num_elements / 2);
  EXPECT_EQ(differ, 0u);
}

// The states' cell records come from the stress pass (InternalForces::cell_records) after a pass
// at u. Oracle: element_cauchy_stress, one process apart from the pass (an ANP tet's nodal
// pressures summed tet by tet rather than atom by atom): the same bits for standard tets, and for
// ANP tets within rounding (1e-12 of the largest stress component).
TEST(Kernels, CellRecordsReportThePassesStress) {
  for (const char* formulation : {"standard", "anp"}) {
    Case c = random_case(testkit::paper_hgo(1e8, formulation), true, 11, 0.33);
    InternalForces forces(c.model, 0.0, 1);
    std::vector<double> f(3 * c.model.num_nodes);
    forces.compute(c.u.data(), nullptr, f.data());
    const std::vector<Mat3> sigma = element_cauchy_stress(c.model, c.u.data());
    double largest = 0, worst = 0;
    std::size_t given = 0, differ = 0;
    forces.cell_records(c.u.data(), [&](std::size_t, std::size_t e, const std::int32_t*, const double* r) {
      const Mat3& s = sigma[e];
      const double voigt[6] = {s(0, 0), s(1, 1), s(2, 2), s(0, 1), s(1, 2), s(0, 2)};
      ++given;
      for (int k = 0; k < 6; ++k) {
        largest = std::max(largest, std::abs(voigt[k]));
        worst = std::max(worst, std::abs(r[k] - voigt[k]));
        differ += r[k] != voigt[k];
      }
      if (r[6] != von_mises(s) && std::string(formulation) == "standard") ++differ;
    });
    std::printf("hgo %s: %zu tets' records, %zu stress components differ from element_cauchy_stress, the largest by %.3g of %.3g Pa\n", formulation,
                given, differ, worst, largest);
    EXPECT_EQ(given, c.model.num_elements);
    if (std::string(formulation) == "standard")
      EXPECT_EQ(differ, 0u);
    else
      EXPECT_LE(worst, 1e-12 * largest);
  }
}
