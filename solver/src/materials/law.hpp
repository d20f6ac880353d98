#pragma once
// What a material law file provides, and the registration that turns it into a MaterialType
// (docs/adding-a-material.md walks through a whole example). A law is a struct with
//   static constexpr const char* kName;                       the scenario's `type`
//   static SectionSpec parameters();                          its keys, with unit, range, default, doc
//   static Law create(const MaterialValues&, const std::string& where, std::vector<double>& constants);
//   double density;                                           kg/m^3, reference configuration
//   double small_strain_bulk() const, small_strain_shear() const;   Pa
//   TACTUS_KERNEL_INLINE StressPoint evaluate(const Mat3& F, const Mat3& cof, double J, const double* data) const;
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
    return static_cast<const Law*>(law)->evaluate(F, cof, J, data);
  };
  t.density = [](const void* law) { return static_cast<const Law*>(law)->density; };
  t.small_strain_bulk = [](const void* law) { return static_cast<const Law*>(law)->small_strain_bulk(); };
  t.small_strain_shear = [](const void* law) { return static_cast<const Law*>(law)->small_strain_shear(); };
  t.stress_pass = [](const StressKernelArgs& args, ThreadAccumulator& acc) {
    if (args.beta > 0)
      stress_range<Law, true>(args, acc);
    else
      stress_range<Law, false>(args, acc);
  };
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
