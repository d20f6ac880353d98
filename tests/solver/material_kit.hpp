#pragma once
// Materials for the solver tests, made through the registry exactly as a scenario makes them.
#include <map>
#include <string>
#include <vector>

#include "tactus/solver/material.hpp"

namespace tactus::testkit {

using solver::Material;
using solver::MaterialValues;

// formulation: "standard" or "anp"; empty: the law's default (ANP when bulk / shear > 100).
inline Material make_law(const std::string& type, std::map<std::string, double> numbers, std::vector<Vec3> fibres = {},
                         const std::string& formulation = "") {
  MaterialValues v;
  v.numbers = std::move(numbers);
  if (!fibres.empty()) v.vectors["fibres"] = std::move(fibres);
  if (!formulation.empty()) v.strings["formulation"] = formulation;
  return Material::make(type, v);
}
inline Material neo_hookean(double mu, double bulk, double density, const std::string& formulation = "") {
  return make_law("neo_hookean", {{"mu", mu}, {"bulk", bulk}, {"density", density}}, {}, formulation);
}
inline Material linear_elastic(double E, double nu, double density) {
  return make_law("linear_elastic", {{"E", E}, {"nu", nu}, {"density", density}});
}
// The paper's tissue (§3.2) with fibres at +-30 deg to x in the x-y plane.
inline Material paper_hgo(double k = 1.0e8, const std::string& formulation = "") {
  return make_law("hgo", {{"c1", 10206.9}, {"k1", 1.7}, {"k2", 882.847}, {"k", k}, {"density", 1050}},
                  {Vec3{0.8660254, 0.5, 0}, Vec3{0.8660254, -0.5, 0}}, formulation);
}

}  // namespace tactus::testkit
