#include "experiments/config.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <unordered_map>

#include <toml++/toml.h>

#include "builders/builder.hpp"
#include "datasets/scene.hpp"  // InputError
#include "experiments/generated_scenes.hpp"
#include "render/fly_camera.hpp"
#if __has_include("traversal/kernels.hpp")
#include "traversal/kernels.hpp"
#define BVHLAB_HAVE_KERNEL_REGISTRY 1
#endif

namespace bvhlab {

namespace fs = std::filesystem;
using nlohmann::json;

const std::vector<AxisInfo>& experimentAxes() {
  static const std::vector<AxisInfo> axes = {
      {"scenes", "scene", ""},  // the scene is the positional INPUT of `bvhlab render`
      {"builders", "builder", "--builder"},
      {"kernels", "kernel", "--kernel"},
      {"leaf_sizes", "leaf_size", "--leaf-size"},
      {"depths", "depth", "--depth"},
      {"storages", "storage", "--storage"},
      {"aa", "aa", "--aa"},
      {"robust", "robust", "--robust"},
      {"branching", "branching", "--branching"},
      {"views", "view", "--view"},
      {"uber", "uber", "--uber"},
      {"smaa_edges", "smaa_edges", "--smaa-edges"},
  };
  return axes;
}

const AxisInfo* findAxis(std::string_view name) {
  for (const AxisInfo& a : experimentAxes())
    if (a.plural == name || a.singular == name) return &a;
  return nullptr;
}

std::string hashHex(std::string_view bytes) {
  uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a 64 offset basis and prime (Fowler/Noll/Vo)
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

json RunRender::keyJson() const {
  json key{{"width", width},     {"height", height},     {"warmup", warmup}, {"frames", frames},
           {"backend", backend}, {"heatmaps", heatmaps}, {"env", env},       {"args", args}};
  if (!cameraPath.empty()) {  // only when set: keys of configs without a path stay as they were
    key["camera_path"] = cameraPath;
    key["camera_path_hash"] = cameraPathHash;
  }
  // How long a run is measured is part of what it is (a 2% interval is not a 5% one).
  key["max_frames"] = maxFrames;
  key["target_ci_pct"] = targetCiPct;
  if (maxSeconds > 0.0) key["max_seconds"] = maxSeconds;
  return key;
}

json RunRender::groupJson() const {
  json g = keyJson();
  g["group_size"] = groupSize;
  g["aa_control"] = aaControl;
  g["interleave"] = interleave;
  g["timeout_s"] = timeoutSeconds;
  return g;
}

const AxisValue* RunSpec::axis(std::string_view singular) const {
  for (const auto& [name, value] : axes)
    if (name == singular) return &value;
  return nullptr;
}

std::string RunSpec::describe() const {
  std::string out;
  for (const auto& [name, value] : axes) {
    if (!out.empty()) out += ' ';
    if (name == "scene" || name == "builder")
      out += value.label;
    else
      out += name + "=" + value.label;
  }
  return out;
}

json RunSpec::keyJson() const {
  json a = json::object();
  for (const auto& [name, value] : axes) a[name] = value.value;
  return json{{"axes", a}, {"render", render.keyJson()}};
}

json RunSpec::toJson() const {
  json a = json::array();
  for (const auto& [name, value] : axes) {
    json v{{"axis", name}, {"label", value.label}, {"value", value.value}};
    if (!value.file.empty()) v["file"] = value.file.string();
    a.push_back(v);
  }
  json r = render.groupJson();
  if (!render.cameraPathFile.empty()) r["camera_path_file"] = render.cameraPathFile.string();
  return json{{"index", index},   {"key", key},       {"axes", a},
              {"render", r},      {"sweeps", sweeps}, {"reference_key", referenceKey},
              {"reference_only", referenceOnly}};
}

RunSpec RunSpec::fromJson(const json& j) {
  RunSpec s;
  s.index = j.at("index").get<std::size_t>();
  s.key = j.at("key").get<std::string>();
  for (const json& v : j.at("axes")) {
    AxisValue value{v.at("label").get<std::string>(), v.at("value"), {}};
    if (v.contains("file")) value.file = v["file"].get<std::string>();
    s.axes.emplace_back(v.at("axis").get<std::string>(), std::move(value));
  }
  const json& r = j.at("render");
  s.render.width = r.at("width");
  s.render.height = r.at("height");
  s.render.warmup = r.at("warmup");
  s.render.frames = r.at("frames");
  s.render.backend = r.at("backend");
  s.render.heatmaps = r.at("heatmaps");
  s.render.env = r.at("env").get<std::map<std::string, std::string>>();
  s.render.args = r.at("args").get<std::vector<std::string>>();
  s.render.timeoutSeconds = r.value("timeout_s", s.render.timeoutSeconds);
  s.render.maxFrames = r.value("max_frames", s.render.frames);
  s.render.targetCiPct = r.value("target_ci_pct", s.render.targetCiPct);
  s.render.maxSeconds = r.value("max_seconds", s.render.maxSeconds);
  s.render.groupSize = r.value("group_size", s.render.groupSize);
  s.render.aaControl = r.value("aa_control", s.render.aaControl);
  s.render.interleave = r.value("interleave", s.render.interleave);
  s.render.cameraPath = r.value("camera_path", "");
  s.render.cameraPathHash = r.value("camera_path_hash", "");
  s.render.cameraPathFile = r.value("camera_path_file", "");
  s.sweeps = j.at("sweeps").get<std::vector<std::string>>();
  s.referenceKey = j.at("reference_key");
  s.referenceOnly = j.at("reference_only");
  return s;
}

KnownNames registeredNames() {
  KnownNames names;
  for (const BuilderInfo& b : builders()) names.builders.push_back(b.name);
#ifdef BVHLAB_HAVE_KERNEL_REGISTRY
  for (const KernelInfo& k : kernels()) names.kernels.push_back(k.name);
#endif
  return names;
}

namespace {

const std::vector<std::string> kStorages = {"tbo", "tex2d"};
// "smaa" is SMAA with --smaa-preset (high by default); "smaa-PRESET" names the preset in the axis.
const std::vector<std::string> kAntialiasing = {"none",        "smaa",      "smaa-low", "smaa-medium",
                                                "smaa-high",   "smaa-ultra", "ssaa4",   "ssaa16"};
#ifdef BVHLAB_HAVE_KERNEL_REGISTRY
const std::vector<std::string>& kRobustness = robustnessNames();
#else
const std::vector<std::string> kRobustness = {"fast", "watertight"};
#endif
const std::vector<std::string> kBranching = {"full", "report"};
const std::vector<std::string> kSmaaEdges = {"luma", "color"};
const std::vector<std::string> kViews = {"shaded", "normal", "depth", "primid", "visits"};
const std::vector<std::string> kBackends = {"osmesa", "egl"};

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

std::string typeName(const toml::node& node) {
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
    if (a == "kernel") {
      std::string k = oneOf(node, key, names_.kernels, "kernel");
      return {k, k, {}};
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
        else if (k == "name") label = string(v, sub);
        else if (k == "eye" || k == "target" || k == "up") value[std::string(k.str())] = vec3(v, sub);
        else if (k == "fov") {
          const double fov = number(v, sub);
          if (!(fov > 0.0 && fov < 180.0)) fail(v.source(), sub, "field of view must be in (0, 180) degrees");
          value["fov"] = fov;
        } else
          fail(k.source(), sub, "unknown key; a scene table has file or generate (+ triangles, seed), name, eye, "
                                "target, up, fov");
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
      else fail(k.source(), sub, "unknown key; a builder table has name, bins, label");
    }
    if (!nameNode) fail(node.source(), key, "a builder table needs `name`");
    value["name"] = name;
    if (label.empty()) {
      label = name;
      if (value.contains("bins")) label += "[bins=" + std::to_string(value["bins"].get<int64_t>()) + "]";
    }
    return {label, value, {}};
  }

  // `key = value` or `key = [values]` in [axes] / [[sweep]]: the values, in order.
  std::vector<AxisValue> axisValues(const AxisInfo& axis, const toml::node& node, const std::string& key) const {
    std::vector<AxisValue> out;
    if (const toml::array* a = node.as_array()) {
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

  const fs::path& file() const { return file_; }
  const fs::path& dir() const { return dir_; }

 private:
  fs::path file_, dir_;
  const KnownNames& names_;
};

using AxisMap = std::map<std::string, std::vector<AxisValue>>;  // singular -> values

struct Sweep {
  std::string name;
  AxisMap axes;
};

// A label in [[exclude]] names a value by its label, a builder by its name, a scene by its file.
bool namesValue(const std::string& axis, const std::string& label, const AxisValue& v) {
  return label == v.label || (axis == "builder" && label == v.value.value("name", "")) ||
         (axis == "scene" && label == v.value.value("file", ""));
}

// One [[exclude]] entry: a run is excluded when every listed axis has one of the listed values.
struct Exclusion {
  struct Condition {
    std::string axis;  // singular
    std::vector<std::string> labels;
    const toml::node* node;
    std::string key;
  };
  std::vector<Condition> conditions;

  bool matches(const RunSpec& run) const {
    for (const Condition& c : conditions) {
      const AxisValue* v = run.axis(c.axis);
      if (!v) return false;
      if (std::none_of(c.labels.begin(), c.labels.end(),
                       [&](const std::string& l) { return namesValue(c.axis, l, *v); }))
        return false;
    }
    return true;
  }
};

std::string scalarLabel(const ConfigReader& r, const toml::node& node, const std::string& key) {
  if (node.is_string()) return node.as_string()->get();
  if (node.is_integer()) return std::to_string(node.as_integer()->get());
  if (node.is_boolean()) return node.as_boolean()->get() ? "true" : "false";
  r.fail(node.source(), key, "expected a string, integer or boolean, got " + typeName(node));
}

void finishRun(RunSpec& run) {
  std::sort(run.axes.begin(), run.axes.end(), [](const auto& a, const auto& b) {
    auto rank = [](const std::string& n) {
      const auto& axes = experimentAxes();
      for (size_t i = 0; i < axes.size(); ++i)
        if (axes[i].singular == n) return i;
      return axes.size();
    };
    return rank(a.first) < rank(b.first);
  });
  run.key = hashHex(run.keyJson().dump());
}

}  // namespace

ExperimentConfig parseExperimentConfig(std::string_view text, const fs::path& file, const KnownNames& names) {
  ExperimentConfig cfg;
  cfg.file = file;
  cfg.text = std::string(text);
  cfg.hash = hashHex(text);
  cfg.name = file.stem().string();
  ConfigReader r(file, names);

  toml::table root;
  try {
    root = toml::parse(text, file.string());
  } catch (const toml::parse_error& e) {
    std::ostringstream msg;
    msg << file.string() << ':' << e.source().begin.line << ':' << e.source().begin.column
        << ": TOML syntax error: " << e.description();
    throw InputError(msg.str());
  }

  AxisMap topAxes;
  std::vector<Sweep> sweeps;
  std::vector<Exclusion> exclusions;
  const toml::table* referenceTable = nullptr;
  const toml::node* cameraPathNode = nullptr;
  const toml::node *framesNode = nullptr, *measureMinNode = nullptr, *maxFramesNode = nullptr;
  std::optional<int> measureMin;

  auto readAxes = [&](const toml::table& t, const std::string& section, AxisMap& out,
                      const std::set<std::string>& skip) {
    for (auto&& [k, v] : t) {
      const std::string name(k.str());
      if (skip.count(name)) continue;
      const std::string key = section + "." + name;
      const AxisInfo* axis = findAxis(name);
      if (!axis) {
        std::vector<std::string> valid;
        for (const AxisInfo& a : experimentAxes()) valid.emplace_back(a.plural);
        r.fail(k.source(), key, "unknown axis; valid axes: " + joined(valid));
      }
      const std::string singular(axis->singular);
      if (out.count(singular)) r.fail(k.source(), key, "axis given twice (as '" + std::string(axis->plural) +
                                                           "' and '" + std::string(axis->singular) + "')");
      out[singular] = r.axisValues(*axis, v, key);
    }
  };

  for (auto&& [k, v] : root) {
    const std::string section(k.str());
    if (section == "experiment") {
      for (auto&& [ek, ev] : r.table(v, section)) {
        const std::string key = "experiment." + std::string(ek.str());
        if (ek == "name") cfg.name = r.string(ev, key);
        else if (ek == "description") cfg.description = r.string(ev, key);
        else if (ek == "seed_figures") cfg.seedFigures = r.boolean(ev, key);
        else if (ek == "reference") referenceTable = &r.table(ev, key);
        else r.fail(ek.source(), key, "unknown key; [experiment] has name, description, reference, seed_figures");
      }
    } else if (section == "render") {
      for (auto&& [rk, rv] : r.table(v, section)) {
        const std::string key = "render." + std::string(rk.str());
        RunRender& out = cfg.render;
        // The size bound is the texture limit measured on llvmpipe (NOTES.md).
        if (rk == "width") out.width = int(r.integer(rv, key, 1, 16384));
        else if (rk == "height") out.height = int(r.integer(rv, key, 1, 16384));
        else if (rk == "warmup") out.warmup = int(r.integer(rv, key, 0, 1000000));
        else if (rk == "frames") {
          framesNode = &rv;
          out.frames = int(r.integer(rv, key, 1, 1000000));
        }
        else if (rk == "backend") out.backend = r.oneOf(rv, key, kBackends, "backend");
        else if (rk == "heatmaps") out.heatmaps = r.boolean(rv, key);
        else if (rk == "timeout_s") {
          out.timeoutSeconds = r.number(rv, key);
          if (!(out.timeoutSeconds > 0.0)) r.fail(rv.source(), key, "must be > 0 seconds");
        } else if (rk == "env") {
          for (auto&& [name, value] : r.table(rv, key))
            out.env[std::string(name.str())] = r.string(value, key + "." + std::string(name.str()));
        } else if (rk == "camera_path") {
          out.cameraPath = r.string(rv, key);
          if (out.cameraPath.empty()) r.fail(rv.source(), key, "empty path");
          const fs::path resolved =
              (fs::path(out.cameraPath).is_absolute() ? fs::path(out.cameraPath) : r.dir() / out.cameraPath)
                  .lexically_normal();
          std::ifstream in(resolved, std::ios::binary);
          if (!in) r.fail(rv.source(), key, "camera path '" + out.cameraPath + "' not found (looked at " +
                                                resolved.string() + ")");
          std::ostringstream bytes;
          bytes << in.rdbuf();
          try {
            parseCameraPath(bytes.str(), resolved.string());  // validated now, not when the run starts
          } catch (const InputError& e) {
            r.fail(rv.source(), key, e.what());
          }
          out.cameraPathFile = resolved;
          out.cameraPathHash = hashHex(bytes.str());
          cameraPathNode = &rv;
        } else if (rk == "args") {
          const toml::array* a = rv.as_array();
          if (!a) r.fail(rv.source(), key, "expected an array of strings, got " + typeName(rv));
          for (const toml::node& arg : *a) out.args.push_back(r.string(arg, key));
        } else
          r.fail(rk.source(), key,
                 "unknown key; [render] has width, height, warmup, frames, backend, heatmaps, timeout_s, env, args, "
                 "camera_path");
      }
    } else if (section == "measure") {
      for (auto&& [mk, mv] : r.table(v, section)) {
        const std::string key = "measure." + std::string(mk.str());
        RunRender& out = cfg.render;
        if (mk == "min_frames") {
          measureMinNode = &mv;
          measureMin = int(r.integer(mv, key, 1, 1000000));
        } else if (mk == "max_frames") {
          maxFramesNode = &mv;
          out.maxFrames = int(r.integer(mv, key, 1, 1000000));
        } else if (mk == "target_ci_pct") {
          out.targetCiPct = r.number(mv, key);
          if (!(out.targetCiPct > 0.0 && out.targetCiPct <= 100.0)) r.fail(mv.source(), key, "must be in (0, 100]");
        } else if (mk == "max_seconds") {
          out.maxSeconds = r.number(mv, key);
          if (!(out.maxSeconds > 0.0)) r.fail(mv.source(), key, "must be > 0 seconds");
        } else if (mk == "group_size") {
          out.groupSize = int(r.integer(mv, key, 1, 100000));
        } else if (mk == "aa_control") {
          out.aaControl = r.boolean(mv, key);
        } else if (mk == "interleave") {
          out.interleave = r.boolean(mv, key);
        } else {
          r.fail(mk.source(), key,
                 "unknown key; [measure] has min_frames, max_frames, target_ci_pct, max_seconds, group_size, "
                 "aa_control, interleave");
        }
      }
    } else if (section == "axes") {
      readAxes(r.table(v, section), "axes", topAxes, {});
    } else if (section == "sweep") {
      const toml::array* a = v.as_array();
      if (!a || !a->is_array_of_tables()) r.fail(v.source(), section, "expected [[sweep]] tables");
      for (size_t i = 0; i < a->size(); ++i) {
        const toml::table& t = *a->get(i)->as_table();
        const std::string key = "sweep[" + std::to_string(i) + "]";
        Sweep s;
        const toml::node* nameNode = t.get("name");
        if (!nameNode) r.fail(t.source(), key, "a [[sweep]] needs a `name`");
        s.name = r.string(*nameNode, key + ".name");
        if (s.name.empty()) r.fail(nameNode->source(), key + ".name", "must not be empty");
        for (const Sweep& other : sweeps)
          if (other.name == s.name) r.fail(nameNode->source(), key + ".name", "duplicate sweep name '" + s.name + "'");
        if (const toml::node* d = t.get("description")) r.string(*d, key + ".description");
        readAxes(t, key, s.axes, {"name", "description"});
        sweeps.push_back(std::move(s));
      }
    } else if (section == "exclude") {
      const toml::array* a = v.as_array();
      if (!a || !a->is_array_of_tables()) r.fail(v.source(), section, "expected [[exclude]] tables");
      for (size_t i = 0; i < a->size(); ++i) {
        const toml::table& t = *a->get(i)->as_table();
        const std::string key = "exclude[" + std::to_string(i) + "]";
        if (t.empty()) r.fail(t.source(), key, "an empty [[exclude]] would exclude every run");
        Exclusion ex;
        for (auto&& [ek, ev] : t) {
          const std::string sub = key + "." + std::string(ek.str());
          const AxisInfo* axis = findAxis(ek.str());
          if (!axis) r.fail(ek.source(), sub, "unknown axis");
          std::vector<std::string> labels;
          if (const toml::array* list = ev.as_array()) {
            if (list->empty()) r.fail(ev.source(), sub, "empty list");
            for (const toml::node& n : *list) labels.push_back(scalarLabel(r, n, sub));
          } else {
            labels.push_back(scalarLabel(r, ev, sub));
          }
          ex.conditions.push_back({std::string(axis->singular), std::move(labels), &ev, sub});
        }
        exclusions.push_back(std::move(ex));
      }
    } else {
      r.fail(k.source(), section, "unknown section; a config has [experiment], [render], [measure], [axes], [[sweep]], [[exclude]]");
    }
  }

  // [measure] min_frames is [render] frames by another name: one value, given in one place.
  if (measureMin) {
    if (framesNode && *measureMin != cfg.render.frames)
      r.fail(measureMinNode->source(), "measure.min_frames",
             "[render] frames = " + std::to_string(cfg.render.frames) + " says otherwise; give it in one place");
    cfg.render.frames = *measureMin;
  }
  if (!maxFramesNode) cfg.render.maxFrames = std::max(cfg.render.maxFrames, cfg.render.frames);
  if (cfg.render.maxFrames < cfg.render.frames)
    r.fail(maxFramesNode->source(), "measure.max_frames",
           std::to_string(cfg.render.maxFrames) + " is below min_frames " + std::to_string(cfg.render.frames));

  if (sweeps.empty()) sweeps.push_back(Sweep{"main", {}});
  for (Sweep& s : sweeps) {
    AxisMap merged = topAxes;
    for (auto& [axis, values] : s.axes) merged[axis] = values;
    s.axes = std::move(merged);
    if (!s.axes.count("scene"))
      r.fail(root.source(), s.name == "main" ? "axes.scenes" : "sweep '" + s.name + "'.scenes",
             "missing: every run needs a scene (or mesh) file");
  }

  // A camera path sets the camera of every frame: a scene's own camera override would be ignored.
  if (cameraPathNode)
    for (const Sweep& s : sweeps)
      for (const AxisValue& v : s.axes.at("scene"))
        for (const char* k : {"eye", "target", "up", "fov"})
          if (v.value.is_object() && v.value.contains(k))
            r.fail(cameraPathNode->source(), "render.camera_path",
                   "scene '" + v.label + "' sets `" + k + "`, but the camera path sets every frame's camera; "
                   "drop one of them");

  // Every exclusion label should name a value some sweep uses: a typo would silently exclude nothing.
  for (const Exclusion& ex : exclusions)
    for (const Exclusion::Condition& c : ex.conditions)
      for (const std::string& label : c.labels) {
        bool known = false;
        for (const Sweep& s : sweeps)
          if (auto it = s.axes.find(c.axis); it != s.axes.end())
            for (const AxisValue& v : it->second) known = known || namesValue(c.axis, label, v);
        if (!known) r.fail(c.node->source(), c.key, "'" + label + "' matches no value of axis '" + c.axis + "'");
      }

  // Expand: sweeps in order, each the product of its axes (first axis slowest), minus exclusions,
  // deduplicated by key (a run shared by two sweeps belongs to both).
  std::unordered_map<std::string, size_t> byKey;
  for (const Sweep& s : sweeps) {
    std::vector<const AxisInfo*> present;
    for (const AxisInfo& a : experimentAxes())
      if (s.axes.count(std::string(a.singular))) present.push_back(&a);
    std::vector<size_t> digit(present.size(), 0);
    for (bool more = true; more;) {
      RunSpec run;
      run.render = cfg.render;
      for (size_t i = 0; i < present.size(); ++i) {
        const std::string name(present[i]->singular);
        run.axes.emplace_back(name, s.axes.at(name)[digit[i]]);
      }
      finishRun(run);
      const bool excluded = std::any_of(exclusions.begin(), exclusions.end(),
                                        [&](const Exclusion& ex) { return ex.matches(run); });
      if (!excluded) {
        auto it = byKey.find(run.key);
        if (it == byKey.end()) {
          run.sweeps = {s.name};
          run.index = cfg.runs.size();
          byKey.emplace(run.key, run.index);
          cfg.runs.push_back(std::move(run));
        } else {
          std::vector<std::string>& names = cfg.runs[it->second].sweeps;
          if (std::find(names.begin(), names.end(), s.name) == names.end()) names.push_back(s.name);
        }
      }
      // Odometer increment: the last axis varies fastest.
      more = false;
      for (size_t i = present.size(); i-- > 0;) {
        if (++digit[i] < s.axes.at(std::string(present[i]->singular)).size()) {
          more = true;
          break;
        }
        digit[i] = 0;
      }
    }
  }
  if (cfg.runs.empty())
    r.fail(root.source(), "exclude", "the [[exclude]] entries remove every run of the product");

  // The reference: each run's reference is the same run with the reference's axis values (and
  // frames/warmup) substituted; one not in the sweep is appended as a reference-only run.
  if (referenceTable) {
    if (referenceTable->empty()) r.fail(referenceTable->source(), "experiment.reference", "empty table");
    std::vector<std::pair<std::string, AxisValue>> overrides;
    std::optional<int> frames, warmup;
    cfg.reference = json::object();
    for (auto&& [k, v] : *referenceTable) {
      const std::string key = "experiment.reference." + std::string(k.str());
      if (k == "frames") {
        frames = int(r.integer(v, key, 1, 1000000));
        cfg.reference["frames"] = *frames;
      } else if (k == "warmup") {
        warmup = int(r.integer(v, key, 0, 1000000));
        cfg.reference["warmup"] = *warmup;
      } else if (const AxisInfo* axis = findAxis(k.str())) {
        if (v.is_array()) r.fail(v.source(), key, "a reference names one value per axis, not a list");
        AxisValue value = r.axisValue(*axis, v, key);
        cfg.reference[std::string(axis->singular)] = value.label;
        overrides.emplace_back(std::string(axis->singular), std::move(value));
      } else {
        r.fail(k.source(), key, "unknown key; a reference has axis values (singular names), frames, warmup");
      }
    }
    const size_t sweepRuns = cfg.runs.size();
    for (size_t i = 0; i < sweepRuns; ++i) {
      RunSpec ref = cfg.runs[i];
      for (const auto& [name, value] : overrides) {
        auto it = std::find_if(ref.axes.begin(), ref.axes.end(), [&](const auto& a) { return a.first == name; });
        if (it != ref.axes.end()) it->second = value;
        else ref.axes.emplace_back(name, value);
      }
      if (frames) ref.render.frames = ref.render.maxFrames = *frames;  // a reference is drawn, not timed
      if (warmup) ref.render.warmup = *warmup;
      finishRun(ref);
      auto it = byKey.find(ref.key);
      if (it == byKey.end()) {
        ref.index = cfg.runs.size();
        ref.sweeps.clear();
        ref.referenceOnly = true;
        ref.referenceKey = ref.key;
        byKey.emplace(ref.key, ref.index);
        cfg.runs[i].referenceKey = ref.key;
        cfg.runs.push_back(std::move(ref));
      } else {
        cfg.runs[i].referenceKey = ref.key;
      }
    }
  }

  // Axis values in config order (sweeps first, then the reference), for tables and plot axes.
  auto addLabel = [&](const std::string& axis, const std::string& label) {
    std::vector<std::string>& labels = cfg.axisLabels[axis];
    if (std::find(labels.begin(), labels.end(), label) == labels.end()) labels.push_back(label);
  };
  for (const Sweep& s : sweeps) {
    cfg.sweepNames.push_back(s.name);
    for (const AxisInfo& a : experimentAxes())
      if (auto it = s.axes.find(std::string(a.singular)); it != s.axes.end())
        for (const AxisValue& v : it->second) addLabel(it->first, v.label);
  }
  for (const RunSpec& run : cfg.runs)
    for (const auto& [name, value] : run.axes) addLabel(name, value.label);
  return cfg;
}

ExperimentConfig loadExperimentConfig(const fs::path& file, const KnownNames& names) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string() + ": cannot open the experiment config");
  std::ostringstream text;
  text << in.rdbuf();
  return parseExperimentConfig(text.str(), file, names);
}

ExperimentConfig loadExperimentConfig(const fs::path& file) {
  return loadExperimentConfig(file, registeredNames());
}

}  // namespace bvhlab
