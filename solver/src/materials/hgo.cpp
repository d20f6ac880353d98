// hgo: Holzapfel-Gasser-Ogden with two fibre families (paper eqs. 20-26):
//   W = c1 (I1bar - 3) + sum_a k1/(2 k2) [exp(k2 (J4bar_a - 1)^2) - 1] + k/2 (J - 1)^2,
//   I1bar = I1 I3^{-1/3}, J4bar_a = J4_a I3^{-1/3}, J4_a = |F a_a|^2 (eq. 17).
// Fibres bear load only in tension. The tension switch tests J4bar (the isochoric fibre stretch),
// as FEBio does, so a fibre is slack whenever its isochoric stretch is <= 1. Differentiating
// (eq. 25 with dI1bar/dC = J^{-2/3}(I - I1/3 C^{-1}) etc.) and pushing by F:
//   P = 2 c1 J^{-2/3} (F - I1/3 F^{-T}) + sum_a 2 psi'_a J^{-2/3} ((F a) (x) a - J4_a/3 F^{-T})
//       + k (J - 1) J F^{-T},   psi'(x) = k1 (x - 1) exp(k2 (x - 1)^2) for x > 1, else 0.
// Per-element data: the two unit fibre directions a_1, a_2 in the reference configuration, from
// the material's `fibres` or, per tet, from the cell fields fibre_1, fibre_2 of bodies.fibres.
#include <sstream>

#include "law.hpp"

namespace tactus::solver {
namespace {

// A unit vector from `a` (3 values); a zero vector is an error naming `file` and `where`.
void unit(const double* a, double* out, const std::string& file, const std::string& where) {
  const double len = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  if (!(len > 1e-12)) throw InputError(file, where, "a non-zero direction", "zero vector");
  for (int c = 0; c < 3; ++c) out[c] = a[c] / len;
}

struct Hgo {
  static constexpr const char* kName = "hgo";
  static constexpr std::size_t kElementData = 6;  // a_1, a_2
  static constexpr bool kElementDataAreDirections = true;
  static constexpr const char* kDoc = "Holzapfel-Gasser-Ogden with two fibre families (paper eqs. 20-26); fibres carry load only in tension.";
  double c1 = 0, k1 = 0, k2 = 0, k = 0, density = 0;

  static std::vector<LawParameter<Hgo>> parameters() {
    return {{&Hgo::c1, number("c1", "Pa", "matrix shear parameter (shear modulus = 2 c1)", 0, true)},
            {&Hgo::k1, number("k1", "Pa", "fibre stiffness", 0, false)},
            {&Hgo::k2, number("k2", "", "fibre exponential stiffening", 0, true)},
            {&Hgo::k, number("k", "Pa", "bulk (volumetric penalty) modulus in k/2 (J-1)^2", 0, true)},
            {&Hgo::density, number("density", "kg/m^3", "mass density in the reference configuration", 0, true)}};
  }
  static std::vector<ValueSpec> extra_keys() {
    ValueSpec fibres;
    fibres.key = "fibres";
    fibres.type = ValueType::vec3_list;
    fibres.doc =
        "the two fibre directions a_1, a_2 in the reference frame (normalised); required unless every body "
        "using the material gives per-element fibres";
    return {fibres};
  }
  // The material's own fibre directions (when it gives them) as its constant element data.
  void finish(const MaterialValues& v, const std::string& where, std::vector<double>& constants) const {
    auto it = v.vectors.find("fibres");
    if (it == v.vectors.end()) return;
    const auto& f = it->second;
    if (f.size() != 2)
      throw InputError(v.source, where + ".fibres", "two fibre directions [[ax, ay, az], [bx, by, bz]] (the paper gives none: choose them)",
                       std::to_string(f.size()) + " directions");
    constants.resize(6);
    for (int i = 0; i < 2; ++i) unit(f[i].data(), constants.data() + 3 * i, v.source, where + ".fibres[" + std::to_string(i) + "]");
  }
  static std::vector<std::pair<std::string, int>> element_fields() { return {{"fibre_1", 3}, {"fibre_2", 3}}; }
  static void element_data_from_fields(const double* fields, double* data, const std::string& where) {
    unit(fields, data, where, "fibre_1");
    unit(fields + 3, data + 3, where, "fibre_2");
  }
  static std::vector<ResultFieldSpec> result_fields() {
    return {{"fibre_stretch", 2, "stretch |F a| of the two fibre families (hgo; 0 elsewhere)"},
            {"fibre_stretch_isochoric", 2,
             "isochoric stretch sqrt(J4bar) = J^(-1/3) |F a| of the two families: the one the law acts on (load only above 1; hgo; 0 elsewhere)"},
            {"fibre_stress", 6, "Cauchy stress of the fibre terms alone (xx, yy, zz, xy, yz, xz; Pa; hgo; 0 elsewhere)"}};
  }
  // A fibre's slope psi'(J4bar) = k1 d exp(k2 d^2), d = J4bar - 1, with e = exp(k2 d^2); false when
  // it carries nothing: slack in compression (switch on J4bar, as FEBio), or k1 = 0 (its exp
  // would overflow at large stretch and 0 * inf poison the stress with NaN).
  TACTUS_KERNEL_INLINE bool fibre_slope(double J4bar, double& dpsi, double& e) const {
    if (J4bar <= 1.0 || k1 == 0.0) return false;
    const double d = J4bar - 1.0;
    e = std::exp(k2 * d * d);
    dpsi = k1 * d * e;
    return true;
  }

  // sigma_f = sum_a 2 psi'_a J^{-5/3} (F a (x) F a - J4_a / 3 I): the fibre terms of P pushed forward.
  void result_values(const Mat3& F, const double* data, double* out) const {
    const double J = F.determinant(), Jm13 = lanes::inv_cbrt(J);
    Mat3 sigma = Mat3::Zero();
    for (int f = 0; f < 2; ++f) {
      const Vec3d Fa = F * Vec3d(data + 3 * f);
      const double J4 = Fa.squaredNorm(), J4bar = Jm13 * Jm13 * J4;
      out[f] = std::sqrt(J4);
      out[2 + f] = std::sqrt(J4bar);
      double dpsi = 0, e = 0;
      if (!fibre_slope(J4bar, dpsi, e)) continue;
      sigma += (2.0 * dpsi * Jm13 * Jm13 / J) * (Fa * Fa.transpose() - J4 / 3.0 * Mat3::Identity());
    }
    const double voigt[6] = {sigma(0, 0), sigma(1, 1), sigma(2, 2), sigma(0, 1), sigma(1, 2), sigma(0, 2)};
    for (int c = 0; c < 6; ++c) out[4 + c] = voigt[c];
  }
  double small_strain_bulk() const { return k; }
  double small_strain_shear() const { return 2.0 * c1; }

  template <class T>
  T volumetric_energy(const T& J) const {
    return penalty_energy(k, J);
  }
  template <class T>
  T volumetric_pressure(const T& J) const {
    return penalty_pressure(k, J);
  }

  // Everything but the volumetric term k/2 (J - 1)^2 (the fibre terms use J4bar: isochoric).
  // The fibre switch is a per-lane select: a slack fibre (J4bar <= 1) gets d = 0, which makes its
  // psi', energy and (through `taut`) tangent zero, as fibre_slope's early return does.
  template <class T>
  TACTUS_KERNEL_INLINE LawStress<T> evaluate_isochoric(const M3<T>& F, const M3<T>& cof, const T& J, const T* data) const {
    const T zero = lanes::splat<T>(0.0);
    const T I1 = lanes::squared_norm(F);
    const T Jm23 = lanes::inv_cbrt(J * J);
    const T inv_J = 1.0 / J;  // one division: they cost most in a vector
    LawStress<T> s;
    T cof_coeff = (-2.0 / 3.0) * c1 * Jm23 * I1 * inv_J;
    s.P = (2.0 * c1 * Jm23) * F;
    s.W = c1 * (Jm23 * I1 - 3.0);
    T fibre_modulus = zero;
    if (k1 != 0.0)  // with k1 = 0 a fibre's exp could overflow and 0 * inf poison the stress
      for (int f = 0; f < 2; ++f) {
        const V3<T> a{{data[3 * f], data[3 * f + 1], data[3 * f + 2]}};
        const V3<T> Fa = F * a;
        const T J4 = lanes::squared_norm(Fa);
        const T J4bar = Jm23 * J4;
        const auto taut = J4bar > 1.0;
        const T d = taut ? J4bar - 1.0 : zero;
        const T e = lanes::exp_of(k2 * d * d);
        const T dpsi = k1 * d * e;                                        // dW/dJ4bar
        const T d2psi = taut ? k1 * e * (1.0 + 2.0 * k2 * d * d) : zero;  // d2W/dJ4bar2
        s.P += (2.0 * dpsi * Jm23) * lanes::outer(Fa, a);
        cof_coeff -= (2.0 / 3.0) * dpsi * Jm23 * J4 * inv_J;
        s.W += k1 / (2.0 * k2) * (e - 1.0);
        // Current tangent along the fibre, d(tau_ff)/d(ln lambda) / J = (4 psi'' J4bar^2 + 4 psi' J4bar) / J.
        fibre_modulus += (4.0 * d2psi * J4bar * J4bar + 4.0 * dpsi * J4bar) * inv_J;
      }
    s.P += cof_coeff * cof;
    s.modulus = (k + 8.0 * c1 / 3.0) + fibre_modulus;
    return s;
  }
};

}  // namespace
}  // namespace tactus::solver

TACTUS_MATERIAL(Hgo)
