#include "experiments/config.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>
#include <set>
#include <tuple>
#include <sstream>
#include <unordered_map>

#include <toml++/toml.h>

#include "experiments/config_reader.hpp"
#include "experiments/config_settings.hpp"
#include "datasets/toml_guard.hpp"

#include "builders/builder.hpp"
#include "datasets/scene.hpp"  // InputError
#include "experiments/generated_scenes.hpp"
#if __has_include("traversal/kernels.hpp")
#include "traversal/kernels.hpp"
#define BVHLAB_HAVE_KERNEL_REGISTRY 1
#endif

namespace bvhlab {

namespace fs = std::filesystem;
using nlohmann::json;

using namespace config_detail;

namespace {

struct Sweep {
  std::string name;
  AxisMap axes;
  std::map<std::string, const toml::node*> nodes;  // singular -> where the axis was written
  std::map<std::string, std::string> keys;         // singular -> its key for errors ("axes.kernels")
  std::set<std::string> every;                     // axes given as "all"
};

// A run's kernel paired with its layout (the `layout` axis, else the default layout): "default"
// becomes that layout's default kernel; false when the kernel walks another layout (the run is not
// part of the product). Unchecked when the names carry no layouts.
bool pairKernel(RunSpec& run, const KnownNames& names) {
  auto kernel = std::find_if(run.axes.begin(), run.axes.end(), [](const auto& a) { return a.first == "kernel"; });
  if (kernel == run.axes.end()) return true;  // the renderer runs the layout's default kernel
  const AxisValue* layoutValue = run.axis("layout");
  const KnownLayout* layout = names.findLayout(layoutValue ? layoutValue->label : names.defaultLayout);
  if (!layout) return true;
  if (kernel->second.label == kDefaultKernel) {
    kernel->second = AxisValue{layout->defaultKernel, layout->defaultKernel, {}};
    return true;
  }
  return std::find(layout->kernels.begin(), layout->kernels.end(), kernel->second.label) != layout->kernels.end();
}

// Whether the run's triangle format can run its robustness variant (the `robust` axis, else the
// renderer's default): precomputed triangles cannot run the watertight test.
bool formatRuns(const RunSpec& run, const KnownNames& names) {
  const AxisValue* format = run.axis("triangle_format");
  if (!format) return true;
  const auto refused = names.triangleFormatRefuses.find(format->label);
  if (refused == names.triangleFormatRefuses.end()) return true;
  const AxisValue* robust = run.axis("robust");
  const std::string variant = robust ? robust->label : names.defaultRobust;
  return std::find(refused->second.begin(), refused->second.end(), variant) == refused->second.end();
}

// The layout a kernel walks ("" when no known layout has it).
std::string layoutOfKernel(const KnownNames& names, const std::string& kernel) {
  for (const KnownLayout& l : names.layouts)
    if (std::find(l.kernels.begin(), l.kernels.end(), kernel) != l.kernels.end()) return l.name;
  return "";
}

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

  if (const std::optional<TomlTextHazard> h = findTomlTextHazard(text))
    throw InputError(file.string() + ':' + std::to_string(h->line) + ':' + std::to_string(h->column) + ": " +
                     h->message);
  toml::table root;
  try {
    root = toml::parse(text, file.string());
  } catch (const toml::parse_error& e) {
    std::ostringstream msg;
    msg << file.string() << ':' << e.source().begin.line << ':' << e.source().begin.column
        << ": TOML syntax error: " << e.description();
    throw InputError(msg.str());
  }

  Sweep topAxes;
  std::vector<Sweep> sweeps;
  std::vector<Exclusion> exclusions;
  const toml::table* referenceTable = nullptr;
  SettingNodes settingNodes;
  const toml::node*& cameraPathNode = settingNodes.cameraPath;
  std::vector<std::tuple<std::string, std::string, const toml::node*, std::string>> baselineNodes;  // axis label node key

  auto readAxes = [&](const toml::table& t, const std::string& section, Sweep& into,
                      const std::set<std::string>& skip) {
    AxisMap& out = into.axes;
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
      into.nodes[singular] = &v;
      into.keys[singular] = key;
      if (ConfigReader::isEveryValue(*axis, v)) into.every.insert(singular);
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
        else if (ek == "replicates") cfg.replicates = int(r.integer(ev, key, 1, kMaxReplicates));
        else if (ek == "reference") referenceTable = &r.table(ev, key);
        else r.fail(ek.source(), key, "unknown key; [experiment] has name, description, reference, seed_figures, replicates");
      }
    } else if (section == "render") {
      readRenderSection(r, v, cfg.render, settingNodes);
    } else if (section == "measure") {
      readMeasureSection(r, v, cfg.render, settingNodes);
    } else if (section == "trace") {
      readTraceSection(r, v, cfg.render);
    } else if (section == "findings") {
      for (auto&& [fk, fv] : r.table(v, section)) {
        const std::string key = "findings." + std::string(fk.str());
        if (fk != "baseline") r.fail(fk.source(), key, "unknown key; [findings] has baseline");
        for (auto&& [ak, av] : r.table(fv, key)) {
          const std::string sub = key + "." + std::string(ak.str());
          const AxisInfo* axis = findAxis(ak.str());
          if (!axis || axis->singular == "scene")
            r.fail(ak.source(), sub, "not an axis findings compare along (a singular axis name other than scene)");
          baselineNodes.emplace_back(std::string(axis->singular), scalarLabel(r, av, sub), &av, sub);
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
        readAxes(t, key, s, {"name", "description"});
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
      r.fail(k.source(), section, "unknown section; a config has [experiment], [render], [measure], [trace], [findings], [axes], [[sweep]], [[exclude]]");
    }
  }

  checkRunSettings(r, cfg.render, settingNodes);

  if (sweeps.empty()) sweeps.push_back(Sweep{"main", {}, {}, {}, {}});
  for (Sweep& s : sweeps) {
    AxisMap merged = topAxes.axes;
    for (auto& [axis, values] : s.axes) merged[axis] = values;
    s.axes = std::move(merged);
    for (const auto& [axis, node] : topAxes.nodes)
      if (!s.nodes.count(axis)) {
        s.nodes[axis] = node;
        s.keys[axis] = topAxes.keys.at(axis);
        if (topAxes.every.count(axis)) s.every.insert(axis);
      }
    if (!s.axes.count("scene"))
      r.fail(root.source(), s.name == "main" ? "axes.scenes" : "sweep '" + s.name + "'.scenes",
             "missing: every run needs a scene (or mesh) file");
  }

  // A run on the `rays` axis traces rays (no shading, no image): axes that only change frames have
  // nothing to act on there, and a camera path has no frames to move through.
  for (const Sweep& s : sweeps) {
    if (!s.axes.count("workload")) continue;
    const std::string where = s.name == "main" ? "axes.rays" : "sweep '" + s.name + "'.rays";
    for (const char* a : {"depth", "aa", "view", "uber", "branching", "smaa_edges", "texture_lod"})
      if (s.axes.count(a))
        r.fail(root.source(), where,
               std::string("rays traces workloads without shading; it cannot be swept together with '") + a +
                   "' (put them in separate [[sweep]]s)");
    if (cameraPathNode)
      r.fail(cameraPathNode->source(), "render.camera_path", "a camera path times frames; the rays axis traces a workload");
  }

  // A run on the `updates` axis traces a clip (`bvhlab trace --update`): it needs a workload.
  for (const Sweep& s : sweeps)
    if (s.axes.count("update") && !s.axes.count("workload"))
      r.fail(root.source(), s.name == "main" ? "axes.updates" : "sweep '" + s.name + "'.updates",
             "updates traces an animated scene's clip: it needs the rays axis too (e.g. rays = [\"primary\"])");

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
    std::set<std::string> pairedKernels;  // kernel values some layout of this sweep walks
    std::set<std::string> runnableFormats;  // triangle formats some run of this sweep can run
    for (bool more = true; more;) {
      RunSpec run;
      run.render = cfg.render;
      for (size_t i = 0; i < present.size(); ++i) {
        const std::string name(present[i]->singular);
        run.axes.emplace_back(name, s.axes.at(name)[digit[i]]);
      }
      // A scene may have its own rays per workload and trace its clip at its own step and length
      // ([trace] count, clip_step, clip_frames).
      if (const AxisValue* scene = run.axis("scene")) {
        run.render.traceCount = scene->value.value("count", run.render.traceCount);
        run.render.clipStep = scene->value.value("clip_step", run.render.clipStep);
        run.render.clipFrames = scene->value.value("clip_frames", run.render.clipFrames);
      }
      const AxisValue* written = run.axis("kernel");
      const std::string kernelLabel = written ? written->label : "";
      const bool formatOk = formatRuns(run, r.names());
      const bool paired = pairKernel(run, r.names()) && formatOk;
      if (paired) pairedKernels.insert(kernelLabel);
      if (formatOk && run.axis("triangle_format")) runnableFormats.insert(run.axis("triangle_format")->label);
      finishRun(run);
      const bool excluded = !paired || std::any_of(exclusions.begin(), exclusions.end(),
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
    // A kernel no layout of the sweep walks is a mistake (kernels = "all" offers every one on purpose).
    if (auto it = s.axes.find("kernel"); it != s.axes.end() && !s.every.count("kernel"))
      for (size_t i = 0; i < it->second.size(); ++i) {
        const std::string& k = it->second[i].label;
        if (pairedKernels.count(k)) continue;
        const std::string walks = layoutOfKernel(r.names(), k);
        std::string layoutsUsed = r.names().defaultLayout + " (the default: the sweep has no `layouts`)";
        if (auto l = s.axes.find("layout"); l != s.axes.end()) {
          layoutsUsed.clear();
          for (const AxisValue& v : l->second) layoutsUsed += (layoutsUsed.empty() ? "" : ", ") + v.label;
        }
        r.fail(s.nodes.at("kernel")->source(), s.keys.at("kernel") + "[" + std::to_string(i) + "]",
               "kernel '" + k + "' walks layout " + walks + ", but this sweep's runs use " + layoutsUsed +
                   "; add \"" + walks + "\" to `layouts` (or use kernel \"default\": each layout's own)");
      }
    // Likewise a triangle format that none of the sweep's robustness variants can run.
    if (auto it = s.axes.find("triangle_format"); it != s.axes.end() && !s.every.count("triangle_format"))
      for (size_t i = 0; i < it->second.size(); ++i) {
        const std::string& f = it->second[i].label;
        if (runnableFormats.count(f)) continue;
        std::string used = r.names().defaultRobust + " (the default: the sweep has no `robust`)";
        if (auto v = s.axes.find("robust"); v != s.axes.end()) {
          used.clear();
          for (const AxisValue& x : v->second) used += (used.empty() ? "" : ", ") + x.label;
        }
        const std::vector<std::string>& refused = r.names().triangleFormatRefuses.at(f);
        std::string works;
        for (const std::string& variant : kRobustness)
          if (std::find(refused.begin(), refused.end(), variant) == refused.end())
            works += (works.empty() ? "" : ", ") + variant;
        r.fail(s.nodes.at("triangle_format")->source(), s.keys.at("triangle_format") + "[" + std::to_string(i) + "]",
               "triangle format '" + f + "' cannot run robust " + used + "; it runs with robust " + works);
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
      if (cfg.runs[i].axis("workload")) continue;  // a traced run (rays axis) draws no image to compare
      RunSpec ref = cfg.runs[i];
      for (const auto& override : overrides) {
        const auto& [name, value] = override;
        // Compare through `override`, not the binding: clang 14 cannot capture structured bindings.
        auto it = std::find_if(ref.axes.begin(), ref.axes.end(),
                               [&](const auto& a) { return a.first == override.first; });
        if (it != ref.axes.end()) it->second = value;
        else ref.axes.emplace_back(name, value);
      }
      if (frames) ref.render.frames = ref.render.maxFrames = *frames;  // a reference is drawn, not timed
      if (warmup) ref.render.warmup = *warmup;
      if (!pairKernel(ref, r.names()) || !formatRuns(ref, r.names()))
        r.fail(referenceTable->source(), "experiment.reference",
               "the reference of run '" + cfg.runs[i].describe() + "' pairs kernel '" + ref.axis("kernel")->label +
                   "' with a layout it does not walk, or its triangle format with a robustness variant it "
                   "cannot run");
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
  // [findings] baseline: each value must be one the sweeps measure on its axis.
  for (const auto& [axis, label, node, key] : baselineNodes) {
    const auto it = cfg.axisLabels.find(axis);
    if (it == cfg.axisLabels.end() || std::find(it->second.begin(), it->second.end(), label) == it->second.end())
      r.fail(node->source(), key, "'" + label + "' is not a value of the " + axis + " axis in this config" +
             (it == cfg.axisLabels.end() ? std::string(" (no sweep sets it)") : " (values: " + joined(it->second) + ")"));
    cfg.findingsBaseline[axis] = label;
  }
  return cfg;
}

ExperimentConfig loadExperimentConfig(const fs::path& file, const KnownNames& names) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw FileError(file.string() + ": cannot open the experiment config");
  std::ostringstream text;
  text << in.rdbuf();
  return parseExperimentConfig(text.str(), file, names);
}

ExperimentConfig loadExperimentConfig(const fs::path& file) {
  return loadExperimentConfig(file, registeredNames());
}

}  // namespace bvhlab
