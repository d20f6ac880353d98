// The material-point driver (tactus-solve material-point): homogeneous deformations of one
// material point, for users fitting parameters. Lateral stretches are found by Newton iteration
// (finite-difference Jacobian) so the lateral Cauchy stresses vanish.
#include <Eigen/Dense>
#include <iomanip>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/solver/material.hpp"
#include "tactus/solver/run.hpp"

namespace tactus::solver {

namespace {

Mat3 cauchy_of(const Material& mat, const Mat3& F) { return cauchy_stress(F, mat.evaluate(F).P); }

// Solves for the free diagonal stretches (indices in `free`) so that sigma_ii = 0 there.
Mat3 relax_lateral(const Material& mat, Mat3 F, const std::vector<int>& free, double stress_scale) {
  const int n = static_cast<int>(free.size());
  for (int it = 0; it < 60; ++it) {
    const Mat3 s = cauchy_of(mat, F);
    Eigen::VectorXd r(n);
    for (int k = 0; k < n; ++k) r[k] = s(free[k], free[k]);
    if (r.norm() <= 1e-12 * stress_scale) return F;
    Eigen::MatrixXd Jac(n, n);
    for (int k = 0; k < n; ++k) {
      Mat3 Fp = F;
      const double h = 1e-7 * F(free[k], free[k]);
      Fp(free[k], free[k]) += h;
      const Mat3 sp = cauchy_of(mat, Fp);
      for (int l = 0; l < n; ++l) Jac(l, k) = (sp(free[l], free[l]) - s(free[l], free[l])) / h;
    }
    const Eigen::VectorXd d = Jac.fullPivLu().solve(-r);
    for (int k = 0; k < n; ++k) {
      double step = d[k];
      const double cap = 0.2 * F(free[k], free[k]);  // keep stretches positive
      step = std::clamp(step, -cap, cap);
      F(free[k], free[k]) += step;
    }
  }
  throw NumericalError("material-point: lateral stresses did not converge to zero (is the material stable here?)");
}

}  // namespace

std::string material_point_csv(const Scenario& sc, const std::string& name, const std::string& mode, double max_value, int samples) {
  auto it = sc.materials.find(name);
  if (it == sc.materials.end()) {
    std::string known;
    for (const auto& [n, m] : sc.materials) known += (known.empty() ? "" : ", ") + n;
    throw InputError(sc.file.string(), "--material", "a material of the scenario (" + known + ")", "\"" + name + "\"");
  }
  const Material mat = Material::make(it->second.type, it->second.values, "materials." + name);
  if (mat.needs_element_data())
    throw InputError(sc.file.string(), "materials." + name, "the material's own element data (hgo: its fibres) for a material point",
                     "none: its elements take theirs from a file");
  if (mode != "uniaxial" && mode != "equibiaxial" && mode != "shear")
    throw InputError("command line", "--mode", "uniaxial, equibiaxial or shear", "\"" + mode + "\"");
  if (samples < 1) throw InputError("command line", "--samples", "at least 1", std::to_string(samples));
  if (mode != "shear" && !(max_value > 0)) throw InputError("command line", "--max", "a stretch > 0", std::to_string(max_value));
  const double scale = mat.small_strain_bulk() + mat.small_strain_shear();
  std::ostringstream o;
  o << std::setprecision(10);
  o << (mode == "shear" ? "gamma" : "stretch") << ",F_xx,F_yy,F_zz,sigma_xx,sigma_yy,sigma_zz,sigma_xy,sigma_yz,sigma_xz\n";
  Mat3 F = Mat3::Identity();
  for (int k = 0; k <= samples; ++k) {
    const double start = mode == "shear" ? 0.0 : 1.0;
    const double value = start + (max_value - start) * k / samples;
    if (mode == "shear") {
      F = Mat3::Identity();
      F(0, 1) = value;
    } else if (mode == "uniaxial") {
      F(0, 0) = value;
      F = relax_lateral(mat, F, {1, 2}, scale);
    } else {
      F(0, 0) = F(1, 1) = value;
      F = relax_lateral(mat, F, {2}, scale);
    }
    const Mat3 s = cauchy_of(mat, F);
    o << value << ',' << F(0, 0) << ',' << F(1, 1) << ',' << F(2, 2) << ',' << s(0, 0) << ',' << s(1, 1) << ',' << s(2, 2) << ',' << s(0, 1) << ','
      << s(1, 2) << ',' << s(0, 2) << '\n';
  }
  return o.str();
}

}  // namespace tactus::solver
