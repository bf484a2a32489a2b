// The typed reading of an experiment config's TOML nodes: every getter checks the node's type and
// range and throws InputError "FILE:LINE: KEY: what is wrong" (experiments/config.cpp uses it to
// parse whole configs). Header-only: only config.cpp and config_settings.cpp include it (toml++ is
// heavy to compile).
#pragma once
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include "builders/builder.hpp"
#include "builders/update.hpp"
#include "datasets/scene.hpp"  // InputError
#include "experiments/config.hpp"
#include "experiments/generated_scenes.hpp"
#include "render/workloads.hpp"
#if __has_include("traversal/kernels.hpp")
#include "traversal/kernels.hpp"
#define BVHLAB_HAVE_KERNEL_REGISTRY 1
#endif

namespace bvhlab::config_detail {

namespace fs = std::filesystem;
using nlohmann::json;

const std::vector<std::string> kStorages = {"tbo", "tex2d", "ssbo"};
// "smaa" is SMAA with --smaa-preset (high by default); "smaa-PRESET" names the preset in the axis.
const std::vector<std::string> kAntialiasing = {"none",        "smaa",      "smaa-low", "smaa-medium",
                                                "smaa-high",   "smaa-ultra", "ssaa4",   "ssaa16"};
#ifdef BVHLAB_HAVE_KERNEL_REGISTRY
inline const std::vector<std::string>& kRobustness = robustnessNames();
#else
const std::vector<std::string> kRobustness = {"fast", "watertight"};
#endif
const std::vector<std::string> kBranching = {"full", "report"};
const std::vector<std::string> kSmaaEdges = {"luma", "color", "geometry"};
const std::vector<std::string> kTextureLod = {"none", "cones", "cones-aniso"};
const std::vector<std::string> kViews = {"shaded", "normal", "depth", "primid", "visits"};
const std::vector<std::string> kBackends = {"osmesa", "egl"};
inline const std::vector<std::string>& kWorkloads = workloadNames();  // render/workloads.hpp
constexpr const char* kDefaultKernel = "default";  // a kernel value: the run's layout's default kernel
constexpr const char* kEveryValue = "all";         // `layouts = "all"`, `kernels = "all"`, `triangle_formats`

inline std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

inline std::string typeName(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a float";
    case toml::node_type::boolean: return "a boolean";
    case toml::node_type::array: return "an array";
    case toml::node_type::table: return "a table";
    default: return "a date/time";
  }
}

// Parses one config file; every error names the file, line and key.
class ConfigReader {
 public:
  ConfigReader(const fs::path& file, const KnownNames& names)
      : file_(file), dir_(file.parent_path()), names_(names) {}

  [[noreturn]] void fail(const toml::source_region& where, const std::string& key,
                         const std::string& what) const {
    std::ostringstream msg;
    msg << file_.string();
    if (where.begin.line > 0) msg << ':' << where.begin.line;
    msg << ": " << key << ": " << what;
    throw InputError(msg.str());
  }

  std::string string(const toml::node& node, const std::string& key) const {
    if (!node.is_string()) fail(node.source(), key, "expected a string, got " + typeName(node));
    return node.as_string()->get();
  }
  int64_t integer(const toml::node& node, const std::string& key, int64_t lo, int64_t hi) const {
    if (!node.is_integer()) fail(node.source(), key, "expected an integer, got " + typeName(node));
    const int64_t v = node.as_integer()->get();
    if (v < lo || v > hi)
      fail(node.source(), key, std::to_string(v) + " is outside " + std::to_string(lo) + ".." + std::to_string(hi));
    return v;
  }
  bool boolean(const toml::node& node, const std::string& key) const {
    if (!node.is_boolean()) fail(node.source(), key, "expected true or false, got " + typeName(node));
    return node.as_boolean()->get();
  }
  double number(const toml::node& node, const std::string& key) const {
    if (node.is_integer()) return double(node.as_integer()->get());
    if (!node.is_floating_point()) fail(node.source(), key, "expected a number, got " + typeName(node));
    const double v = node.as_floating_point()->get();
    if (!std::isfinite(v)) fail(node.source(), key, "expected a finite number, got " + std::to_string(v));
    return v;
  }
  const toml::table& table(const toml::node& node, const std::string& key) const {
    if (!node.is_table()) fail(node.source(), key, "expected a table, got " + typeName(node));
    return *node.as_table();
  }
  std::string oneOf(const toml::node& node, const std::string& key, const std::vector<std::string>& valid,
                    const char* what) const {
    std::string v = string(node, key);
    if (!valid.empty() && std::find(valid.begin(), valid.end(), v) == valid.end())
      fail(node.source(), key, "unknown " + std::string(what) + " '" + v + "'; valid: " + joined(valid));
    return v;
  }
  json vec3(const toml::node& node, const std::string& key) const {
    const toml::array* a = node.as_array();
    if (!a || a->size() != 3) fail(node.source(), key, "expected [x, y, z], got " + typeName(node));
    json out = json::array();
    for (const toml::node& c : *a) out.push_back(number(c, key));
    return out;
  }

  // One value of one axis, e.g. an element of `builders = [...]`.
  AxisValue axisValue(const AxisInfo& axis, const toml::node& node, const std::string& key) const {
    const std::string_view a = axis.singular;
    if (a == "scene") return sceneValue(node, key);
    if (a == "builder") return builderValue(node, key);
    if (a == "update") {
      // An update strategy's spec (builders/update.hpp); the run traces the scene's clip with it.
      const std::string spec = string(node, key);
      try {
        parseUpdateSpec(spec);
      } catch (const std::invalid_argument& e) {
        fail(node.source(), key, e.what());
      }
      return {spec, spec, {}};
    }
    if (a == "kernel") {
      // "default": the run's layout's default kernel (experiments/config.cpp pairs them).
      std::vector<std::string> valid = names_.kernels;
      if (!valid.empty()) valid.push_back(kDefaultKernel);
      std::string k = oneOf(node, key, valid, "kernel");
      return {k, k, {}};
    }
    if (a == "triangle_format") {
      std::string f = oneOf(node, key, names_.triangleFormats, "triangle format");
      return {f, f, {}};
    }
    if (a == "layout") {
      std::vector<std::string> valid;
      for (const KnownLayout& l : names_.layouts) valid.push_back(l.name);
      std::string l = oneOf(node, key, valid, "layout");
      return {l, l, {}};
    }
    if (a == "leaf_size" || a == "depth") {
      // Leaves hold at most 255 triangles (layout/layout.hpp); the depth bound only catches typos.
      const int64_t v = a == "leaf_size" ? integer(node, key, 1, 255) : integer(node, key, 1, 1000);
      return {std::to_string(v), v, {}};
    }
    if (a == "uber") {
      const bool v = boolean(node, key);
      return {v ? "true" : "false", v, {}};
    }
    const std::vector<std::string>& valid = a == "storage"  ? kStorages
                                            : a == "aa"     ? kAntialiasing
                                            : a == "robust" ? kRobustness
                                            : a == "branching" ? kBranching
                                            : a == "smaa_edges" ? kSmaaEdges
                                            : a == "texture_lod" ? kTextureLod
                                            : a == "workload" ? kWorkloads
                                                               : kViews;
    std::string v = oneOf(node, key, valid, std::string(a).c_str());
    return {v, v, {}};
  }

  AxisValue sceneValue(const toml::node& node, const std::string& key) const {
    AxisValue out;
    const toml::node* fileNode = &node;
    const toml::node* generateNode = nullptr;
    std::string label;
    json value = json::object();
    if (node.is_table()) {
      const toml::table& t = *node.as_table();
      fileNode = nullptr;
      for (auto&& [k, v] : t) {
        const std::string sub = key + "." + std::string(k.str());
        if (k == "file") fileNode = &v;
        else if (k == "generate") {
          generateNode = &v;
          value["generate"] = oneOf(v, sub, generatedMeshKinds(), "generator");
        } else if (k == "triangles") {
          // makeLargeMesh needs >= 100; the layout addresses at most 2^28 - 1 triangles.
          value["triangles"] = integer(v, sub, 100, (int64_t(1) << 28) - 1);
        } else if (k == "seed") value["seed"] = integer(v, sub, 0, std::numeric_limits<int64_t>::max());
        else if (k == "clip_step") value["clip_step"] = integer(v, sub, 1, 1 << 20);  // [trace]'s, for this scene
        else if (k == "clip_frames") value["clip_frames"] = integer(v, sub, 0, 1 << 20);
        else if (k == "count") value["count"] = integer(v, sub, 1, int64_t(1) << 24);
        else if (k == "name") label = string(v, sub);
        else if (k == "eye" || k == "target" || k == "up") value[std::string(k.str())] = vec3(v, sub);
        else if (k == "fov") {
          const double fov = number(v, sub);
          if (!(fov > 0.0 && fov < 180.0)) fail(v.source(), sub, "field of view must be in (0, 180) degrees");
          value["fov"] = fov;
        } else
          fail(k.source(), sub, "unknown key; a scene table has file or generate (+ triangles, seed), name, eye, "
                                "target, up, fov, count, clip_step, clip_frames");
      }
      if (generateNode) {
        if (fileNode) fail(fileNode->source(), key, "a scene has `file` or `generate`, not both");
        if (!value.contains("triangles")) fail(generateNode->source(), key, "`generate` needs `triangles`");
        if (!value.contains("seed")) value["seed"] = 1;
        out.label = label.empty() ? value["generate"].get<std::string>() + "-" +
                                        std::to_string(value["triangles"].get<int64_t>())
                                  : label;
        out.value = value;
        return out;  // the file is written by the runner (generated_scenes.hpp)
      }
      if (value.contains("triangles") || value.contains("seed"))
        fail(node.source(), key, "`triangles` and `seed` go with `generate`");
      if (!fileNode) fail(node.source(), key, "a scene table needs `file` (or `generate`)");
    } else if (!node.is_string()) {
      fail(node.source(), key, "expected a scene/mesh file path or a table {file = ..., ...}, got " + typeName(node));
    }
    const std::string written = string(*fileNode, key);
    fs::path resolved = fs::path(written).is_absolute() ? fs::path(written) : dir_ / written;
    std::error_code ec;
    if (!fs::is_regular_file(resolved, ec))
      fail(fileNode->source(), key,
           "scene/mesh file '" + written + "' not found (looked at " + resolved.lexically_normal().string() + ")" +
               (written.find("datasets/cache") != std::string::npos ? "; run `bash datasets/fetch.sh` first" : ""));
    value["file"] = written;
    out.label = label.empty() ? fs::path(written).stem().string() : label;
    out.value = value;
    out.file = resolved.lexically_normal();
    return out;
  }

  AxisValue builderValue(const toml::node& node, const std::string& key) const {
    if (!node.is_table()) {
      std::string name = oneOf(node, key, names_.builders, "builder");
      return {name, json{{"name", name}}, {}};
    }
    const toml::table& t = *node.as_table();
    std::string name, label;
    json value = json::object();
    const toml::node* nameNode = nullptr;
    for (auto&& [k, v] : t) {
      const std::string sub = key + "." + std::string(k.str());
      if (k == "name") {
        name = oneOf(v, sub, names_.builders, "builder");
        nameNode = &v;
      } else if (k == "label") label = string(v, sub);
      else if (k == "bins") value["bins"] = integer(v, sub, 2, 1 << 16);  // fewer than 2 bins cannot split
      else if (k == "optimize") value["optimize"] = oneOf(v, sub, optimizePasses(), "optimize pass");
      else if (k == "sbvh_alpha") {
        const double a = number(v, sub);
        if (!(a >= 0.0 && a <= 1.0)) fail(v.source(), sub, "must be in 0..1 (a fraction of the root's area)");
        value["sbvh_alpha"] = a;
      } else if (k == "sbvh_budget") {
        const double b = number(v, sub);
        if (!(b >= 1.0 && std::isfinite(b))) fail(v.source(), sub, "must be a finite number >= 1 (leaf references per primitive)");
        value["sbvh_budget"] = b;
      } else if (k == "ploc_radius") value["ploc_radius"] = integer(v, sub, 1, 1024);
      else if (k == "ploc_top_down") value["ploc_top_down"] = integer(v, sub, 0, kMaxPlocTopDown);
      else if (k == "morton_size_bits") value["morton_size_bits"] = integer(v, sub, 0, kMaxMortonSizeBits);
      else if (k == "morton_grid") value["morton_grid"] = oneOf(v, sub, mortonGridNames(), "Morton grid");
      else fail(k.source(), sub,
                "unknown key; a builder table has name, bins, optimize, sbvh_alpha, sbvh_budget, ploc_radius, ploc_top_down, morton_size_bits, "
                "morton_grid, label");
    }
    if (!nameNode) fail(node.source(), key, "a builder table needs `name`");
    value["name"] = name;
    if (label.empty()) {
      label = name;
      if (value.contains("bins")) label += "[bins=" + std::to_string(value["bins"].get<int64_t>()) + "]";
      if (value.contains("sbvh_alpha")) label += "[alpha=" + value["sbvh_alpha"].dump() + "]";
      if (value.contains("sbvh_budget")) label += "[budget=" + value["sbvh_budget"].dump() + "]";
      if (value.contains("ploc_radius")) label += "[radius=" + std::to_string(value["ploc_radius"].get<int64_t>()) + "]";
      if (value.contains("ploc_top_down"))
        label += "[top-down=" + std::to_string(value["ploc_top_down"].get<int64_t>()) + "]";
      if (value.contains("morton_size_bits"))
        label += "[size-bits=" + std::to_string(value["morton_size_bits"].get<int64_t>()) + "]";
      if (value.contains("morton_grid")) label += "[grid=" + value["morton_grid"].get<std::string>() + "]";
      if (value.contains("optimize")) label += "+" + value["optimize"].get<std::string>();
    }
    return {label, value, {}};
  }

  // `key = value` or `key = [values]` in [axes] / [[sweep]]: the values, in order. `layouts = "all"`
  // is every registered layout, `kernels = "all"` every registered kernel (each run keeps those that
  // walk its layout), `triangle_formats = "all"` every triangle format (each run keeps those its
  // robustness variant can run): a config written that way picks up new ones without an edit.
  std::vector<AxisValue> axisValues(const AxisInfo& axis, const toml::node& node, const std::string& key) const {
    std::vector<AxisValue> out;
    if (isEveryValue(axis, node)) {
      if (axis.singular == "layout")
        for (const KnownLayout& l : names_.layouts) out.push_back({l.name, l.name, {}});
      else if (axis.singular == "triangle_format")
        for (const std::string& f : names_.triangleFormats) out.push_back({f, f, {}});
      else
        for (const std::string& k : names_.kernels) out.push_back({k, k, {}});
      if (out.empty()) fail(node.source(), key, "\"all\" needs the renderer's registry, which is not built in");
    } else if (const toml::array* a = node.as_array()) {
      if (a->empty()) fail(node.source(), key, "empty list (an axis needs at least one value)");
      for (size_t i = 0; i < a->size(); ++i)
        out.push_back(axisValue(axis, *a->get(i), key + "[" + std::to_string(i) + "]"));
    } else {
      out.push_back(axisValue(axis, node, key));
    }
    std::set<std::string> labels;
    for (const AxisValue& v : out)
      if (!labels.insert(v.label).second)
        fail(node.source(), key, "value '" + v.label + "' appears twice (labels must be unique; give a `name`/`label`)");
    return out;
  }

  // `layouts = "all"` / `kernels = "all"` / `triangle_formats = "all"`.
  static bool isEveryValue(const AxisInfo& axis, const toml::node& node) {
    return (axis.singular == "layout" || axis.singular == "kernel" || axis.singular == "triangle_format") &&
           node.is_string() &&
           node.as_string()->get() == kEveryValue;
  }

  const fs::path& file() const { return file_; }
  const fs::path& dir() const { return dir_; }
  const KnownNames& names() const { return names_; }

 private:
  fs::path file_, dir_;
  const KnownNames& names_;
};

using AxisMap = std::map<std::string, std::vector<AxisValue>>;  // singular -> values

}  // namespace bvhlab::config_detail
