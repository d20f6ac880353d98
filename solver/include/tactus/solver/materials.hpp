#pragma once
// Hyperelastic materials of the total-Lagrangian solver. A material is a strain energy W(C) and
// its stress; element integration lives elsewhere (kernels/). Each material evaluates, from the
// deformation gradient F of a one-point tet:
//   P  first Piola-Kirchhoff stress (P = F S, S = 2 dW/dC, paper eq. 18),
//   W  strain energy per reference volume,
//   M  the current P-wave modulus (Pa) for the stable time step (DESIGN: K + 4mu/3, plus the
//      fibres' current tangent stiffness for hgo).
// Adding a material: one struct here (params + spec + evaluate), one line in MaterialKind and
// in the registry/dispatch (materials.cpp, kernels).
#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <variant>

#include "tactus/solver/parameters.hpp"

namespace tactus::solver {

using Mat3 = Eigen::Matrix3d;
using Vec3d = Eigen::Vector3d;

// F^{-T} J = cof(F): the cofactor matrix, so F^{-T} = cof(F) / J without a division per entry.
inline Mat3 cofactor(const Mat3& F) {
  Mat3 c;
  c(0, 0) = F(1, 1) * F(2, 2) - F(1, 2) * F(2, 1);
  c(0, 1) = F(1, 2) * F(2, 0) - F(1, 0) * F(2, 2);
  c(0, 2) = F(1, 0) * F(2, 1) - F(1, 1) * F(2, 0);
  c(1, 0) = F(0, 2) * F(2, 1) - F(0, 1) * F(2, 2);
  c(1, 1) = F(0, 0) * F(2, 2) - F(0, 2) * F(2, 0);
  c(1, 2) = F(0, 1) * F(2, 0) - F(0, 0) * F(2, 1);
  c(2, 0) = F(0, 1) * F(1, 2) - F(0, 2) * F(1, 1);
  c(2, 1) = F(0, 2) * F(1, 0) - F(0, 0) * F(1, 2);
  c(2, 2) = F(0, 0) * F(1, 1) - F(0, 1) * F(1, 0);
  return c;
}

// x^{-1/3} for x > 0, to 1e-15 relative (measured worst 6.7e-16 over 1e-6..1e6). libm's cbrt
// (with its frexp/scalbn) took a quarter of a neo-Hookean update; this is a bit-level first guess
// refined by four division-free Newton steps on 1/y^3 = x:  y <- y (4 - x y^3) / 3.
inline double inv_cbrt(double x) {
  std::uint64_t i;
  std::memcpy(&i, &x, sizeof i);
  i = 0x553ef0ff289dd796ULL - i / 3;
  double y;
  std::memcpy(&y, &i, sizeof y);
  for (int k = 0; k < 4; ++k) y = y * (4.0 - x * y * y * y) * (1.0 / 3.0);
  return y;
}

// The per-element material evaluation must inline into the force loop.
#define TACTUS_KERNEL_INLINE [[gnu::always_inline]] inline

struct StressPoint {
  Mat3 P;
  double W = 0;
  double modulus = 0;
};

// Compressible neo-Hookean (decoupled): W = mu/2 (I1bar - 3) + K/2 (J - 1)^2.
// The hgo law with k1 = 0 and c1 = mu/2 reduces to it, which the tests use as a cross-check.
struct NeoHookean {
  double mu = 0, bulk = 0, density = 0;
  static const SectionSpec& spec();
  static NeoHookean from(const std::map<std::string, double>& p) { return {p.at("mu"), p.at("bulk"), p.at("density")}; }
  double small_strain_bulk() const { return bulk; }
  double small_strain_shear() const { return mu; }

  StressPoint evaluate(const Mat3& F) const {
    const Mat3 cof = cofactor(F);
    return evaluate(F, cof, F.row(0).dot(cof.row(0)));
  }
  TACTUS_KERNEL_INLINE StressPoint evaluate(const Mat3& F, const Mat3& cof, double J) const {
    const double I1 = F.squaredNorm();
    const double Jm23 = inv_cbrt(J * J);
    // P = mu J^{-2/3} (F - I1/3 F^{-T}) + K (J - 1) J F^{-T},  F^{-T} = cof / J
    StressPoint s;
    s.P = (mu * Jm23) * F + (bulk * (J - 1.0) - mu * Jm23 * I1 / (3.0 * J)) * cof;
    s.W = 0.5 * mu * (Jm23 * I1 - 3.0) + 0.5 * bulk * (J - 1.0) * (J - 1.0);
    s.modulus = bulk + 4.0 * mu / 3.0;
    return s;
  }
};

// St Venant-Kirchhoff ("linear_elastic" in the paper's sense: linear S(E) in the TL frame):
// S = lambda tr(E) I + 2 mu E, W = lambda/2 tr(E)^2 + mu E:E. Parameters E, nu as for bone.
struct LinearElastic {
  double youngs = 0, poisson = 0, density = 0;
  double lambda = 0, mu = 0;
  static const SectionSpec& spec();
  static LinearElastic from(const std::map<std::string, double>& p) {
    LinearElastic m{p.at("E"), p.at("nu"), p.at("density")};
    m.mu = m.youngs / (2.0 * (1.0 + m.poisson));
    m.lambda = m.youngs * m.poisson / ((1.0 + m.poisson) * (1.0 - 2.0 * m.poisson));
    return m;
  }
  double small_strain_bulk() const { return lambda + 2.0 * mu / 3.0; }
  double small_strain_shear() const { return mu; }

  TACTUS_KERNEL_INLINE StressPoint evaluate(const Mat3& F, const Mat3& /*cof*/, double /*J*/) const { return evaluate(F); }
  TACTUS_KERNEL_INLINE StressPoint evaluate(const Mat3& F) const {
    const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
    const double trE = E.trace();
    const Mat3 S = lambda * trE * Mat3::Identity() + 2.0 * mu * E;
    StressPoint s;
    s.P = F * S;
    s.W = 0.5 * lambda * trE * trE + mu * E.squaredNorm();
    s.modulus = lambda + 2.0 * mu;
    return s;
  }
};

// Holzapfel-Gasser-Ogden, two fibre families (paper eqs. 20-26):
//   W = c1 (I1bar - 3) + sum_a k1/(2 k2) [exp(k2 (J4bar_a - 1)^2) - 1] + k/2 (J - 1)^2,
//   I1bar = I1 I3^{-1/3}, J4bar_a = J4_a I3^{-1/3}, J4_a = |F a_a|^2 (eq. 17).
// Fibres bear load only in tension. The tension switch tests J4bar (the isochoric fibre
// stretch), as FEBio does, so a fibre is slack whenever its isochoric stretch is <= 1.
// Differentiating (eq. 25 with dI1bar/dC = J^{-2/3}(I - I1/3 C^{-1}) etc.) and pushing by F:
//   P = 2 c1 J^{-2/3} (F - I1/3 F^{-T}) + sum_a 2 psi'_a J^{-2/3} ((F a) (x) a - J4_a/3 F^{-T})
//       + k (J - 1) J F^{-T},   psi'(x) = k1 (x - 1) exp(k2 (x - 1)^2) for x > 1, else 0.
struct Hgo {
  double c1 = 0, k1 = 0, k2 = 0, k = 0, density = 0;
  Vec3d a1{1, 0, 0}, a2{0, 1, 0};  // unit fibre directions in the reference configuration
  static const SectionSpec& spec();
  static Hgo from(const std::map<std::string, double>& p) {
    return {p.at("c1"), p.at("k1"), p.at("k2"), p.at("k"), p.at("density"), {1, 0, 0}, {0, 1, 0}};
  }
  double small_strain_bulk() const { return k; }
  double small_strain_shear() const { return 2.0 * c1; }

  StressPoint evaluate(const Mat3& F) const {
    const Mat3 cof = cofactor(F);
    return evaluate(F, cof, F.row(0).dot(cof.row(0)));
  }
  TACTUS_KERNEL_INLINE StressPoint evaluate(const Mat3& F, const Mat3& cof, double J) const {
    return evaluate(F, cof, J, a1, a2);
  }
  // With per-element fibre directions f1, f2 (unit vectors, reference configuration).
  TACTUS_KERNEL_INLINE StressPoint evaluate(const Mat3& F, const Mat3& cof, double J, const Vec3d& f1,
                                            const Vec3d& f2) const {
    const double I1 = F.squaredNorm();
    const double Jm23 = inv_cbrt(J * J);
    StressPoint s;
    double cof_coeff = k * (J - 1.0) - 2.0 * c1 * Jm23 * I1 / (3.0 * J);
    s.P = (2.0 * c1 * Jm23) * F;
    s.W = c1 * (Jm23 * I1 - 3.0) + 0.5 * k * (J - 1.0) * (J - 1.0);
    double fibre_modulus = 0;
    const Vec3d* dirs[2] = {&f1, &f2};
    for (const Vec3d* a : dirs) {
      const Vec3d Fa = F * (*a);
      const double J4 = Fa.squaredNorm();
      const double J4bar = Jm23 * J4;
      if (J4bar <= 1.0) continue;  // slack in compression (switch on J4bar, as FEBio)
      const double d = J4bar - 1.0;
      const double e = std::exp(k2 * d * d);
      const double dpsi = k1 * d * e;                        // dW/dJ4bar
      const double d2psi = k1 * e * (1.0 + 2.0 * k2 * d * d);  // d2W/dJ4bar2
      s.P.noalias() += (2.0 * dpsi * Jm23) * Fa * a->transpose();
      cof_coeff -= 2.0 * dpsi * Jm23 * J4 / (3.0 * J);
      s.W += k1 / (2.0 * k2) * (e - 1.0);
      // Current tangent along the fibre, d(tau_ff)/d(ln lambda) / J = (4 psi'' J4bar^2 + 4 psi' J4bar) / J.
      fibre_modulus += (4.0 * d2psi * J4bar * J4bar + 4.0 * dpsi * J4bar) / J;
    }
    s.P += cof_coeff * cof;
    s.modulus = k + 8.0 * c1 / 3.0 + fibre_modulus;
    return s;
  }
};

enum class MaterialKind { neo_hookean, linear_elastic, hgo };

using Material = std::variant<NeoHookean, LinearElastic, Hgo>;

// Every registered material: its name (the scenario's `type`) and parameter declarations.
struct MaterialEntry {
  MaterialKind kind;
  const char* name;
  const SectionSpec& (*spec)();
};
const std::vector<MaterialEntry>& material_registry();

// Builds a material of the named type from validated parameters.
Material make_material(const std::string& type, const std::map<std::string, double>& params);
const char* material_type_name(const Material& m);
double material_density(const Material& m);
// Small-strain moduli, used for Rayleigh stiffness damping and the initial stable step.
double material_bulk(const Material& m);
double material_shear(const Material& m);

// Cauchy stress sigma = F S F^T / J = P F^T / J (paper eq. 18), and its von Mises value.
inline Mat3 cauchy_stress(const Mat3& F, const Mat3& P) { return P * F.transpose() / F.determinant(); }
inline double von_mises(const Mat3& s) {
  const double a = s(0, 0) - s(1, 1), b = s(1, 1) - s(2, 2), c = s(2, 2) - s(0, 0);
  return std::sqrt(0.5 * (a * a + b * b + c * c) + 3.0 * (s(0, 1) * s(0, 1) + s(1, 2) * s(1, 2) + s(0, 2) * s(0, 2)));
}

}  // namespace tactus::solver
