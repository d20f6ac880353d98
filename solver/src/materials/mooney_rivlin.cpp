// mooney_rivlin: the compressible (decoupled) Mooney-Rivlin law,
//   W = c10 (I1bar - 3) + c01 (I2bar - 3) + K/2 (J - 1)^2,
//   I1bar = J^{-2/3} I1, I2bar = J^{-4/3} I2, I2 = (I1^2 - tr C^2) / 2.
// With dI1/dF = 2F, dI2/dF = 2 (I1 F - F F^T F) and dJ/dF = cof(F):
//   P = c10 J^{-2/3} (2F - 2/3 I1 cof/J) + c01 J^{-4/3} (2 (I1 F - F F^T F) - 4/3 I2 cof/J) + K (J - 1) cof.
// Small-strain shear modulus 2 (c10 + c01); with c01 = 0 it is neo_hookean with mu = 2 c10.
// (Added as the worked example of docs/adding-a-material.md: this file and one registry line.)
#include "law.hpp"

namespace tactus::solver {
namespace {

struct MooneyRivlin {
  static constexpr const char* kName = "mooney_rivlin";
  static constexpr const char* kDoc = "Compressible Mooney-Rivlin: W = c10 (I1bar - 3) + c01 (I2bar - 3) + bulk/2 (J - 1)^2.";
  double c10 = 0, c01 = 0, bulk = 0, density = 0;

  static std::vector<LawParameter<MooneyRivlin>> parameters() {
    return {{&MooneyRivlin::c10, number("c10", "Pa", "first-invariant coefficient", 0, false)},
            {&MooneyRivlin::c01, number("c01", "Pa", "second-invariant coefficient", 0, false)},
            {&MooneyRivlin::bulk, number("bulk", "Pa", "bulk modulus", 0, true)},
            {&MooneyRivlin::density, number("density", "kg/m^3", "mass density in the reference configuration", 0, true)}};
  }
  void finish(const MaterialValues& v, const std::string& where, std::vector<double>&) const {
    if (!(c10 + c01 > 0)) throw InputError(v.source, where, "c10 + c01 > 0 (a positive shear modulus)", "0");
  }
  double small_strain_bulk() const { return bulk; }
  double small_strain_shear() const { return 2.0 * (c10 + c01); }

  template <class T>
  TACTUS_KERNEL_INLINE LawStress<T> evaluate_isochoric(const M3<T>& F, const M3<T>& cof, const T& J, const T* /*data*/) const {
    const M3<T> C = lanes::transpose_times(F, F);
    const T I1 = lanes::trace(C);
    const T I2 = 0.5 * (I1 * I1 - lanes::squared_norm(C));
    const T Jm23 = lanes::inv_cbrt(J * J), Jm43 = Jm23 * Jm23;
    LawStress<T> s;
    s.P = (2.0 * c10 * Jm23) * F + (2.0 * c01 * Jm43) * (I1 * F - F * C) -
          ((2.0 / 3.0) * c10 * Jm23 * I1 / J + (4.0 / 3.0) * c01 * Jm43 * I2 / J) * cof;
    s.W = c10 * (Jm23 * I1 - 3.0) + c01 * (Jm43 * I2 - 3.0);
    s.modulus = lanes::splat<T>(bulk + 4.0 * small_strain_shear() / 3.0);
    return s;
  }
  template <class T>
  T volumetric_energy(const T& J) const {
    return penalty_energy(bulk, J);
  }
  template <class T>
  T volumetric_pressure(const T& J) const {
    return penalty_pressure(bulk, J);
  }
};

}  // namespace
}  // namespace tactus::solver

TACTUS_MATERIAL(MooneyRivlin)
