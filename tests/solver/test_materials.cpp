// solver/materials: S = 2 dW/dC by finite differences, objectivity, the HGO uniaxial curve against
// an independent principal-stretch computation, and slack fibres in compression.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cstdio>
#include <random>
#include <sstream>

#include "tactus/solver/material.hpp"
#include "tactus/solver/run.hpp"
#include "tactus/solver/scenario.hpp"

using namespace tactus::solver;

namespace {

double energy(const Material& m, const Mat3& F) { return m.evaluate(F).W; }
Mat3 first_piola(const Material& m, const Mat3& F) { return m.evaluate(F).P; }

// The laws through the registry, as a scenario would make them.
Material law(const std::string& type, std::map<std::string, double> numbers, std::vector<tactus::Vec3> fibres = {}) {
  MaterialValues v;
  v.numbers = std::move(numbers);
  if (!fibres.empty()) v.vectors["fibres"] = fibres;
  return Material::make(type, v);
}
Material neo_hookean(double mu, double bulk, double rho) { return law("neo_hookean", {{"mu", mu}, {"bulk", bulk}, {"density", rho}}); }

// W as a function of C alone: F = C^{1/2} (symmetric root; W depends on F only through C).
double energy_of_C(const Material& m, const Mat3& C) {
  Eigen::SelfAdjointEigenSolver<Mat3> es(C);
  const Mat3 U = es.eigenvectors() * es.eigenvalues().cwiseSqrt().asDiagonal() * es.eigenvectors().transpose();
  return energy(m, U);
}

// 2 dW/dC by 4th-order central differences on the independent entries of symmetric C.
Mat3 fd_second_piola(const Material& m, const Mat3& C, double h) {
  Mat3 S;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) {
      auto W = [&](double d) {
        Mat3 Cp = C;
        Cp(i, j) += d;
        if (i != j) Cp(j, i) += d;
        return energy_of_C(m, Cp);
      };
      const double dW = (-W(2 * h) + 8 * W(h) - 8 * W(-h) + W(-2 * h)) / (12 * h);
      // Perturbing C_ij and C_ji together gives dW/dC_ij + dW/dC_ji = 2 dW/dC_ij for i != j.
      S(i, j) = S(j, i) = (i == j ? 2.0 : 1.0) * dW;
    }
  return S;
}

Mat3 random_F(std::mt19937& rng, double amplitude) {
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  Mat3 F = Mat3::Identity();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) F(i, j) += u(rng);
  return F;
}

Mat3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n;
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  return q.normalized().toRotationMatrix();
}

// The paper's tissue (fibres at +-30 deg in the x-y plane), with the bulk modulus lowered so the
// fibre and matrix terms are not lost next to the volumetric one in a relative comparison, and a
// stiff-k variant.
const tactus::Vec3 kFibre1{std::cos(0.5236), std::sin(0.5236), 0}, kFibre2{std::cos(0.5236), -std::sin(0.5236), 0};
Material paper_hgo(double k = 1.0e8, double k1 = 1.7, double k2 = 882.847) {
  return law("hgo", {{"c1", 10206.9}, {"k1", k1}, {"k2", k2}, {"k", k}, {"density", 1050}}, {kFibre1, kFibre2});
}

std::vector<Material> materials_under_test() {
  return {neo_hookean(3000.0, 50000.0, 1000.0),
          law("linear_elastic", {{"E", 10e9}, {"nu", 0.22}, {"density", 2150}}),
          paper_hgo(2.0e5),
          paper_hgo(),
          paper_hgo(2.0e5, 2.0e4, 5.0) /* fibres that dominate */,
          law("mooney_rivlin", {{"c10", 2000.0}, {"c01", 800.0}, {"bulk", 50000.0}, {"density", 1000}}),
          law("mooney_rivlin", {{"c10", 0.0}, {"c01", 1500.0}, {"bulk", 2.0e5}, {"density", 1000}})};
}

}  // namespace

// Oracle: finite differences of W. Tolerance 1e-6 relative to |S| (4th-order stencil, h = 1e-4:
// truncation ~h^4 W''''' and round-off ~eps W / h are both far below it).
TEST(Materials, SecondPiolaIsTwiceDerivativeOfEnergy) {
  std::mt19937 rng(1234);
  for (const Material& m : materials_under_test()) {
    for (int trial = 0; trial < 20; ++trial) {
      const Mat3 F = random_F(rng, 0.08);
      const Mat3 C = F.transpose() * F;
      const Mat3 S = F.inverse() * first_piola(m, F);
      const Mat3 S_fd = fd_second_piola(m, C, 1e-4);
      EXPECT_LE((S - S_fd).norm(), 1e-6 * S.norm()) << m.type_name() << " trial " << trial << "\nS=\n" << S << "\nS_fd=\n" << S_fd;
      EXPECT_LE((S - S.transpose()).norm(), 1e-12 * S.norm()) << "S must be symmetric";
    }
  }
}

// Oracle: frame indifference. P(QF) = Q P(F), so S and W are unchanged and sigma -> Q sigma Q^T.
TEST(Materials, ObjectiveUnderRotation) {
  std::mt19937 rng(99);
  for (const Material& m : materials_under_test())
    for (int trial = 0; trial < 20; ++trial) {
      const Mat3 F = random_F(rng, 0.1), Q = random_rotation(rng);
      const Mat3 P = first_piola(m, F), PQ = first_piola(m, Q * F);
      const Mat3 S = F.inverse() * P, SQ = (Q * F).inverse() * PQ;
      EXPECT_LE((S - SQ).norm(), 1e-10 * S.norm()) << m.type_name();
      EXPECT_NEAR(energy(m, F), energy(m, Q * F), 1e-10 * std::abs(energy(m, F)) + 1e-12);
      const Mat3 sigma = cauchy_stress(F, P), sigmaQ = cauchy_stress(Q * F, PQ);
      EXPECT_LE((Q * sigma * Q.transpose() - sigmaQ).norm(), 1e-10 * sigma.norm());
    }
}

TEST(Materials, StressFreeAtIdentity) {
  for (const Material& m : materials_under_test()) {
    EXPECT_LE(first_piola(m, Mat3::Identity()).norm(), 1e-9);
    EXPECT_NEAR(energy(m, Mat3::Identity()), 0.0, 1e-12);
  }
}

// Oracle: with the fibres shortened (isochoric J4bar < 1) the hgo law equals the same law with
// k1 = 0, which is the neo-Hookean law with mu = 2 c1.
TEST(Materials, FibresSlackInCompression) {
  const Material h = paper_hgo(2.0e5, 1e5);  // a large k1 would show at once if compressed fibres carried load
  const Material no_fibres = paper_hgo(2.0e5, 0.0);
  const Material nh = neo_hookean(2 * 10206.9, 2.0e5, 1050);
  // Compress along x (both fibres have a large x component) with lateral expansion.
  Mat3 F = Mat3::Identity();
  F(0, 0) = 0.85, F(1, 1) = 1.02, F(2, 2) = 1.08;
  for (const tactus::Vec3& a : {kFibre1, kFibre2})
    ASSERT_LT(std::cbrt(1 / (F.determinant() * F.determinant())) * (F * Vec3d(a.data())).squaredNorm(), 1.0);
  EXPECT_LE((h.evaluate(F).P - no_fibres.evaluate(F).P).norm(), 1e-12 * no_fibres.evaluate(F).P.norm());
  EXPECT_LE((h.evaluate(F).P - nh.evaluate(F).P).norm(), 1e-10 * nh.evaluate(F).P.norm());
  EXPECT_DOUBLE_EQ(h.evaluate(F).W, no_fibres.evaluate(F).W);
  // Stretched along x, the same fibres do carry load.
  F(0, 0) = 1.1, F(1, 1) = 0.96, F(2, 2) = 0.96;
  EXPECT_GT((h.evaluate(F).P - no_fibres.evaluate(F).P).norm(), 1.0);
}

namespace {

// Independent uniaxial response of hgo with fibres at +-theta in the x-y plane, from the scalar
// energy in principal stretches (no tensor code): sigma_i = lambda_i / J dW/dlambda_i, with
// dW/dlambda_i by 4th-order differences, and the lateral stretches solved by Newton so that
// sigma_yy = sigma_zz = 0. The two symmetric families keep x, y, z principal.
struct PrincipalHgo {
  double c1, k1, k2, k, theta;
  double W(double l1, double l2, double l3) const {
    const double J = l1 * l2 * l3, Jm23 = std::pow(J, -2.0 / 3.0);
    double w = c1 * (Jm23 * (l1 * l1 + l2 * l2 + l3 * l3) - 3) + 0.5 * k * (J - 1) * (J - 1);
    const double J4 = l1 * l1 * std::cos(theta) * std::cos(theta) + l2 * l2 * std::sin(theta) * std::sin(theta);
    const double x = Jm23 * J4 - 1;
    if (x > 0) w += 2 * k1 / (2 * k2) * (std::exp(k2 * x * x) - 1);  // two identical families
    return w;
  }
  double sigma(int i, double l1, double l2, double l3) const {
    double l[3] = {l1, l2, l3};
    const double h = 1e-5 * l[i];
    auto f = [&](double d) {
      double p[3] = {l1, l2, l3};
      p[i] += d;
      return W(p[0], p[1], p[2]);
    };
    const double dW = (-f(2 * h) + 8 * f(h) - 8 * f(-h) + f(-2 * h)) / (12 * h);
    return l[i] * dW / (l1 * l2 * l3);
  }
  // Returns sigma_xx at axial stretch l1.
  double uniaxial(double l1) const {
    double l2 = 1, l3 = 1;
    for (int it = 0; it < 100; ++it) {
      const double r2 = sigma(1, l1, l2, l3), r3 = sigma(2, l1, l2, l3);
      if (std::hypot(r2, r3) < 1e-9 * (k + c1)) break;
      const double e = 1e-7;
      const double a = (sigma(1, l1, l2 + e, l3) - r2) / e, b = (sigma(1, l1, l2, l3 + e) - r2) / e;
      const double c = (sigma(2, l1, l2 + e, l3) - r3) / e, d = (sigma(2, l1, l2, l3 + e) - r3) / e;
      const double det = a * d - b * c;
      l2 -= (d * r2 - b * r3) / det;
      l3 -= (-c * r2 + a * r3) / det;
    }
    return sigma(0, l1, l2, l3);
  }
};

std::vector<std::vector<double>> parse_csv(const std::string& text) {
  std::vector<std::vector<double>> rows;
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::istringstream ls(line);
    std::string cell;
    while (std::getline(ls, cell, ',')) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

Scenario hgo_scenario(double theta, double k) {
  Scenario sc;
  MaterialInstance m;
  m.name = "tissue";
  m.type = "hgo";
  m.values.numbers = {{"c1", 10206.9}, {"k1", 1.7e3}, {"k2", 20.0}, {"k", k}, {"density", 1050}};
  m.values.vectors["fibres"] = {tactus::Vec3{std::cos(theta), std::sin(theta), 0}, tactus::Vec3{std::cos(theta), -std::sin(theta), 0}};
  sc.materials["tissue"] = m;
  return sc;
}

}  // namespace

// Oracle: PrincipalHgo above. Tolerance 1e-6 relative to the largest |sigma_xx| of the curve
// (both sides converge their lateral stresses to ~1e-9 of the moduli).
TEST(Materials, HgoUniaxialCurveAlongAcrossAndOblique) {
  for (double theta : {0.0, 0.5236, 1.5708}) {  // along the fibres, +-30 deg, across
    const double k = 1.0e6;
    const Scenario sc = hgo_scenario(theta, k);
    const auto rows = parse_csv(material_point_csv(sc, "tissue", "uniaxial", 1.15, 15));
    const PrincipalHgo ref{10206.9, 1.7e3, 20.0, k, theta};
    double peak = 0;
    for (const auto& r : rows) peak = std::max(peak, std::abs(r[4]));
    ASSERT_GT(peak, 0);
    for (const auto& r : rows) {
      EXPECT_NEAR(r[4], ref.uniaxial(r[0]), 1e-6 * peak) << "theta " << theta << " stretch " << r[0];
      EXPECT_NEAR(r[5], 0.0, 1e-6 * peak);  // lateral stresses solved to zero
      EXPECT_NEAR(r[6], 0.0, 1e-6 * peak);
    }
  }
  // Along the fibres the response is much stiffer than across (fibres slack when crossed).
  const auto along = parse_csv(material_point_csv(hgo_scenario(0.0, 1e6), "tissue", "uniaxial", 1.15, 3));
  const auto across = parse_csv(material_point_csv(hgo_scenario(1.5708, 1e6), "tissue", "uniaxial", 1.15, 3));
  EXPECT_GT(along.back()[4], 3 * across.back()[4]);
}

// Oracle: simple shear keeps J = 1, so the neo-Hookean sigma = mu dev(F F^T) gives in closed form
// sigma_xy = mu gamma and sigma_xx - sigma_yy = mu gamma^2.
TEST(Materials, NeoHookeanSimpleShearClosedForm) {
  Scenario sc;
  sc.materials["rubber"] = MaterialInstance{"rubber", "neo_hookean", {{{"mu", 3000.0}, {"bulk", 50000.0}, {"density", 1000}}, {}}};
  const auto rows = parse_csv(material_point_csv(sc, "rubber", "shear", 0.5, 5));
  for (const auto& r : rows) {
    const double g = r[0];
    EXPECT_NEAR(r[7], 3000.0 * g, 1e-9 * 3000.0);
    EXPECT_NEAR(r[4] - r[5], 3000.0 * g * g, 1e-9 * 3000.0);
  }
}

// Mooney-Rivlin, added as one file and one registration line (docs/adding-a-material.md).
// Oracles: with c01 = 0 it is neo_hookean with mu = 2 c10 (to round-off); in simple shear (J = 1)
// the closed form sigma_xy = 2 (c10 + c01) gamma holds at every gamma (the I1 and I2 terms are
// both linear in gamma there), and sigma_xx - sigma_yy = 2 c10 gamma^2 - ... is checked through
// the same material-point driver users call.
TEST(Materials, MooneyRivlinReducesToNeoHookeanAndShearsInClosedForm) {
  std::mt19937 rng(7);
  const Material mr = law("mooney_rivlin", {{"c10", 1500.0}, {"c01", 0.0}, {"bulk", 5.0e4}, {"density", 1000}});
  const Material nh = neo_hookean(3000.0, 5.0e4, 1000);
  for (int trial = 0; trial < 20; ++trial) {
    const Mat3 F = random_F(rng, 0.2);
    EXPECT_LE((mr.evaluate(F).P - nh.evaluate(F).P).norm(), 1e-12 * nh.evaluate(F).P.norm());
    EXPECT_NEAR(mr.evaluate(F).W, nh.evaluate(F).W, 1e-12 * std::abs(nh.evaluate(F).W) + 1e-15);
  }
  Scenario sc;
  sc.materials["skin"] = MaterialInstance{"skin", "mooney_rivlin", {{{"c10", 2000.0}, {"c01", 800.0}, {"bulk", 1e6}, {"density", 1000}}, {}}};
  const auto rows = parse_csv(material_point_csv(sc, "skin", "shear", 0.6, 6));
  for (const auto& r : rows) {
    const double g = r[0];
    // Simple shear F = I + g e_x (x) e_y: B = F F^T, sigma = 2 (c10 + c01 I1) B - 2 c01 B^2 + p I,
    // so sigma_xy = 2 (c10 + c01 I1) g - 2 c01 (B^2)_xy with I1 = 3 + g^2 and (B^2)_xy = g (2 + g^2).
    const double expected = 2 * (2000.0 + 800.0 * (3 + g * g)) * g - 2 * 800.0 * g * (2 + g * g);
    EXPECT_NEAR(r[7], expected, 1e-9 * 2800.0) << "gamma " << g;
    EXPECT_NEAR(r[7], 2 * (2000.0 + 800.0) * g, 1e-9 * 2800.0);  // which is 2 (c10 + c01) g
  }
  std::printf("mooney_rivlin: shear stress at gamma 0.6: %.6f Pa (2 (c10 + c01) gamma = %.6f)\n", rows.back()[7], 2 * 2800.0 * 0.6);
}

// Oracle: the hgo law's own stress with and without its fibres (k1 = 0): the result field
// fibre_stress must be their difference, sigma(k1) - sigma(0), at a general deformation that
// stretches one family (J != 1), and fibre_stretch_isochoric must be J^(-1/3) |F a|.
TEST(Materials, HgoFibreOutputsAreTheFibreTerms) {
  const std::vector<tactus::Vec3> fibres{{1, 0, 0}, {0, 1, 0}};
  const Material with = law("hgo", {{"c1", 1e4}, {"k1", 2e4}, {"k2", 5.0}, {"k", 1e6}, {"density", 1000}}, fibres);
  const Material without = law("hgo", {{"c1", 1e4}, {"k1", 0.0}, {"k2", 5.0}, {"k", 1e6}, {"density", 1000}}, fibres);
  Mat3 F;
  F << 1.12, 0.03, -0.02, 0.01, 0.95, 0.04, 0.02, -0.01, 0.97;
  const Mat3 expected = cauchy_stress(F, first_piola(with, F)) - cauchy_stress(F, first_piola(without, F));
  const MaterialType& t = with.type();
  std::size_t n = 0;
  for (const auto& f : t.result_fields) n += static_cast<std::size_t>(f.components);
  ASSERT_EQ(n, 10u);  // fibre_stretch (2), fibre_stretch_isochoric (2), fibre_stress (6)
  std::vector<double> out(n);
  t.result_values(with.law(), F, with.constant_element_data().data(), out.data());
  const double J = F.determinant();
  EXPECT_NEAR(out[2], std::cbrt(1 / J) * (F * Vec3d(1, 0, 0)).norm(), 1e-14);
  EXPECT_NEAR(out[3], std::cbrt(1 / J) * (F * Vec3d(0, 1, 0)).norm(), 1e-14);
  const double voigt[6] = {expected(0, 0), expected(1, 1), expected(2, 2), expected(0, 1), expected(1, 2), expected(0, 2)};
  double worst = 0;
  for (int k = 0; k < 6; ++k) worst = std::max(worst, std::abs(out[4 + k] - voigt[k]));
  std::printf("hgo fibre stress: sigma_f,xx %.6e Pa (sigma(k1) - sigma(0): %.6e), largest difference %.2e Pa; isochoric stretches %.6f %.6f\n",
              out[4], voigt[0], worst, out[2], out[3]);
  EXPECT_GT(std::abs(voigt[0]), 100.0);  // the stretched family carries load
  EXPECT_LE(worst, 1e-9 * std::abs(voigt[0]));
}

// Oracle: hgo with k1 = 0 is the neo-Hookean law with mu = 2 c1 and bulk k at any stretch; at a
// fibre stretch of 1.6 (exp(k2 (J4bar - 1)^2) overflows a double) its stress must stay finite and
// equal to neo-Hookean's (it was NaN: 0 * inf).
TEST(Materials, HgoWithoutFibreStiffnessIsNeoHookeanAtAnyStretch) {
  const Material hgo = law("hgo", {{"c1", 1e4}, {"k1", 0.0}, {"k2", 882.847}, {"k", 1e6}, {"density", 1000}}, {{1, 0, 0}, {0, 1, 0}});
  const Material nh = neo_hookean(2e4, 1e6, 1000);
  Mat3 F = Mat3::Identity();
  F(0, 0) = 1.6, F(1, 1) = 0.8, F(2, 2) = 0.8, F(0, 1) = 0.1;
  const Mat3 P = first_piola(hgo, F), Q = first_piola(nh, F);
  std::printf("hgo k1 = 0 at a fibre stretch of 1.6: |P - P_neo-Hookean| = %.2e of |P| = %.4e Pa\n", (P - Q).norm() / Q.norm(), Q.norm());
  ASSERT_TRUE(P.allFinite());
  EXPECT_LE((P - Q).norm(), 1e-12 * Q.norm());
}
