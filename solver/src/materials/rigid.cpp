// rigid: a material group (or a whole body, "*" = ...) that moves as rigid bodies, one per
// connected piece of its tets (time/rigid.cpp): six degrees of freedom each, mass and inertia from
// the tets and this density. Its tets carry no stress and do not limit the time step; the
// deformable tets around them are tied to them through the nodes they share.
#include "law.hpp"

namespace tactus::solver {
namespace {

struct Rigid {
  static constexpr const char* kName = "rigid";
  static constexpr bool kRigid = true;
  static constexpr const char* kDoc =
      "Rigid: each connected piece of these tets is one rigid body (6 degrees of freedom; mass, centre and inertia from the "
      "tets); no stress, no limit on the time step.";
  double density = 0;

  static std::vector<LawParameter<Rigid>> parameters() { return {{&Rigid::density, number("density", "kg/m^3", "mass density", 0, true)}}; }
  double small_strain_bulk() const { return 0; }
  double small_strain_shear() const { return 0; }
  template <class T>
  TACTUS_KERNEL_INLINE LawStress<T> evaluate(const M3<T>&, const M3<T>&, const T&, const T*) const {
    const T zero = lanes::splat<T>(0.0);
    return {lanes::identity_times(zero), zero, zero};
  }
};

}  // namespace
}  // namespace tactus::solver

TACTUS_MATERIAL(Rigid)
