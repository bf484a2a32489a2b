// Runs and their keys: the axes a config may sweep, a run's parameters, its stable key (FNV-1a 64 of
// its parameters) and its plan.json form. The TOML parsing that produces them is experiments/config.cpp.
#include <cstdio>

#include "builders/builder.hpp"
#include "experiments/config.hpp"
#include "layout/layouts.hpp"
#include "layout/triangle_formats.hpp"
#if __has_include("traversal/kernels.hpp")
#include "traversal/kernels.hpp"
#define BVHLAB_HAVE_KERNEL_REGISTRY 1
#endif

namespace bvhlab {

using nlohmann::json;

const std::vector<AxisInfo>& experimentAxes() {
  static const std::vector<AxisInfo> axes = {
      {"scenes", "scene", ""},  // the scene is the positional INPUT of `bvhlab render`
      {"builders", "builder", "--builder"},
      // The texture layout the tree is packed in (layout/layouts.hpp); a kernel walks one layout.
      {"layouts", "layout", "--layout"},
      // How triangles are stored (layout/triangle_formats.hpp; render JSON "triangle_format": "triangles"
      // is the triangle count there).
      {"triangle_formats", "triangle_format", "--triangles"},
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
      // Texture level of detail by ray cones (shaders/texture_lod.glsl): none | cones | cones-aniso.
      {"texture_lod", "texture_lod", "--texture-lod"},
      // A ray workload: the run traces it (`bvhlab trace --rays`) instead of rendering frames.
      {"rays", "workload", "--rays"},
      // An update strategy (builders/update.hpp): the run traces an animated scene's clip frame by
      // frame (`bvhlab trace --update`, docs/animation.md); needs the rays axis.
      {"updates", "update", "--update"},
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
  if (programCopies != 1) key["program_copies"] = programCopies;  // frame_ms is then a median over copies
  if (gpuBuilds != 0) key["gpu_builds"] = gpuBuilds;  // only when set: other configs' keys stay as they were
  return key;
}

json RunRender::groupJson() const {
  json g = keyJson();
  g["group_size"] = groupSize;
  g["aa_control"] = aaControl;
  g["share_programs"] = sharePrograms;
  g["interleave"] = interleave;
  g["timeout_s"] = timeoutSeconds;
  g["trace_count"] = traceCount;
  g["trace_seed"] = traceSeed;
  g["ao_radius"] = aoRadius;
  g["embree_threads"] = embreeThreads;
  g["min_sample_ms"] = minSampleMs;
  g["clip_frames"] = clipFrames;
  g["clip_step"] = clipStep;
  g["update_repeats"] = updateRepeats;
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
  json key{{"axes", a}, {"render", render.keyJson()}};
  if (axis("workload")) {  // only trace runs: the keys of render runs stay as they were
    key["trace"] = {{"count", render.traceCount}, {"seed", render.traceSeed}, {"ao_radius", render.aoRadius}};
    // Only when set: the keys of configs without it stay as they were.
    if (render.embreeThreads != 0) key["trace"]["embree_threads"] = render.embreeThreads;
    if (render.minSampleMs >= 0.0) key["trace"]["min_sample_ms"] = render.minSampleMs;
    if (axis("update"))
      key["trace"]["clip"] = {{"frames", render.clipFrames}, {"step", render.clipStep}, {"update_repeats", render.updateRepeats}};
  }
  return key;
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
  s.render.sharePrograms = r.value("share_programs", s.render.sharePrograms);
  s.render.programCopies = r.value("program_copies", s.render.programCopies);
  s.render.interleave = r.value("interleave", s.render.interleave);
  s.render.traceCount = r.value("trace_count", s.render.traceCount);
  s.render.traceSeed = r.value("trace_seed", s.render.traceSeed);
  s.render.aoRadius = r.value("ao_radius", s.render.aoRadius);
  s.render.embreeThreads = r.value("embree_threads", s.render.embreeThreads);
  s.render.minSampleMs = r.value("min_sample_ms", s.render.minSampleMs);
  s.render.clipFrames = r.value("clip_frames", s.render.clipFrames);
  s.render.clipStep = r.value("clip_step", s.render.clipStep);
  s.render.updateRepeats = r.value("update_repeats", s.render.updateRepeats);
  s.render.gpuBuilds = r.value("gpu_builds", s.render.gpuBuilds);
  s.render.cameraPath = r.value("camera_path", "");
  s.render.cameraPathHash = r.value("camera_path_hash", "");
  s.render.cameraPathFile = r.value("camera_path_file", "");
  s.sweeps = j.at("sweeps").get<std::vector<std::string>>();
  s.referenceKey = j.at("reference_key");
  s.referenceOnly = j.at("reference_only");
  return s;
}

const KnownLayout* KnownNames::findLayout(const std::string& name) const {
  for (const KnownLayout& l : layouts)
    if (l.name == name) return &l;
  return nullptr;
}

KnownNames registeredNames() {
  KnownNames names;
  for (const BuilderInfo& b : builders()) names.builders.push_back(b.name);
#ifdef BVHLAB_HAVE_KERNEL_REGISTRY
  for (const KernelInfo* k : allKernels()) names.kernels.push_back(k->name);
  for (const LayoutInfo& l : layouts()) {
    KnownLayout known{l.name, l.defaultKernel, {}};
    for (const KernelInfo& k : kernelsFor(l.name)) known.kernels.push_back(k.name);
    names.layouts.push_back(std::move(known));
  }
#endif
  names.defaultLayout = kDefaultLayout;
  // Which robustness variants each triangle format cannot run: asked of the format's own check.
  const std::vector<Robustness>& variants = robustnessVariants();
  for (const TriangleFormatInfo& f : triangleFormats()) {
    names.triangleFormats.push_back(f.name);
    std::vector<std::string>& refused = names.triangleFormatRefuses[f.name];
    for (size_t i = 0; i < variants.size(); ++i) {
      try {
        checkTriangleFormat(f.name, variants[i]);
      } catch (const std::invalid_argument&) {
        refused.push_back(robustnessNames()[i]);
      }
    }
  }
  names.defaultRobust = robustnessName(Robustness::Watertight);  // shaders/assemble.hpp's default
  return names;
}

}  // namespace bvhlab
