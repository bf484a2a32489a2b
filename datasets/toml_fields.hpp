// Typed, validated reads of TOML values for the scene-file readers (scene_reader.cpp, animation_reader.cpp):
// every refusal is one InputError line "FILE:LINE: message" naming the key.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/glm.hpp>
#include <toml++/toml.h>

#include "datasets/scene.hpp"

namespace bvhlab {
namespace toml_fields {

struct Range {
  double lo, hi;
  bool loOpen, hiOpen;
  bool contains(double v) const {
    return (loOpen ? v > lo : v >= lo) && (hiOpen ? v < hi : v <= hi);
  }
  std::string describe() const {
    auto num = [](double x) {
      std::ostringstream s;
      s << x;
      return s.str();
    };
    if (std::isinf(hi)) return std::string(loOpen ? "> " : ">= ") + num(lo);
    return std::string(loOpen ? "(" : "[") + num(lo) + ", " + num(hi) + (hiOpen ? ")" : "]");
  }
};
inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr Range kNonNegative{0.0, kInf, false, true};
inline constexpr Range kPositive{0.0, kInf, true, true};
inline constexpr Range kUnit{0.0, 1.0, false, false};
inline constexpr Range kAny{-kInf, kInf, true, true};

inline std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// The checks shared by the readers of one scene file; `file_` names the file in every message.
class TomlFields {
 public:
  explicit TomlFields(std::filesystem::path file) : file_(std::move(file)) {}

 protected:
  std::filesystem::path file_;

  // ---- errors ----
  [[noreturn]] void failAt(size_t line, const std::string& message) const {
    throw InputError(file_.string() + ":" + std::to_string(line) + ": " + message);
  }
  [[noreturn]] void fail(const toml::node& node, const std::string& message) const {
    failAt(node.source().begin.line, message);
  }

  // ---- structure ----
  void checkKeys(const toml::table& t, std::initializer_list<std::string_view> allowed, const std::string& where) const {
    for (auto&& [key, node] : t) {
      if (std::find(allowed.begin(), allowed.end(), key.str()) != allowed.end()) continue;
      std::string list;
      for (std::string_view a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      failAt(key.source().begin.line ? key.source().begin.line : node.source().begin.line,
             "unknown key '" + std::string(key.str()) + "' in " + where + " (allowed: " + list + ")");
    }
  }

  const toml::table* tableAt(const toml::table& root, std::string_view key) const {
    const toml::node* n = root.get(key);
    if (!n) return nullptr;
    if (!n->is_table()) fail(*n, "'" + std::string(key) + "' must be a table: write [" + std::string(key) + "]");
    return n->as_table();
  }

  std::vector<const toml::table*> tableArray(const toml::table& root, std::string_view key) const {
    std::vector<const toml::table*> out;
    const toml::node* n = root.get(key);
    if (!n) return out;
    const toml::array* a = n->as_array();
    if (!a || !a->is_array_of_tables())
      fail(*n, "'" + std::string(key) + "' must be an array of tables: write [[" + std::string(key) + "]]");
    for (const toml::node& e : *a) out.push_back(e.as_table());
    return out;
  }

  // ---- typed values ----
  double number(const toml::node& n, const std::string& name, Range range = kAny) const {
    if (!n.is_number()) fail(n, name + " must be a number");
    const double v = n.value<double>().value_or(0.0);
    if (!std::isfinite(v)) fail(n, name + " is NaN or infinite");
    if (!range.contains(v)) fail(n, name + " must be " + range.describe() + " (got " + fmt(v) + ")");
    return v;
  }
  float getFloat(const toml::table& t, std::string_view key, const std::string& where, float def,
                 Range range = kAny) const {
    const toml::node* n = t.get(key);
    return n ? float(number(*n, where + "." + std::string(key), range)) : def;
  }
  int getInt(const toml::table& t, std::string_view key, const std::string& where, int def, int lo, int hi) const {
    const toml::node* n = t.get(key);
    if (!n) return def;
    const std::string name = where + "." + std::string(key);
    if (!n->is_integer()) fail(*n, name + " must be an integer");
    const int64_t v = n->value<int64_t>().value_or(0);
    if (v < lo || v > hi) fail(*n, name + " must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "] (got " + std::to_string(v) + ")");
    return int(v);
  }
  bool getBool(const toml::table& t, std::string_view key, const std::string& where, bool def) const {
    const toml::node* n = t.get(key);
    if (!n) return def;
    if (!n->is_boolean()) fail(*n, where + "." + std::string(key) + " must be true or false");
    return n->value<bool>().value_or(def);
  }
  std::optional<std::string> getString(const toml::table& t, std::string_view key, const std::string& where) const {
    const toml::node* n = t.get(key);
    if (!n) return std::nullopt;
    if (!n->is_string()) fail(*n, where + "." + std::string(key) + " must be a string");
    return n->value<std::string>();
  }
  std::string requireString(const toml::table& t, std::string_view key, const std::string& where) const {
    auto s = getString(t, key, where);
    if (!s) failAt(t.source().begin.line, where + ": missing required key '" + std::string(key) + "'");
    return *s;
  }
  // An array of exactly N numbers, each in `range`.
  template <int N>
  glm::vec<N, float> vecOf(const toml::node& n, const std::string& name, Range range = kAny) const {
    const toml::array* a = n.as_array();
    if (!a || a->size() != size_t(N)) fail(n, name + " must be an array of " + std::to_string(N) + " numbers");
    glm::vec<N, float> v;
    for (int i = 0; i < N; ++i) v[i] = float(number(*a->get(size_t(i)), name + "[" + std::to_string(i) + "]", range));
    return v;
  }
  glm::dvec3 pointOf(const toml::node& n, const std::string& name) const {
    const toml::array* a = n.as_array();
    if (!a || a->size() != 3) fail(n, name + " must be an array of 3 numbers");
    glm::dvec3 v;
    for (int i = 0; i < 3; ++i) v[i] = number(*a->get(size_t(i)), name + "[" + std::to_string(i) + "]");
    return v;
  }
  std::optional<glm::vec3> getVec3(const toml::table& t, std::string_view key, const std::string& where,
                                   Range range = kAny) const {
    const toml::node* n = t.get(key);
    if (!n) return std::nullopt;
    return vecOf<3>(*n, where + "." + std::string(key), range);
  }
  glm::vec3 requireVec3(const toml::table& t, std::string_view key, const std::string& where, Range range = kAny) const {
    auto v = getVec3(t, key, where, range);
    if (!v) failAt(t.source().begin.line, where + ": missing required key '" + std::string(key) + "'");
    return *v;
  }
  // A number s (meaning [s, s, s] / [s, s]) or an array of N numbers.
  template <int N>
  glm::vec<N, float> scalarOrVec(const toml::node& n, const std::string& name, Range range) const {
    if (n.is_number()) return glm::vec<N, float>(float(number(n, name, range)));
    return vecOf<N>(n, name, range);
  }

  // Keys that only some kinds accept: a clear message instead of a bare "unknown key".
  void rejectForeignKeys(const toml::table& t, const std::string& where, const std::string& kind,
                         std::initializer_list<std::pair<std::string_view, std::string_view>> keyToKind) const {
    for (auto [key, owner] : keyToKind)
      if (owner != kind)
        if (const toml::node* n = t.get(key))
          fail(*n, where + ": key '" + std::string(key) + "' is only valid with kind = \"" + std::string(owner) + "\"");
  }
};

}  // namespace toml_fields
}  // namespace bvhlab
