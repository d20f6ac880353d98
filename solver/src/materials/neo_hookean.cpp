// neo_hookean: compressible neo-Hookean, W = mu/2 (I1bar - 3) + K/2 (J - 1)^2. The hgo law with
// k1 = 0 and c1 = mu/2 reduces to it, which the tests use as a cross-check.
#include "law.hpp"

namespace tactus::solver {
namespace {

struct NeoHookean {
  static constexpr const char* kName = "neo_hookean";
  double mu = 0, bulk = 0, density = 0;

  static SectionSpec parameters() {
    return {"",
            "Compressible neo-Hookean: W = mu/2 (I1bar - 3) + bulk/2 (J - 1)^2.",
            {number("mu", "Pa", "shear modulus", 0, true), number("bulk", "Pa", "bulk modulus", 0, true),
             number("density", "kg/m^3", "mass density in the reference configuration", 0, true)}};
  }
  static NeoHookean create(const MaterialValues& v, const std::string&, std::vector<double>&) {
    return {parameter(v, "mu"), parameter(v, "bulk"), parameter(v, "density")};
  }
  double small_strain_bulk() const { return bulk; }
  double small_strain_shear() const { return mu; }

  // The isochoric part: P = mu J^{-2/3} (F - I1/3 F^{-T}), F^{-T} = cof / J.
  TACTUS_KERNEL_INLINE StressPoint evaluate_isochoric(const Mat3& F, const Mat3& cof, double J, const double* /*data*/) const {
    const double I1 = F.squaredNorm();
    const double Jm23 = inv_cbrt(J * J);
    StressPoint s;
    s.P = (mu * Jm23) * F - (mu * Jm23 * I1 / (3.0 * J)) * cof;
    s.W = 0.5 * mu * (Jm23 * I1 - 3.0);
    s.modulus = bulk + 4.0 * mu / 3.0;
    return s;
  }
  double volumetric_energy(double J) const { return 0.5 * bulk * (J - 1.0) * (J - 1.0); }
  double volumetric_pressure(double J) const { return bulk * (J - 1.0); }
};

}  // namespace
}  // namespace tactus::solver

TACTUS_MATERIAL(NeoHookean)
