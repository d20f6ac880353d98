#pragma once
// What a material law file provides, and the registration that turns it into a MaterialType
// (docs/adding-a-material.md walks through a whole example). A law is a struct with
//   static constexpr const char* kName;                       the scenario's `type`
//   static SectionSpec parameters();                          its keys, with unit, range, default, doc
//   static Law create(const MaterialValues&, const std::string& where, std::vector<double>& constants);
//   double density;                                           kg/m^3, reference configuration
//   double small_strain_bulk() const, small_strain_shear() const;   Pa
//   TACTUS_KERNEL_INLINE StressPoint evaluate(const Mat3& F, const Mat3& cof, double J, const double* data) const;
// or, when W = W_iso(F) + U(J) (then the law can also run as ANP tets), instead of evaluate:
//   TACTUS_KERNEL_INLINE StressPoint evaluate_isochoric(const Mat3& F, const Mat3& cof, double J, const double* data) const;
//   double volumetric_energy(double J) const;     U(J)
//   double volumetric_pressure(double J) const;   U'(J)
// and, when it needs per-element data (fibre directions):
//   static constexpr std::size_t kElementData;                doubles per element
//   static std::vector<std::pair<std::string, int>> element_fields();   cell fields of bodies.fibres
//   static void element_data_from_fields(const double* fields, double* data, const std::string& where);
//   static constexpr bool kElementDataAreDirections;          when they are 3-vectors that rotate with a body
// and, when it adds result fields:
//   static std::vector<ResultFieldSpec> result_fields();
//   void result_values(const Mat3& F, const double* data, double* out) const;
// The file ends with TACTUS_MATERIAL(Law); registry.cpp lists it once.
#include "../kernels/element_loop.hpp"
#include "tactus/core/error.hpp"
#include "tactus/solver/material.hpp"

namespace tactus::solver {

template <class Law>
MaterialType make_material_type() {
  MaterialType t;
  t.name = Law::kName;
  t.parameters = Law::parameters();
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
    return std::make_shared<const Law>(Law::create(values, where, constants));
  };
  t.evaluate = [](const void* law, const Mat3& F, const Mat3& cof, double J, const double* data) {
    return evaluate_law(*static_cast<const Law*>(law), F, cof, J, data);
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
    formulation.default_text = "\"anp\" when bulk / shear > 100, else \"standard\"";
    formulation.doc =
        "standard: one-point linear tets; anp: average nodal pressure tets (volumetric part from nodal volumes of this "
        "material's tets), which do not lock when nearly incompressible";
    t.parameters.keys.push_back(formulation);
    t.evaluate_isochoric = [](const void* law, const Mat3& F, const Mat3& cof, double J, const double* data) {
      return static_cast<const Law*>(law)->evaluate_isochoric(F, cof, J, data);
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

// A number parameter of `values`, validated by the reader already (present, in range).
inline double parameter(const MaterialValues& values, const std::string& key) { return values.numbers.at(key); }

}  // namespace tactus::solver

// Defines the law's registration function, listed once in registry.cpp.
#define TACTUS_MATERIAL(Law)                                                                                    \
  const tactus::solver::MaterialType& tactus_material_##Law() {                                                 \
    static const tactus::solver::MaterialType type = tactus::solver::make_material_type<tactus::solver::Law>(); \
    return type;                                                                                                \
  }
