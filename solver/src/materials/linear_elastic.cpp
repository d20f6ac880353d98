// linear_elastic: St Venant-Kirchhoff ("linear elastic" in the paper's sense: S linear in E in
// the total-Lagrangian frame), S = lambda tr(E) I + 2 mu E, W = lambda/2 tr(E)^2 + mu E:E; bone
// (paper §3.2: E = 10 GPa, nu = 0.22) and the block.
#include "law.hpp"

namespace tactus::solver {
namespace {

struct LinearElastic {
  static constexpr const char* kName = "linear_elastic";
  static constexpr const char* kDoc = "St Venant-Kirchhoff (linear S(E) in the total-Lagrangian frame); bone, the block.";
  double youngs = 0, poisson = 0, density = 0;
  double lambda = 0, mu = 0;  // derived (finish)

  static std::vector<LawParameter<LinearElastic>> parameters() {
    return {{&LinearElastic::youngs, number("E", "Pa", "Young's modulus", 0, true)},
            {&LinearElastic::poisson, number("nu", "", "Poisson's ratio", -1, true, 0.5, true)},
            {&LinearElastic::density, number("density", "kg/m^3", "mass density in the reference configuration", 0, true)}};
  }
  void finish(const MaterialValues&, const std::string&, std::vector<double>&) {
    mu = youngs / (2.0 * (1.0 + poisson));
    lambda = youngs * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson));
  }
  double small_strain_bulk() const { return lambda + 2.0 * mu / 3.0; }
  double small_strain_shear() const { return mu; }

  template <class T>
  TACTUS_KERNEL_INLINE LawStress<T> evaluate(const M3<T>& F, const M3<T>& /*cof*/, const T& /*J*/, const T* /*data*/) const {
    const M3<T> E = 0.5 * (lanes::transpose_times(F, F) - lanes::identity_times(lanes::splat<T>(1.0)));
    const T trE = lanes::trace(E);
    const M3<T> S = (2.0 * mu) * E + lanes::identity_times<T>(lambda * trE);
    LawStress<T> s;
    s.P = F * S;
    s.W = 0.5 * lambda * trE * trE + mu * lanes::squared_norm(E);
    s.modulus = lanes::splat<T>(lambda + 2.0 * mu);
    return s;
  }
};

}  // namespace
}  // namespace tactus::solver

TACTUS_MATERIAL(LinearElastic)
