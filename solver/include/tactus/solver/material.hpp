#pragma once
// Hyperelastic materials of the total-Lagrangian solver.
//
// A material law is one file in solver/src/materials/ plus one registration line in
// solver/src/materials/registry.cpp (docs/adding-a-material.md shows a whole example). The law
// declares its parameters (name, unit, range, default, doc), any per-element data it needs
// (hgo: two fibre directions per tet) and extra result fields, and evaluates, from the deformation
// gradient F of a one-point tet:
//   P        the first Piola-Kirchhoff stress (P = F S, S = 2 dW/dC, paper eq. 18),
//   W        the strain energy per reference volume,
//   modulus  the current P-wave modulus (Pa) for the stable time step (K + 4 mu / 3, plus the
//            fibres' current tangent stiffness for hgo).
// A law whose energy splits as W_iso(F) + U(J) (neo_hookean, hgo, mooney_rivlin) evaluates the two
// parts separately and can then run as average-nodal-pressure tets (`formulation = "anp"`, the
// default when bulk / shear > 100), which do not lock volumetrically (kernels/element_loop.hpp).
// The registry turns each law into a MaterialType: the scenario reader validates against its
// declarations, the key reference is generated from them, and the stress pass, the output pass and
// the material-point driver call its kernels once per block of elements (never a virtual call per
// element: the element loop is compiled for each law).
#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "tactus/core/mesh.hpp"
#include "tactus/solver/parameters.hpp"

namespace tactus::solver {

using Mat3 = Eigen::Matrix3d;
using Vec3d = Eigen::Vector3d;

// F^{-T} J = cof(F): the cofactor matrix, so F^{-T} = cof(F) / J without a division per entry.
// For any 3x3 matrix type indexed F(i, j): Eigen's, or the stress kernels' lanes::M3 of packs.
template <class M>
inline M cofactor(const M& F) {
  M c;
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

// The per-element material evaluation must inline into the force loop.
#define TACTUS_KERNEL_INLINE [[gnu::always_inline]] inline

struct StressPoint {
  Mat3 P;
  double W = 0;
  double modulus = 0;
};

// Validated values of one [materials.<name>] section: numbers, and the law's vector keys
// (hgo: `fibres`).
struct MaterialValues {
  std::map<std::string, double> numbers;
  std::map<std::string, std::vector<Vec3>> vectors;
  std::map<std::string, std::string> strings{};  // `formulation`
  std::string source = "material";               // the file they came from, for messages
};

// A cell field a law adds to the results (hgo: fibre_stretch).
struct ResultFieldSpec {
  std::string name;
  int components = 1;
  std::string doc;
};

struct StressKernelArgs;  // kernels/element_loop.hpp
struct OutputKernelArgs;
struct StressAccumulator;

// One registered law: its declarations and its kernels (made by make_material_type<Law>()).
struct MaterialType {
  std::string name;        // the scenario's `type`
  SectionSpec parameters;  // every key of its [materials.<name>] section but `type`
  // Per-element data: doubles per tet, and the cell fields of a body's element-data file
  // (bodies.fibres) it is made from (hgo: fibre_1, fibre_2).
  std::size_t element_data_size = 0;
  std::vector<std::pair<std::string, int>> element_fields;
  // Whether the element data is 3-vectors in the reference frame that rotate with a body (hgo's
  // fibre directions); a law with other element data cannot be used in a rotated body.
  bool element_data_is_directions = false;
  // Its tets move as rigid bodies (time/rigid.cpp): no stress pass, no stable-step limit.
  bool rigid = false;
  std::vector<ResultFieldSpec> result_fields;

  // Builds the law from validated values; `constants` receives its element data when the section
  // gives it (hgo with `fibres`), else stays empty and every element must get it from a file.
  std::shared_ptr<const void> (*create)(const MaterialValues& values, const std::string& where, std::vector<double>& constants) = nullptr;
  // Element data of one tet from the element fields' values (in element_fields order).
  void (*element_data_from_fields)(const double* fields, double* data, const std::string& where) = nullptr;
  StressPoint (*evaluate)(const void* law, const Mat3& F, const Mat3& cof, double J, const double* data) = nullptr;
  void (*result_values)(const void* law, const Mat3& F, const double* data, double* out) = nullptr;  // result_fields, in order
  double (*density)(const void* law) = nullptr;
  double (*small_strain_bulk)(const void* law) = nullptr;  // for Rayleigh beta and the initial step
  double (*small_strain_shear)(const void* law) = nullptr;
  void (*stress_pass)(const StressKernelArgs& args, StressAccumulator& acc) = nullptr;

  // Laws with W = W_iso(F) + U(J) (null otherwise): the isochoric part alone (P, W; the modulus
  // is still the whole one), and the ANP nodal pass over nodes [lo, hi): `volume` holds each
  // node's current volume v_a on entry and its pressure U'(v_a / V_a) on return (nodes with
  // V_a = 0, not in the block, are left alone); returns sum_a V_a U(v_a / V_a).
  StressPoint (*evaluate_isochoric)(const void* law, const Mat3& F, const Mat3& cof, double J, const double* data) = nullptr;
  double (*anp_nodal_pressure)(const void* law, const double* node_reference_volume, double* volume, std::size_t lo, std::size_t hi) = nullptr;
  bool volumetric_split() const { return evaluate_isochoric != nullptr; }
};

// How a law's tets are integrated: one-point linear tets, or average nodal pressure tets.
enum class Formulation { standard, anp };
// The formulations as the material's `formulation` key writes them (a law with a volumetric split).
const std::vector<Choice<Formulation>>& formulation_choices();
// The `formulation` key: bulk / shear above this makes ANP the default for a law that can use it.
inline constexpr double kAnpDefaultBulkToShear = 100.0;
// The `pressure_smoothing` key of ANP tets: node -> tet -> node averaging passes applied to the
// nodal volume ratio and, by symmetry, to the nodal pressure (kernels/internal_force.cpp).
inline constexpr int kAnpDefaultPressureSmoothing = 2;
inline constexpr int kAnpMaxPressureSmoothing = 8;
// The `volume_floor` key of ANP tets: the element volume ratio J_e below which a barrier adds the
// element's own volumetric resistance (0: off). ANP constrains only nodal volumes, so a tet can
// lose its volume while its nodes' averages hold (the kernel of the nodal constraint, resisted
// only at the shear scale); the barrier closes that mode below the floor and is exactly zero
// above it, so runs whose tets stay above the floor are unchanged to the bit.
inline constexpr double kAnpDefaultVolumeFloor = 0.5;

// The barrier of the volume floor J0 with stiffness kappa (the material's bulk modulus): per
// reference volume b(J) = -kappa (J - J0)^2 ln(J / J0) for J < J0, else 0 (the form of the
// incremental-potential contact barrier, C2 at J0, infinite as J -> 0). Its first derivative is
// a pressure added to the tet's nodal one (P += b'(J) cof F); its second, a bulk stiffness, is
// added to the tet's P-wave modulus for the stable step.
struct VolumeFloorBarrier {
  double energy = 0, pressure = 0, stiffness = 0;
};
inline VolumeFloorBarrier volume_floor_barrier(double J, double floor, double kappa) {
  VolumeFloorBarrier b;
  if (!(J < floor) || !(J > 0)) return b;
  const double d = J - floor, L = std::log(J / floor);
  b.energy = -kappa * d * d * L;
  b.pressure = -kappa * (2.0 * d * L + d * d / J);
  b.stiffness = -kappa * (2.0 * L + 4.0 * d / J - d * d / (J * J));
  return b;
}

// Every registered law, in registration order.
const std::vector<const MaterialType*>& material_types();
// The law named `type`, or an InputError naming `where` and listing the known ones.
const MaterialType& material_type(const std::string& type, const std::string& where = "material type");
// "neo_hookean | linear_elastic | hgo | ...".
std::string material_type_list();

// A law with its parameters: a cheap handle, shared by the blocks that use it.
class Material {
 public:
  Material() = default;
  // Validates `values` against the law's declarations (InputError naming `where`.key).
  static Material make(const std::string& type, const MaterialValues& values, const std::string& where = "material");

  const MaterialType& type() const { return *type_; }
  const std::string& type_name() const { return type_->name; }
  const void* law() const { return law_.get(); }
  double density() const { return type_->density(law_.get()); }
  double small_strain_bulk() const { return type_->small_strain_bulk(law_.get()); }
  double small_strain_shear() const { return type_->small_strain_shear(law_.get()); }
  // The law's element data from its own section (empty when every element must bring its own).
  const std::vector<double>& constant_element_data() const { return constants_; }
  bool needs_element_data() const { return type_->element_data_size > 0 && constants_.empty(); }
  Formulation formulation() const { return formulation_; }
  bool anp() const { return formulation_ == Formulation::anp; }
  // ANP tets: how many averaging passes smooth the nodal volume ratio and pressure (0: plain ANP).
  int pressure_smoothing() const { return pressure_smoothing_; }
  // ANP tets: the element volume ratio below which the volume-floor barrier acts (0: off).
  double volume_floor() const { return volume_floor_; }
  bool rigid() const { return type_->rigid; }

  // P, W and modulus at F; `data`: this element's data (default: the constants).
  StressPoint evaluate(const Mat3& F, const double* data = nullptr) const;
  // The same for an ANP tet whose nodes' average pressure is `pressure` (W: the isochoric part and
  // the volume floor's barrier, unless `floor` is false: a tet placed by rigid pieces).
  StressPoint evaluate_with_pressure(const Mat3& F, double pressure, const double* data = nullptr, bool floor = true) const;

 private:
  const MaterialType* type_ = nullptr;
  std::shared_ptr<const void> law_;
  std::vector<double> constants_;
  Formulation formulation_ = Formulation::standard;
  int pressure_smoothing_ = kAnpDefaultPressureSmoothing;
  double volume_floor_ = kAnpDefaultVolumeFloor;
};

// Cauchy stress sigma = F S F^T / J = P F^T / J (paper eq. 18), and its von Mises value.
inline Mat3 cauchy_stress(const Mat3& F, const Mat3& P) { return P * F.transpose() / F.determinant(); }
inline double von_mises(const Mat3& s) {
  const double a = s(0, 0) - s(1, 1), b = s(1, 1) - s(2, 2), c = s(2, 2) - s(0, 0);
  return std::sqrt(0.5 * (a * a + b * b + c * c) + 3.0 * (s(0, 1) * s(0, 1) + s(1, 2) * s(1, 2) + s(0, 2) * s(0, 2)));
}

}  // namespace tactus::solver
