// The scenario reader's value checks (scenario_keys.hpp).
#include "scenario_keys.hpp"

namespace tactus::solver::keys {

const char* type_name(ValueType t) {
  switch (t) {
    case ValueType::number:
      return "a number";
    case ValueType::integer:
      return "an integer";
    case ValueType::boolean:
      return "true or false";
    case ValueType::string:
      return "a string";
    case ValueType::vec3:
      return "an array of 3 numbers";
    case ValueType::number_list:
      return "an array of numbers";
    case ValueType::vec3_list:
      return "an array of [x, y, z] arrays";
    case ValueType::table:
      return "a table";
    case ValueType::table_list:
      return "an array of tables";
  }
  return "";
}

void Reader::check_keys(const toml::table& t, const SectionSpec& spec, const std::string& path, const std::set<std::string>& extra) const {
  for (const auto& [k, node] : t) {
    const std::string key(k.str());
    if (!spec.find(key) && !extra.count(key)) {
      std::string allowed;
      for (const auto& s : spec.keys) allowed += (allowed.empty() ? "" : ", ") + s.key;
      for (const auto& s : extra) allowed += ", " + s;
      fail(join(path, key), "one of the keys " + allowed, "unknown key \"" + key + "\"");
    }
  }
  for (const auto& s : spec.keys)
    if (s.required && !t.contains(s.key)) fail(join(path, s.key), s.doc + " (" + type_name(s.type) + ")", "missing");
}

double Reader::number(const toml::table& t, const ValueSpec& s, const std::string& path, double def) const {
  const toml::node* n = t.get(s.key);
  if (!n) return def;
  auto v = n->value<double>();
  if (!v || n->is_boolean()) fail(join(path, s.key), std::string(type_name(ValueType::number)) + unit_suffix(s), describe(*n));
  check_range(*v, s, join(path, s.key));
  return *v;
}

std::int64_t Reader::integer(const toml::table& t, const ValueSpec& s, const std::string& path) const {
  const toml::node* n = t.get(s.key);
  std::optional<double> v;
  if (n && n->is_integer()) v = static_cast<double>(*n->value<std::int64_t>());
  if (n && n->is_floating_point()) v = *n->value<double>();
  if (!v || !std::isfinite(*v) || *v != std::floor(*v) || std::abs(*v) > 9.0e18)
    fail(join(path, s.key), "an integer (a whole number)" + unit_suffix(s), n ? describe(*n) : "missing");
  check_range(*v, s, join(path, s.key));
  return static_cast<std::int64_t>(*v);
}

void Reader::check_range(double v, const ValueSpec& s, const std::string& key) const {
  if (!s.in_range(v)) {
    std::ostringstream f;
    f << v;
    fail(key, "a value " + s.range_text() + unit_suffix(s), f.str());
  }
}

bool Reader::boolean(const toml::table& t, const ValueSpec& s, const std::string& path, bool def) const {
  const toml::node* n = t.get(s.key);
  if (!n) return def;
  if (!n->is_boolean()) fail(join(path, s.key), "true or false", describe(*n));
  return *n->value<bool>();
}

std::string Reader::string(const toml::table& t, const ValueSpec& s, const std::string& path, std::string def) const {
  const toml::node* n = t.get(s.key);
  if (!n) return def;
  if (!n->is_string()) fail(join(path, s.key), "a string", describe(*n));
  return *n->value<std::string>();
}

Vec3 Reader::vec3(const toml::node& n, const std::string& key, const std::string& unit) const {
  const toml::array* a = n.as_array();
  Vec3 v{};
  if (!a || a->size() != 3) fail(key, "an array of 3 numbers" + (unit.empty() ? "" : " in " + unit), describe(n));
  for (std::size_t i = 0; i < 3; ++i) {
    auto x = (*a)[i].value<double>();
    if (!x || (*a)[i].is_boolean() || !std::isfinite(*x)) fail(key, "an array of 3 finite numbers", describe(n));
    v[i] = *x;
  }
  return v;
}

Vec3 Reader::vec3(const toml::table& t, const ValueSpec& s, const std::string& path, Vec3 def) const {
  const toml::node* n = t.get(s.key);
  return n ? vec3(*n, join(path, s.key), s.unit) : def;
}

std::vector<Vec3> Reader::vec3_list(const toml::table& t, const ValueSpec& s, const std::string& path) const {
  std::vector<Vec3> out;
  const toml::node* n = t.get(s.key);
  if (!n) return out;
  const toml::array* a = n->as_array();
  if (!a) fail(join(path, s.key), "an array of [x, y, z] arrays", describe(*n));
  for (std::size_t i = 0; i < a->size(); ++i) out.push_back(vec3((*a)[i], join(path, s.key) + "[" + std::to_string(i) + "]", s.unit));
  return out;
}

std::vector<double> Reader::number_list(const toml::table& t, const ValueSpec& s, const std::string& path) const {
  std::vector<double> out;
  const toml::node* n = t.get(s.key);
  if (!n) return out;
  const toml::array* a = n->as_array();
  if (!a) fail(join(path, s.key), "an array of numbers", describe(*n));
  for (std::size_t i = 0; i < a->size(); ++i) {
    auto x = (*a)[i].value<double>();
    if (!x || (*a)[i].is_boolean() || !std::isfinite(*x) || (s.unit == "s" && *x < 0))
      fail(join(path, s.key) + "[" + std::to_string(i) + "]", s.unit == "s" ? "a time >= 0 in s" : "a finite number", describe((*a)[i]));
    out.push_back(*x);
  }
  return out;
}

const toml::table& Reader::table(const toml::node& n, const std::string& key) const {
  const toml::table* t = n.as_table();
  if (!t) fail(key, "a table", describe(n));
  return *t;
}

std::string Reader::describe(const toml::node& n) {
  std::ostringstream o;
  if (n.is_table()) return "a table";
  if (n.is_array()) {
    const toml::array& a = *n.as_array();
    o << '[';
    for (std::size_t i = 0; i < a.size() && i < 6; ++i) o << (i ? ", " : "") << describe(a[i]);
    o << (a.size() > 6 ? ", ... (" + std::to_string(a.size()) + " values)]" : "]");
    return o.str();
  }
  if (n.is_string()) {
    o << '"' << *n.value<std::string>() << '"';  // (not "\"" + s: GCC 12 -Wrestrict false positive)
    return o.str();
  }
  if (n.is_boolean()) return *n.value<bool>() ? "true" : "false";
  if (auto d = n.value<double>()) {
    o << *d;
    return o.str();
  }
  return "a value of another type";
}

// 1e7 and 25e-6 as a user writes them ("1e7", "2.5e-5"), 0.9 as "0.9".
std::string default_text(double v) {
  std::ostringstream o;
  o << v;
  std::string s = o.str();
  if (const auto e = s.find('e'); e != std::string::npos) {
    const bool negative = s[e + 1] == '-';
    std::string exponent = s.substr(e + 2);
    while (exponent.size() > 1 && exponent[0] == '0') exponent.erase(0, 1);
    s = s.substr(0, e) + (negative ? "e-" : "e") + exponent;
  }
  return s;
}

std::string default_text(const Vec3& v) {
  std::string s(1, '[');  // (appended, not "[" + s: GCC 12's -Wrestrict false positive)
  s.append(default_text(v[0])).append(", ").append(default_text(v[1])).append(", ").append(default_text(v[2])).append("]");
  return s;
}

std::string default_text(const std::string& v) { return v.empty() ? "" : "\"" + v + "\""; }

}  // namespace tactus::solver::keys
