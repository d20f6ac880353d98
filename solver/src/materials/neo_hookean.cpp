// neo_hookean: compressible neo-Hookean, W = mu/2 (I1bar - 3) + K/2 (J - 1)^2. The hgo law with
// k1 = 0 and c1 = mu/2 reduces to it, which the tests use as a cross-check.
#include "law.hpp"

namespace tactus::solver {
namespace {

struct NeoHookean {
  static constexpr const char* kName = "neo_hookean";
  static constexpr const char* kDoc = "Compressible neo-Hookean: W = mu/2 (I1bar - 3) + bulk/2 (J - 1)^2.";
  double mu = 0, bulk = 0, density = 0;

  static std::vector<LawParameter<NeoHookean>> parameters() {
    return {{&NeoHookean::mu, number("mu", "Pa", "shear modulus", 0, true)},
            {&NeoHookean::bulk, number("bulk", "Pa", "bulk modulus", 0, true)},
            {&NeoHookean::density, number("density", "kg/m^3", "mass density in the reference configuration", 0, true)}};
  }
  double small_strain_bulk() const { return bulk; }
  double small_strain_shear() const { return mu; }

  // The isochoric part: P = mu J^{-2/3} (F - I1/3 F^{-T}), F^{-T} = cof / J.
  template <class T>
  TACTUS_KERNEL_INLINE LawStress<T> evaluate_isochoric(const M3<T>& F, const M3<T>& cof, const T& J, const T* /*data*/) const {
    const T I1 = lanes::squared_norm(F);
    const T Jm23 = lanes::inv_cbrt(J * J);
    LawStress<T> s;
    s.P = (mu * Jm23) * F - (mu * Jm23 * I1 / (3.0 * J)) * cof;
    s.W = 0.5 * mu * (Jm23 * I1 - 3.0);
    s.modulus = lanes::splat<T>(bulk + 4.0 * mu / 3.0);
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

TACTUS_MATERIAL(NeoHookean)
