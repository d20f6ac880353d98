// The registered material laws: one line each (a law is its own file, materials/<law>.cpp).
#include <algorithm>
#include "tactus/core/error.hpp"
#include "tactus/solver/material.hpp"

#define TACTUS_MATERIALS(X) \
  X(NeoHookean)             \
  X(LinearElastic)          \
  X(Hgo)                    \
  X(MooneyRivlin)           \
  X(Rigid)

#define TACTUS_DECLARE(Law) const tactus::solver::MaterialType& tactus_material_##Law();
TACTUS_MATERIALS(TACTUS_DECLARE)
#undef TACTUS_DECLARE

namespace tactus::solver {

const std::vector<Choice<Formulation>>& formulation_choices() {
  static const std::vector<Choice<Formulation>> choices{{Formulation::standard, "standard", "one-point linear tets"},
                                                        {Formulation::anp, "anp", "average nodal pressure tets"}};
  return choices;
}

const std::vector<const MaterialType*>& material_types() {
#define TACTUS_LIST(Law) &tactus_material_##Law(),
  static const std::vector<const MaterialType*> types{TACTUS_MATERIALS(TACTUS_LIST)};
#undef TACTUS_LIST
  return types;
}

std::string material_type_list() {
  std::string s;
  for (const MaterialType* t : material_types()) s += (s.empty() ? "" : " | ") + t->name;
  return s;
}

const MaterialType& material_type(const std::string& type, const std::string& where) {
  for (const MaterialType* t : material_types())
    if (t->name == type) return *t;
  throw InputError("scenario", where, "one of " + material_type_list(), "\"" + type + "\"");
}

Material Material::make(const std::string& type, const MaterialValues& values, const std::string& where) {
  Material m;
  m.type_ = &material_type(type, where + ".type");  // (an InputError naming "scenario" as the file)
  // Values that did not come through the scenario reader (tests, benchmarks) are checked here the
  // same way: every declared number present (or defaulted) and in range, every integer given a
  // whole number in range.
  MaterialValues checked = values;
  for (const ValueSpec& s : m.type_->parameters.keys) {
    if (s.type != ValueType::number && s.type != ValueType::integer) continue;
    auto it = checked.numbers.find(s.key);
    if (it == checked.numbers.end()) {
      if (s.type == ValueType::integer || !s.required) continue;  // optional: the law's default
      throw InputError(values.source, where + "." + s.key, s.doc, "missing");
    }
    if (s.type == ValueType::integer && it->second != std::floor(it->second))
      throw InputError(values.source, where + "." + s.key, "an integer", std::to_string(it->second));
    if (!s.in_range(it->second))
      throw InputError(values.source, where + "." + s.key, "a value " + s.range_text() + (s.unit.empty() ? "" : " in " + s.unit),
                       std::to_string(it->second));
  }
  m.law_ = m.type_->create(checked, where, m.constants_);
  // formulation: explicit, or ANP by default where standard tets would lock (bulk / shear > 100).
  if (auto it = values.strings.find("formulation"); it != values.strings.end()) {
    if (!m.type_->volumetric_split())
      throw InputError(values.source, where + ".formulation", "no formulation key (" + type + " has one formulation)", "\"" + it->second + "\"");
    const auto& choices = formulation_choices();
    const auto chosen = std::find_if(choices.begin(), choices.end(), [&](const Choice<Formulation>& c) { return it->second == c.name; });
    if (chosen == choices.end()) throw InputError(values.source, where + ".formulation", "\"anp\" or \"standard\"", "\"" + it->second + "\"");
    m.formulation_ = chosen->value;
  } else if (m.type_->volumetric_split() && m.small_strain_bulk() > kAnpDefaultBulkToShear * m.small_strain_shear()) {
    m.formulation_ = Formulation::anp;
  }
  if (auto it = values.numbers.find("pressure_smoothing"); it != values.numbers.end() && m.type_->volumetric_split())
    m.pressure_smoothing_ = static_cast<int>(it->second);  // checked above against the law's declaration
  if (auto it = values.numbers.find("volume_floor"); it != values.numbers.end() && m.type_->volumetric_split()) m.volume_floor_ = it->second;
  return m;
}

StressPoint Material::evaluate(const Mat3& F, const double* data) const {
  const Mat3 cof = cofactor(F);
  return type_->evaluate(law_.get(), F, cof, F.row(0).dot(cof.row(0)), data ? data : constants_.data());
}

StressPoint Material::evaluate_with_pressure(const Mat3& F, double pressure, const double* data, bool floor) const {
  const Mat3 cof = cofactor(F);
  const double J = F.row(0).dot(cof.row(0));
  StressPoint s = type_->evaluate_isochoric(law_.get(), F, cof, J, data ? data : constants_.data());
  const VolumeFloorBarrier barrier = anp() && floor ? volume_floor_barrier(J, volume_floor_, small_strain_bulk()) : VolumeFloorBarrier{};
  s.P += (pressure + barrier.pressure) * cof;
  s.W += barrier.energy;
  s.modulus += barrier.stiffness;
  return s;
}

}  // namespace tactus::solver
