#include "shaders/assemble.hpp"

#include <regex>
#include <sstream>
#include <stdexcept>

#include "layout/layouts.hpp"
#include "layout/triangle_formats.hpp"
#include "traversal/kernels.hpp"
#include "traversal/two_level.hpp"

namespace bvhlab {

View parseView(const std::string& s) {
  if (s == "shaded") return View::Shaded;
  if (s == "normal") return View::Normal;
  if (s == "depth") return View::Depth;
  if (s == "primid") return View::PrimId;
  throw std::invalid_argument("unknown view '" + s + "' (valid: shaded, normal, depth, primid, visits)");
}
Branching parseBranching(const std::string& s) {
  if (s == "full") return Branching::Full;
  if (s == "report") return Branching::Report;
  throw std::invalid_argument("unknown branching '" + s + "' (valid: full, report)");
}
Storage parseStorage(const std::string& s) {
  if (s == "tbo") return Storage::Tbo;
  if (s == "tex2d") return Storage::Tex2D;
  if (s == "ssbo") return Storage::Ssbo;
  throw std::invalid_argument("unknown storage '" + s + "' (valid: tbo, tex2d, ssbo)");
}
TextureLod parseTextureLod(const std::string& s) {
  if (s == "none") return TextureLod::None;
  if (s == "cones") return TextureLod::Cones;
  if (s == "cones-aniso") return TextureLod::ConesAniso;
  throw std::invalid_argument("unknown texture LOD '" + s + "' (valid: none, cones, cones-aniso)");
}
const char* textureLodName(TextureLod t) {
  return t == TextureLod::None ? "none" : t == TextureLod::Cones ? "cones" : "cones-aniso";
}
const char* viewName(View v) {
  static const char* names[] = {"shaded", "normal", "depth", "primid"};
  return names[static_cast<int>(v)];
}
const char* branchingName(Branching b) { return b == Branching::Full ? "full" : "report"; }
const char* storageName(Storage s) { return s == Storage::Tbo ? "tbo" : s == Storage::Tex2D ? "tex2d" : "ssbo"; }
const char* storageModule(Storage s) {
  return s == Storage::Tbo ? "storage_tbo.glsl" : s == Storage::Tex2D ? "storage_tex2d.glsl" : "storage_ssbo.glsl";
}

SceneFeatures analyzeScene(const Scene& scene) {
  SceneFeatures f;
  for (const Object& o : scene.objects) {
    if (o.kind == ObjectKind::Mesh) continue;
    f.kinds[static_cast<int>(o.kind)] = true;
    ++f.numObjects;
  }
  f.mesh = scene.triangleCount() > 0;
  f.numLights = static_cast<int>(scene.lights.size());
  f.numMaterials = static_cast<int>(scene.materials.size());
  f.lights = f.numLights > 0;
  f.shadows = f.lights && (f.numObjects > 0 || f.mesh);
  for (const Material& m : scene.materials) {
    if (m.reflectivity > 0.0f || m.transparency > 0.0f) f.reflection = true;
    if (m.transparency > 0.0f) f.refraction = true;
    if (m.texture >= 0) f.textures = true;
  }
  f.world = scene.world.kind;
  return f;
}

bool usesTextureLod(const SceneFeatures& f, const ShaderOptions& o) {
  return o.textureLod != TextureLod::None && (o.uber || f.textures || f.world == WorldKind::Map);
}

int effectiveDepth(const SceneFeatures& f, int requested, bool uber) {
  if (requested < 1) throw std::invalid_argument("max depth must be >= 1");
  if (uber) return requested;
  return (f.reflection || f.refraction) ? requested : 1;
}

const std::string& glslModule(const std::string& name) {
  auto it = glslSources().find(name);
  if (it == glslSources().end()) throw std::out_of_range("no GLSL module named '" + name + "'");
  return it->second;
}

namespace {

int countLines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  if (!s.empty() && s.back() != '\n') ++n;
  return n;
}

class Assembler {
 public:
  void raw(const std::string& name, const std::string& text) {
    ShaderModule m{name, line_, countLines(text)};
    out_.source += text;
    if (!text.empty() && text.back() != '\n') out_.source += '\n';
    line_ += m.lineCount;
    out_.modules.push_back(m);
  }
  void module(const std::string& name) { raw(name, glslModule(name)); }
  AssembledShader take() { return std::move(out_); }

 private:
  AssembledShader out_;
  int line_ = 1;
};

const char* kKindModules[6] = {"prim_sphere.glsl", "prim_box.glsl", "prim_cylinder.glsl",
                               "prim_cone.glsl", "prim_torus.glsl", "prim_plane.glsl"};
const char* kKindDefines[6] = {"HAS_SPHERE", "HAS_BOX", "HAS_CYLINDER", "HAS_CONE", "HAS_TORUS", "HAS_PLANE"};

// The kernel's module: once for a flat tree; for a two-level tree (traversal/two_level.glsl) twice
// around two_level.glsl, as the BLAS walk and as the TLAS walk with its counters renamed.
void appendKernel(Assembler& a, const std::string& layout, const std::string& kernel, bool twoLevel) {
  const KernelInfo& info = findKernel(layout, kernel);
  const std::string& file = info.glslFile;
  if (!info.glslDefines.empty()) a.raw("<kernel defines>", info.glslDefines);
  if (!twoLevel) {
    a.module(file);
    return;
  }
  a.raw("<blas walk>", "#define KERNEL_WALK blasWalk\n#define KERNEL_LEAF_TEST testTriangle\n");
  a.module(file);
  a.raw("<end of blas walk>", "#undef KERNEL_WALK\n#undef KERNEL_LEAF_TEST\n");
  a.module("two_level.glsl");
  a.raw("<tlas walk>",
        "#define KERNEL_WALK tlasWalk\n#define KERNEL_LEAF_TEST testInstance\n#define g_nodeVisits g_tlasNodeVisits\n"
        "#define g_boxTests g_tlasBoxTests\n#define g_triTests g_instanceTests\n");
  a.module(file);
  a.raw("<end of tlas walk>",
        "#undef KERNEL_WALK\n#undef KERNEL_LEAF_TEST\n#undef g_nodeVisits\n#undef g_boxTests\n#undef g_triTests\n");
}

}  // namespace

void checkTwoLevel(const std::string& layout, const std::string& kernel) {
  if (!twoLevelLayoutSupported(findLayout(layout).name))
    throw std::invalid_argument("layout '" + layout + "' has no two-level trees (layouts with them: v1, bvh2-cb)");
  const std::string& name = findKernel(layout, kernel).name;
  if (!hasTwoLevelWalk(name)) twoLevelMirror(name, Robustness::Fast);  // throws, naming the kernels with one
}

AssembledShader assembleTracer(const SceneFeatures& f, const ShaderOptions& o) {
  checkTriangleFormat(o.triangles, o.robust);
  if (o.twoLevel) checkTwoLevel(o.layout, o.kernel);
  const bool uber = o.uber;
  std::ostringstream d;
  d << "#version 450 core\n";
  const int depth = effectiveDepth(f, o.maxDepth, uber);
  d << "#define MAX_DEPTH " << depth << "\n";
  d << "#define VIEW " << static_cast<int>(o.view) << "\n";
  d << "#define NUM_OBJECTS " << f.numObjects << "\n";
  d << "#define NUM_LIGHTS " << f.numLights << "\n";
  d << "#define OBJECT_ARRAY_SIZE " << std::max(1, f.numObjects) << "\n";
  d << "#define MATERIAL_ARRAY_SIZE " << std::max(1, f.numMaterials) << "\n";
  d << "#define LIGHT_ARRAY_SIZE " << std::max(1, f.numLights) << "\n";
  d << "#define BVH_STACK_SIZE " << o.bvhStackSize << "\n";
  if (o.ssaaGrid < 1 || o.ssaaGrid > 8) throw std::invalid_argument("SSAA grid must be 1..8 per axis");
  d << "#define SSAA_GRID " << o.ssaaGrid << "\n";
  if (uber) d << "#define UBER 1\n";
  if (o.countStats) d << "#define COUNT_STATS 1\n";
  if (o.primaryIdOut) d << "#define PRIMARY_ID_OUT 1\n";
  if (o.twoLevel) d << "#define TWO_LEVEL 1\n";
  if (o.robust.offset == OriginOffset::Ulp) d << "#define RAY_OFFSET_ULP 1\n";
  if (o.robust.box == BoxTest::Robust) d << "#define BVH_BOX_ROBUST 1\n";  // kernels may pick their box test by it
  if (o.reinhard) d << "#define TONEMAP_REINHARD 1\n";
  for (int k = 0; k < 6; ++k)
    if (uber || f.kinds[k]) d << "#define " << kKindDefines[k] << " 1\n";
  const bool mesh = uber || f.mesh;
  if (mesh) {
    d << "#define HAS_MESH 1\n";
    d << "#define MESH_PRESENT " << (uber ? "(u_meshPresent != 0)" : "true") << "\n";
  }
  if (uber || f.lights) d << "#define HAS_LIGHTS 1\n";
  if (uber || f.shadows) d << "#define HAS_SHADOWS 1\n";
  if (uber || f.refraction) d << "#define HAS_REFRACTION 1\n";
  if (uber || f.textures) d << "#define HAS_TEXTURES 1\n";
  const bool cones = usesTextureLod(f, o);
  if (cones) {
    d << "#define TEXTURE_LOD " << (o.textureLod == TextureLod::ConesAniso ? 2 : 1) << "\n";
    if (!o.coneCurvature) d << "#define CONE_NO_CURVATURE 1\n";
    if (o.lodView) d << "#define LOD_VIEW 1\n";
  }
  if (!uber) {
    d << (f.world == WorldKind::Color ? "#define WORLD_COLOR 1\n"
          : f.world == WorldKind::Sky ? "#define WORLD_SKY 1\n"
                                      : "#define WORLD_MAP 1\n");
  }

  Assembler a;
  a.raw("<defines>", d.str());
  a.module("common.glsl");
  if (mesh) {
    if (uber) a.raw("<uber>", "uniform int u_meshPresent;\n");
    a.module(storageModule(o.storage));
    for (const std::string& m : findLayout(o.layout).glslModules) a.module(m);
    // The robustness knobs (traversal/robustness.hpp): each test is a drop-in module.
    a.module(o.robust.box == BoxTest::Robust ? "ray_box_robust.glsl" : "ray_box.glsl");
    a.module(o.robust.triangle == TriangleTest::Watertight ? "ray_triangle_watertight.glsl" : "ray_triangle.glsl");
    a.module(findTriangleFormat(o.triangles).glslModule);  // testTriangle and the triangle accessors
    appendKernel(a, o.layout, o.kernel, o.twoLevel);
  }
  for (int k = 0; k < 6; ++k)
    if (uber || f.kinds[k]) a.module(kKindModules[k]);
  if (uber || f.textures) a.module("textures.glsl");
  if (cones) a.module("texture_lod.glsl");
  a.module("scene.glsl");
  if (uber || f.world == WorldKind::Color) a.module("world_color.glsl");
  if (uber || f.world == WorldKind::Sky) a.module("world_sky.glsl");
  if (uber || f.world == WorldKind::Map) a.module("world_map.glsl");
  a.module("world.glsl");
  if (o.robust.offset == OriginOffset::Ulp) a.module("offset_ulp.glsl");
  a.module("shade.glsl");
  if (o.view == View::Shaded) a.module(o.branching == Branching::Full ? "trace_full.glsl" : "trace_report.glsl");
  a.module("main.glsl");
  AssembledShader s = a.take();
  s.effectiveDepth = depth;
  return s;
}

AssembledShader assembleTraversal(const std::string& kernel, Storage storage, Robustness robust, int bvhStackSize,
                                  const std::string& defines, const std::string& layout, const std::string& triangles,
                                  bool twoLevel) {
  findKernel(layout, kernel);  // a mismatch fails before any GLSL
  checkTriangleFormat(triangles, robust);
  if (twoLevel) checkTwoLevel(layout, kernel);
  std::ostringstream d;
  d << "#version 450 core\n#define BVH_STACK_SIZE " << bvhStackSize << "\n";
  if (robust.box == BoxTest::Robust) d << "#define BVH_BOX_ROBUST 1\n";  // kernels may pick their box test by it
  d << defines;
  if (twoLevel) d << "#define TWO_LEVEL 1\n";
  Assembler a;
  a.raw("<defines>", d.str());
  a.module("common.glsl");
  a.module(storageModule(storage));
  for (const std::string& m : findLayout(layout).glslModules) a.module(m);
  a.module(robust.box == BoxTest::Robust ? "ray_box_robust.glsl" : "ray_box.glsl");
  a.module(robust.triangle == TriangleTest::Watertight ? "ray_triangle_watertight.glsl" : "ray_triangle.glsl");
  a.module(findTriangleFormat(triangles).glslModule);
  appendKernel(a, layout, kernel, twoLevel);
  return a.take();
}

AssembledShader assembleRayTracer(const std::string& kernel, Storage storage, Robustness robust, int bvhStackSize,
                                  bool anyHit, bool countStats, const std::string& layout,
                                  const std::string& triangles, bool twoLevel, bool persistentThreads) {
  // The workgroup size; kernels that keep per-invocation data in shared memory index it by lane.
  std::string defines = "#define COMPUTE_LANES " + std::to_string(kComputeLanes) + "\n";
  if (anyHit) defines += "#define ANY_HIT 1\n";
  if (countStats) defines += "#define COUNT_STATS 1\n";
  if (persistentThreads) {
    // trace_rays.glsl's persistent threads; the subgroup batch fetch where the extension is available
    // (its macro is defined only then: the GLSL falls back to one ray per atomicAdd).
    defines += "#define PERSISTENT_THREADS 1\n#extension GL_KHR_shader_subgroup_ballot : enable\n";
  }
  AssembledShader s = assembleTraversal(kernel, storage, robust, bvhStackSize, defines, layout, triangles, twoLevel);
  s.modules.push_back(ShaderModule{"trace_rays.glsl", s.modules.back().firstLine + s.modules.back().lineCount,
                                   0});
  const std::string& text = glslModule("trace_rays.glsl");
  s.modules.back().lineCount = countLines(text);
  s.source += text;
  if (!text.empty() && text.back() != '\n') s.source += '\n';
  return s;
}

AssembledShader assembleModule(const std::string& defines, const std::string& module) {
  Assembler a;
  a.raw("<defines>", "#version 450 core\n" + defines);
  a.module(module);
  return a.take();
}

bool AssembledShader::hasModule(const std::string& name) const {
  for (const ShaderModule& m : modules)
    if (m.name == name) return true;
  return false;
}

std::string AssembledShader::locate(int line) const {
  for (const ShaderModule& m : modules)
    if (line >= m.firstLine && line < m.firstLine + m.lineCount)
      return m.name + ":" + std::to_string(line - m.firstLine + 1);
  return "<assembled>:" + std::to_string(line);
}

std::string AssembledShader::mapLog(const std::string& log) const {
  // Mesa: "0:123(45): error: ..."   NVIDIA: "0(123) : error C0000: ..."
  static const std::regex mesa(R"(^\s*\d+:(\d+)\(\d+\):\s*)");
  static const std::regex nvidia(R"(^\s*\d+\((\d+)\)\s*:\s*)");
  std::istringstream in(log);
  std::ostringstream out;
  std::string lineText;
  while (std::getline(in, lineText)) {
    std::smatch m;
    if (std::regex_search(lineText, m, mesa) || std::regex_search(lineText, m, nvidia))
      out << locate(std::stoi(m[1].str())) << ": " << m.suffix().str() << "\n";
    else if (!lineText.empty())
      out << lineText << "\n";
  }
  return out.str();
}

std::string fullscreenVertexShader() {
  return "#version 450 core\n"
         "// One triangle that covers the viewport.\n"
         "void main() {\n"
         "  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));\n"
         "  gl_Position = vec4(2.0 * p - 1.0, 0.0, 1.0);\n"
         "}\n";
}

}  // namespace bvhlab
