// Parameter declarations and the registry of materials (one line per material).
#include "tactus/core/error.hpp"
#include "tactus/solver/materials.hpp"

namespace tactus::solver {

namespace {
ValueSpec density_spec() { return number("density", "kg/m^3", "mass density in the reference configuration", 0, true); }
}  // namespace

const SectionSpec& NeoHookean::spec() {
  static const SectionSpec s{"neo_hookean",
                             "Compressible neo-Hookean: W = mu/2 (I1bar - 3) + bulk/2 (J - 1)^2.",
                             {number("mu", "Pa", "shear modulus", 0, true), number("bulk", "Pa", "bulk modulus", 0, true),
                              density_spec()}};
  return s;
}

const SectionSpec& LinearElastic::spec() {
  static const SectionSpec s{"linear_elastic",
                             "St Venant-Kirchhoff (linear S(E) in the total-Lagrangian frame); bone, the block.",
                             {number("E", "Pa", "Young's modulus", 0, true),
                              number("nu", "", "Poisson's ratio", -1, true, 0.5, true), density_spec()}};
  return s;
}

const SectionSpec& Hgo::spec() {
  static const SectionSpec s{
      "hgo",
      "Holzapfel-Gasser-Ogden with two fibre families (paper eqs. 20-26); fibres carry load only in tension.",
      {number("c1", "Pa", "matrix shear parameter (shear modulus = 2 c1)", 0, true),
       number("k1", "Pa", "fibre stiffness", 0, false), number("k2", "", "fibre exponential stiffening", 0, true),
       number("k", "Pa", "bulk (volumetric penalty) modulus in k/2 (J-1)^2", 0, true), density_spec()}};
  return s;
}

const std::vector<MaterialEntry>& material_registry() {
  static const std::vector<MaterialEntry> r{
      {MaterialKind::neo_hookean, "neo_hookean", &NeoHookean::spec},
      {MaterialKind::linear_elastic, "linear_elastic", &LinearElastic::spec},
      {MaterialKind::hgo, "hgo", &Hgo::spec},
  };
  return r;
}

Material make_material(const std::string& type, const std::map<std::string, double>& p) {
  if (type == "neo_hookean") return NeoHookean::from(p);
  if (type == "linear_elastic") return LinearElastic::from(p);
  if (type == "hgo") return Hgo::from(p);
  throw InputError("material", "type", "one of neo_hookean, linear_elastic, hgo", "\"" + type + "\"");
}

const char* material_type_name(const Material& m) {
  return std::visit([](const auto& x) { return std::decay_t<decltype(x)>::spec().name.c_str(); }, m);
}
double material_density(const Material& m) {
  return std::visit([](const auto& x) { return x.density; }, m);
}
double material_bulk(const Material& m) {
  return std::visit([](const auto& x) { return x.small_strain_bulk(); }, m);
}
double material_shear(const Material& m) {
  return std::visit([](const auto& x) { return x.small_strain_shear(); }, m);
}

}  // namespace tactus::solver
