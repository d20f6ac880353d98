#pragma once
// One declaration per scenario key: each key is bound to the struct member it fills, together with
// its type, unit, range and doc (as FEBio's ADD_PARAMETER and deal.II's add_parameter do). The
// reader fills the member from the declaration, and the reference (docs/scenario-reference.md)
// prints the member's own initial value as the default, so a default is written once: where the
// member is declared. Private to the scenario reader (scenario.cpp).
#include <toml++/toml.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tactus/core/error.hpp"
#include "tactus/core/vec3.hpp"
#include "tactus/solver/parameters.hpp"

namespace tactus::solver::keys {

const char* type_name(ValueType t);

// Reads and checks single values of one scenario file; every failure names the key's full path.
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& expected, const std::string& found = {}) const {
    throw InputError(file_, key, expected, found);
  }
  // Unknown keys and missing required keys of one table.
  void check_keys(const toml::table& t, const SectionSpec& spec, const std::string& path, const std::set<std::string>& extra = {}) const;

  double number(const toml::table& t, const ValueSpec& s, const std::string& path, double def) const;
  // A whole number: a TOML integer, or a float without a fractional part (1e7 as max_steps
  // documents it); 2.5 is refused naming the key, never rounded.
  std::int64_t integer(const toml::table& t, const ValueSpec& s, const std::string& path) const;
  bool boolean(const toml::table& t, const ValueSpec& s, const std::string& path, bool def) const;
  std::string string(const toml::table& t, const ValueSpec& s, const std::string& path, std::string def = {}) const;
  Vec3 vec3(const toml::node& n, const std::string& key, const std::string& unit) const;
  Vec3 vec3(const toml::table& t, const ValueSpec& s, const std::string& path, Vec3 def) const;
  std::vector<Vec3> vec3_list(const toml::table& t, const ValueSpec& s, const std::string& path) const;
  std::vector<double> number_list(const toml::table& t, const ValueSpec& s, const std::string& path) const;
  const toml::table& table(const toml::node& n, const std::string& key) const;
  // Each table of an array of tables ([[key]]), handed to visit(table, path) with path "key[i]".
  template <class Visit>
  void each_table(const toml::node& n, const std::string& key, Visit&& visit) const {
    const toml::array* arr = n.as_array();
    if (!arr) fail(key, "[[" + key + "]] tables", describe(n));
    for (std::size_t i = 0; i < arr->size(); ++i) {
      const std::string path = key + "[" + std::to_string(i) + "]";
      visit(table((*arr)[i], path), path);
    }
  }

  static std::string join(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }
  static std::string unit_suffix(const ValueSpec& s) { return s.unit.empty() ? "" : " in " + s.unit; }
  // A value as the user wrote it (an array with its values, so the wrong one shows: "[0.1, nan, 0]").
  static std::string describe(const toml::node& n);

 private:
  void check_range(double v, const ValueSpec& s, const std::string& key) const;
  std::string file_;
};

// How a default is shown in the reference.
std::string default_text(double v);
std::string default_text(const Vec3& v);
std::string default_text(const std::string& v);

// A key of the section whose values fill an S: its declaration and how it fills the member.
template <class S>
struct Key {
  ValueSpec spec;
  std::function<void(const Reader&, const toml::table&, const std::string& path, S&)> read;  // called when the key is present
};

// A section (a table, or each table of an array of tables) bound to the struct S it fills.
template <class S>
struct Section {
  std::string name, doc;
  std::vector<Key<S>> keys;

  SectionSpec spec() const {
    SectionSpec s{name, doc, {}};
    for (const Key<S>& k : keys) s.keys.push_back(k.spec);
    return s;
  }
  // Checks the table's keys, then fills `out` (which holds the defaults) from those present.
  void read(const Reader& r, const toml::table& t, const std::string& path, S& out, const std::set<std::string>& extra = {}) const {
    r.check_keys(t, spec(), path, extra);
    for (const Key<S>& k : keys)
      if (t.contains(k.spec.key)) k.read(r, t, path, out);
  }
};

// The declaration helpers: `spec` carries key, unit, range and doc (parameters.hpp's number(),
// required unless opt(), or declare()); `note` follows the default in the reference ("0 (off)").
using ::tactus::solver::number;
inline ValueSpec opt(ValueSpec s) {
  s.required = false;
  return s;
}
inline ValueSpec declare(std::string key, std::string unit, std::string doc, bool required = false) {
  ValueSpec s;
  s.key = std::move(key);
  s.unit = std::move(unit);
  s.doc = std::move(doc);
  s.required = required;
  return s;
}

inline ValueSpec with_default(ValueSpec s, ValueType type, const std::string& text, const std::string& note) {
  s.type = type;
  if (!s.required) s.default_text = text.empty() ? note : note.empty() ? text : text + " (" + note + ")";
  return s;
}

template <class S>
Key<S> bind_key(double S::*m, ValueSpec s, const std::string& note = {}) {
  s = with_default(std::move(s), ValueType::number, default_text(S{}.*m), note);
  return {s, [m, s](const Reader& r, const toml::table& t, const std::string& p, S& o) { o.*m = r.number(t, s, p, o.*m); }};
}
// A count kept in a double (max_steps = 1e7) or an int: whole numbers only.
template <class S>
Key<S> bind_count(double S::*m, ValueSpec s, const std::string& note = {}) {
  s = with_default(std::move(s), ValueType::integer, default_text(S{}.*m), note);
  return {s, [m, s](const Reader& r, const toml::table& t, const std::string& p, S& o) { o.*m = static_cast<double>(r.integer(t, s, p)); }};
}
template <class S>
Key<S> bind_key(int S::*m, ValueSpec s, const std::string& note = {}) {
  if (!(s.max <= 2147483647.0)) s.max = 2147483647.0;
  if (!(s.min >= -2147483647.0)) s.min = -2147483647.0;
  s = with_default(std::move(s), ValueType::integer, default_text(static_cast<double>(S{}.*m)), note);
  return {s, [m, s](const Reader& r, const toml::table& t, const std::string& p, S& o) { o.*m = static_cast<int>(r.integer(t, s, p)); }};
}
template <class S>
Key<S> bind_key(bool S::*m, ValueSpec s, const std::string& note = {}) {
  s = with_default(std::move(s), ValueType::boolean, S{}.*m ? "true" : "false", note);
  return {s, [m, s](const Reader& r, const toml::table& t, const std::string& p, S& o) { o.*m = r.boolean(t, s, p, o.*m); }};
}
template <class S>
Key<S> bind_key(std::string S::*m, ValueSpec s, const std::string& note = {}) {
  s = with_default(std::move(s), ValueType::string, default_text(S{}.*m), note);
  return {s, [m, s](const Reader& r, const toml::table& t, const std::string& p, S& o) { o.*m = r.string(t, s, p); }};
}
// A file name, kept as written (resolved against the scenario's folder by the section's reader).
template <class S>
Key<S> bind_key(std::filesystem::path S::*m, ValueSpec s, const std::string& note = {}) {
  s = with_default(std::move(s), ValueType::string, default_text((S{}.*m).string()), note);
  return {s, [m, s](const Reader& r, const toml::table& t, const std::string& p, S& o) { o.*m = r.string(t, s, p); }};
}
template <class S>
Key<S> bind_key(Vec3 S::*m, ValueSpec s, const std::string& note = {}) {
  s = with_default(std::move(s), ValueType::vec3, default_text(S{}.*m), note);
  return {s, [m, s](const Reader& r, const toml::table& t, const std::string& p, S& o) { o.*m = r.vec3(t, s, p, o.*m); }};
}
// A vector given or not (no default value: absent means "not given").
template <class S>
Key<S> bind_key(std::optional<Vec3> S::*m, ValueSpec s, const std::string& note = {}) {
  s = with_default(std::move(s), ValueType::vec3, "", note);
  return {s, [m, s](const Reader& r, const toml::table& t, const std::string& p, S& o) { o.*m = r.vec3(t, s, p, Vec3{0, 0, 0}); }};
}
// A number given or not (absent: "not given", e.g. a cylinder's radius on another kind of mesh).
template <class S>
Key<S> bind_key(std::optional<double> S::*m, ValueSpec s, const std::string& note = {}) {
  s = with_default(std::move(s), ValueType::number, "", note);
  return {s, [m, s](const Reader& r, const toml::table& t, const std::string& p, S& o) { o.*m = r.number(t, s, p, 0.0); }};
}
template <class S>
Key<S> bind_key(std::vector<double> S::*m, ValueSpec s, const std::string& note = {}) {
  std::string text = "[";
  const S defaults{};  // (named: a range-for over a member of a temporary outlives the temporary)
  for (double v : defaults.*m) text += (text.size() > 1 ? ", " : "") + default_text(v);
  s = with_default(std::move(s), ValueType::number_list, text + "]", note);
  return {s, [m, s](const Reader& r, const toml::table& t, const std::string& p, S& o) { o.*m = r.number_list(t, s, p); }};
}
template <class S>
Key<S> bind_key(std::vector<Vec3> S::*m, ValueSpec s, const std::string& note = {}) {
  s = with_default(std::move(s), ValueType::vec3_list, "", note);
  return {s, [m, s](const Reader& r, const toml::table& t, const std::string& p, S& o) { o.*m = r.vec3_list(t, s, p); }};
}
// Two points ([min, max] of a box, or a plane's point and normal): `shape` says what is expected.
template <class S>
Key<S> bind_key(std::optional<std::array<Vec3, 2>> S::*m, ValueSpec s, std::string shape) {
  s = with_default(std::move(s), ValueType::vec3_list, "", "");
  return {s, [m, s, shape](const Reader& r, const toml::table& t, const std::string& p, S& o) {
            const std::vector<Vec3> v = r.vec3_list(t, s, p);
            if (v.size() != 2) r.fail(Reader::join(p, s.key), shape, "an array of " + std::to_string(v.size()));
            o.*m = std::array<Vec3, 2>{v[0], v[1]};
          }};
}

// An enumeration, validated once here: the member holds the enum, never the string.
template <class S, class E>
Key<S> bind_key(E S::*m, ValueSpec s, std::vector<Choice<E>> choices, const std::string& note = {}) {
  std::string doc, names;
  for (const Choice<E>& c : choices) {
    doc += (doc.empty() ? "" : " | ") + std::string(c.name) + (*c.doc ? std::string(" (") + c.doc + ")" : "");
    names += (names.empty() ? "\"" : ", \"") + std::string(c.name) + "\"";
  }
  s.doc += (s.doc.empty() ? "" : ": ") + doc;
  for (const Choice<E>& c : choices) s.choices.push_back(c.name);
  s = with_default(std::move(s), ValueType::string, "\"" + name_of(S{}.*m, choices) + "\"", note);
  return {s, [m, s, choices, names](const Reader& r, const toml::table& t, const std::string& p, S& o) {
            const std::string given = r.string(t, s, p);
            for (const Choice<E>& c : choices)
              if (given == c.name) {
                o.*m = c.value;
                return;
              }
            r.fail(Reader::join(p, s.key), "one of " + names, "\"" + given + "\"");
          }};
}

// A key whose value needs its own reading (a table of names, a set of letters): `read` fills the
// members from the value (given its own declaration), `text` is the default shown for S{}.
template <class S>
Key<S> bind_custom(ValueSpec s, ValueType type, std::function<std::string(const S&)> text,
                   std::function<void(const Reader&, const ValueSpec&, const toml::table&, const std::string&, S&)> read) {
  s = with_default(std::move(s), type, text ? text(S{}) : "", "");
  return {s, [s, read](const Reader& r, const toml::table& t, const std::string& p, S& o) { read(r, s, t, p, o); }};
}

}  // namespace tactus::solver::keys
