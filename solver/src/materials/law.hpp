#pragma once
// What a material law file provides, and the registration that turns it into a MaterialType
// (docs/adding-a-material.md walks through a whole example). A law is a struct with
//   static constexpr const char* kName;                       the scenario's `type`
//   static constexpr const char* kDoc;                        what it is, for the reference
//   static std::vector<LawParameter<Law>> parameters();       each number key bound to its member, with unit, range, doc
//   double density;                                           kg/m^3, reference configuration (one of the members)
//   double small_strain_bulk() const, small_strain_shear() const;   Pa
//   template <class T> TACTUS_KERNEL_INLINE LawStress<T> evaluate(const M3<T>& F, const M3<T>& cof, const T& J, const T* data) const;
// or, when W = W_iso(F) + U(J) (then the law can also run as ANP tets), instead of evaluate:
//   template <class T> TACTUS_KERNEL_INLINE LawStress<T> evaluate_isochoric(same arguments) const;
//   template <class T> T volumetric_energy(const T& J) const;     U(J)
//   template <class T> T volumetric_pressure(const T& J) const;   U'(J)
// The evaluations are templates over the lane type T: double for one tet, lanes::Pack for one
// tet per SIMD lane (kernels/lanes.hpp); write them with the operators and helpers of
// lanes.hpp, and a branch on the deformation as a per-lane select `mask ? a : b`.
// When the law needs per-element data (fibre directions):
//   static constexpr std::size_t kElementData;                doubles per element (data[k], as lanes)
//   static std::vector<std::pair<std::string, int>> element_fields();   cell fields of bodies.fibres
//   static void element_data_from_fields(const double* fields, double* data, const std::string& where);
//   static constexpr bool kElementDataAreDirections;          when they are 3-vectors that rotate with a body
// and, when it adds result fields:
//   static std::vector<ResultFieldSpec> result_fields();
//   void result_values(const Mat3& F, const double* data, double* out) const;
// and, when it derives constants, validates a combination or reads a key that is not a number:
//   static std::vector<ValueSpec> extra_keys();               (hgo's fibres)
//   void finish(const MaterialValues&, const std::string& where, std::vector<double>& constants);
// The file ends with TACTUS_MATERIAL(Law); registry.cpp lists it once.
#include "../kernels/element_loop.hpp"
#include "tactus/core/error.hpp"
#include "tactus/solver/material.hpp"

namespace tactus::solver {

using lanes::M3;
using lanes::V3;

inline M3<double> to_m3(const Mat3& A) {
  M3<double> r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = A(i, j);
  return r;
}
inline StressPoint to_stress_point(const LawStress<double>& s) {
  StressPoint r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.P(i, j) = s.P(i, j);
  r.W = s.W;
  r.modulus = s.modulus;
  return r;
}

// U(J) = K/2 (J - 1)^2 and U'(J) = K (J - 1): the volumetric penalty of neo_hookean,
// mooney_rivlin and hgo (the paper's k/2 (J - 1)^2, eq. 20).
template <class T>
T penalty_energy(double K, const T& J) {
  return 0.5 * K * (J - 1.0) * (J - 1.0);
}
template <class T>
T penalty_pressure(double K, const T& J) {
  return K * (J - 1.0);
}

// A number key of a law bound to the member it sets: one declaration gives the reference's text
// and the law's value (FEBio's ADD_PARAMETER), so create() looks up no key by string.
template <class Law>
struct LawParameter {
  double Law::*member;
  ValueSpec spec;
};

// The law from validated values (MaterialType::create): each bound member set from its key, then
// the law's own finish (derived constants, combined checks, keys that are not numbers).
template <class Law>
Law create_law(const MaterialValues& values, const std::string& where, std::vector<double>& constants) {
  Law law{};
  for (const LawParameter<Law>& p : Law::parameters()) law.*p.member = values.numbers.at(p.spec.key);
  if constexpr (requires { law.finish(values, where, constants); }) law.finish(values, where, constants);
  return law;
}

template <class Law>
MaterialType make_material_type() {
  MaterialType t;
  t.name = Law::kName;
  t.parameters.doc = Law::kDoc;
  for (const LawParameter<Law>& p : Law::parameters()) t.parameters.keys.push_back(p.spec);
  if constexpr (requires { Law::extra_keys(); })
    for (const ValueSpec& k : Law::extra_keys()) t.parameters.keys.push_back(k);
  t.parameters.name = std::string("materials.<name> with type = \"") + Law::kName + "\"";
  if constexpr (requires { Law::kElementData; }) {
    t.element_data_size = Law::kElementData;
    t.element_fields = Law::element_fields();
    t.element_data_from_fields = &Law::element_data_from_fields;
    if constexpr (requires { Law::kElementDataAreDirections; }) t.element_data_is_directions = Law::kElementDataAreDirections;
  }
  if constexpr (requires { Law::kRigid; }) t.rigid = Law::kRigid;
  if constexpr (requires { Law::result_fields(); }) {
    t.result_fields = Law::result_fields();
    t.result_values = [](const void* law, const Mat3& F, const double* data, double* out) {
      static_cast<const Law*>(law)->result_values(F, data, out);
    };
  }
  t.create = [](const MaterialValues& values, const std::string& where, std::vector<double>& constants) -> std::shared_ptr<const void> {
    return std::make_shared<const Law>(create_law<Law>(values, where, constants));
  };
  t.evaluate = [](const void* law, const Mat3& F, const Mat3& cof, double J, const double* data) {
    return to_stress_point(evaluate_law(*static_cast<const Law*>(law), to_m3(F), to_m3(cof), J, data));
  };
  t.density = [](const void* law) { return static_cast<const Law*>(law)->density; };
  t.small_strain_bulk = [](const void* law) { return static_cast<const Law*>(law)->small_strain_bulk(); };
  t.small_strain_shear = [](const void* law) { return static_cast<const Law*>(law)->small_strain_shear(); };
  t.stress_pass = [](const StressKernelArgs& args, StressAccumulator& acc) {
    if constexpr (VolumetricSplit<Law>) {
      if (args.nodal_pressure) {
        if (args.beta > 0)
          stress_range<Law, true, true>(args, acc);
        else
          stress_range<Law, false, true>(args, acc);
        return;
      }
    }
    if (args.beta > 0)
      stress_range<Law, true>(args, acc);
    else
      stress_range<Law, false>(args, acc);
  };
  if constexpr (VolumetricSplit<Law>) {
    ValueSpec formulation;
    formulation.key = "formulation";
    formulation.type = ValueType::string;
    for (const Choice<Formulation>& c : formulation_choices()) formulation.choices.push_back(c.name);
    formulation.default_text = "\"anp\" when bulk / shear > 100, else \"standard\"";
    formulation.doc =
        "standard: one-point linear tets; anp: average nodal pressure tets (volumetric part from nodal volumes of this "
        "material's tets), which do not lock when nearly incompressible";
    t.parameters.keys.push_back(formulation);
    ValueSpec smoothing;
    smoothing.key = "pressure_smoothing";
    smoothing.type = ValueType::integer;
    smoothing.min = 0, smoothing.max = kAnpMaxPressureSmoothing;
    smoothing.default_text = std::to_string(kAnpDefaultPressureSmoothing);
    smoothing.doc =
        "anp only: passes of node -> tet -> node averaging applied to the nodal volume ratio and to the nodal pressure; 0 is plain "
        "ANP, whose nodal pressure oscillates when nearly incompressible, each pass about halves that oscillation";
    t.parameters.keys.push_back(smoothing);
    ValueSpec floor;
    floor.key = "volume_floor";
    floor.type = ValueType::number;
    floor.min = 0, floor.max = 0.99;
    floor.default_text = "0.5";
    floor.doc =
        "anp only: the tet volume ratio J below which a barrier adds the tet's own volumetric resistance (stiffness: the bulk "
        "modulus; exactly zero above it), so that no single tet collapses while its nodes' averaged volumes hold; 0 is off";
    t.parameters.keys.push_back(floor);
    t.evaluate_isochoric = [](const void* law, const Mat3& F, const Mat3& cof, double J, const double* data) {
      return to_stress_point(static_cast<const Law*>(law)->evaluate_isochoric(to_m3(F), to_m3(cof), J, data));
    };
    t.anp_nodal_pressure = [](const void* law, const double* reference_volume, double* volume, std::size_t lo, std::size_t hi) {
      const Law& mat = *static_cast<const Law*>(law);
      double energy = 0;
      for (std::size_t a = lo; a < hi; ++a) {
        const double V = reference_volume[a];
        if (!(V > 0)) continue;
        const double J = volume[a] / V;
        energy += V * mat.volumetric_energy(J);
        volume[a] = mat.volumetric_pressure(J);
      }
      return energy;
    };
  }
  return t;
}

}  // namespace tactus::solver

// Defines the law's registration function, listed once in registry.cpp.
#define TACTUS_MATERIAL(Law)                                                                                    \
  const tactus::solver::MaterialType& tactus_material_##Law() {                                                 \
    static const tactus::solver::MaterialType type = tactus::solver::make_material_type<tactus::solver::Law>(); \
    return type;                                                                                                \
  }
