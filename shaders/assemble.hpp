// Shader assembly: the fragment shader is concatenated from modules according to the scene's
// content ("simulate only the effects a scene calls for"), or from all of them (--uber).
#pragma once
#include <array>
#include <map>
#include <string>
#include <vector>

#include "datasets/scene.hpp"
#include "traversal/kernels.hpp"

namespace bvhlab {

enum class View { Shaded, Normal, Depth, PrimId };
enum class Branching { Full, Report };  // full: trace both Fresnel branches; report: Algorithm 1's compromise
enum class Storage { Tbo, Tex2D, Ssbo };
// Texture level of detail (shaders/texture_lod.glsl): none = level 0 everywhere (bilinear, no mipmaps);
// cones = ray cones, isotropic level; cones-aniso = ray cones, the footprint ellipse sampled by taps
// along its major axis.
enum class TextureLod { None, Cones, ConesAniso };

View parseView(const std::string&);
Branching parseBranching(const std::string&);
Storage parseStorage(const std::string&);
TextureLod parseTextureLod(const std::string&);  // throws std::invalid_argument listing the valid names
const char* textureLodName(TextureLod);
const char* viewName(View);
const char* branchingName(Branching);
const char* storageName(Storage);
// The GLSL module that defines fetchNode/fetchTriangle/fetchAttribute/fetchVertex for a storage kind.
const char* storageModule(Storage);

// What a scene needs simulated.
struct SceneFeatures {
  std::array<bool, 6> kinds{};  // analytic kinds present (ObjectKind order, Mesh excluded)
  bool mesh = false;            // triangles present: traversal kernel + layout modules
  bool lights = false;
  bool shadows = false;         // lights and anything that can occlude
  bool reflection = false;      // some material reflects (mirror or dielectric)
  bool refraction = false;      // some material is transparent
  bool textures = false;
  WorldKind world = WorldKind::Sky;
  int numObjects = 0, numMaterials = 0, numLights = 0;  // analytic objects only
};
SceneFeatures analyzeScene(const Scene& scene);

struct ShaderOptions {
  int maxDepth = 5;
  View view = View::Shaded;
  Branching branching = Branching::Full;
  std::string kernel = "stack-ordered";  // must walk `layout` (traversal/kernels.hpp findKernel(layout, name))
  std::string layout = "v1";             // the packed tree's layout (layout/layouts.hpp): its accessor modules
  std::string triangles = "raw";         // the packed tree's triangle format (layout/triangle_formats.hpp)
  // A two-level tree (layout/pack_two_level.hpp; traversal/two_level.glsl): the kernel assembled as its
  // BLAS and TLAS walks. traceClosest then leaves the hit's instance record in g_instance; shading in
  // world space needs instanceNormalToWorld(g_instance, n) on the object-space normal.
  bool twoLevel = false;
  Storage storage = Storage::Tbo;
  int bvhStackSize = 64;  // from the packed tree depth (see traversal/kernels.hpp)
  bool countStats = false;
  // Writes the primary ray's hit id (+1, 0 = miss) to colour attachment 3: SMAA's geometry edges
  // (render/smaa.hpp) keep only edges between different primitives. One SSAA sample's id (the last).
  bool primaryIdOut = false;
  bool reinhard = false;
  bool uber = false;
  int ssaaGrid = 1;  // shaded view: ssaaGrid^2 regular sub-pixel rays per pixel (1 = off)
  // Ray-cone texture filtering; compiled in only when the scene samples a texture (usesTextureLod).
  TextureLod textureLod = TextureLod::None;
  bool coneCurvature = true;  // false: cones keep their spread at curved surfaces (a test switch)
  bool lodView = false;       // shaded view writes the first lookup's level instead (main.glsl; tests)
  // Triangle test, box test and secondary-ray offset, each on its own. Default: all three robust
  // ("watertight"), chosen on these measurements (bench_robust, quiet 2-core machine, one process,
  // frames interleaved; `bvhlab hard-cases --gpu`):
  //  - cost: 1.30x fast's frame time on the bunny (75k triangles), 1.12x on the report scene; all of it
  //    is the watertight triangle test (tri alone 1.31x / 1.11x; box and ulp alone within +-4% of fast);
  //  - triangles + boxes: 0 of 33,154 must-hit rays leak (fast: 1,337; watertight triangles with plain
  //    boxes still 142, lost to boxes the slab test culls), 0 of 556,182 GLSL pixels from inside closed
  //    meshes (fast: 27), 0 hit/miss disagreements with the exact oracle (fast: 136 of 3,350);
  //  - ULP offset: 2,091 of 15,376 reflected rays inside closed meshes lost (epsilon: 3,840), equal on the
  //    far/scaled scenes; its known cost is acne_zoom (telephoto from 1e4): 13 of 690 face pixels wrong
  //    where epsilon has none (datasets/hard/README.md). `--robust tri+box` keeps the epsilon offset.
  // `--robust fast` is the seed's Moller-Trumbore setting.
  Robustness robust = Robustness::Watertight;
};

struct ShaderModule {
  std::string name;  // file name, e.g. "shade.glsl"
  int firstLine = 0; // 1-based line of the assembled source where the module starts
  int lineCount = 0;
};

struct AssembledShader {
  std::string source;
  std::vector<ShaderModule> modules;  // in order; the preamble is module "<defines>"
  int effectiveDepth = 1;             // max depth after specialisation
  bool hasModule(const std::string& name) const;
  // "file.glsl:LINE" for a line of the assembled source.
  std::string locate(int line) const;
  // Rewrites a driver's compile log ("0:123(4): error ..." Mesa, "0(123) : error ..." NVIDIA) so each
  // message names the module and its own line.
  std::string mapLog(const std::string& log) const;
};

// Whether the tracer compiles ray cones in: a cone mode is asked for and the scene samples a texture
// (a material texture or a world map), or the uber shader.
bool usesTextureLod(const SceneFeatures& features, const ShaderOptions& options);

// Effective max depth: lowered to 1 when nothing reflects or refracts (uber keeps the request).
int effectiveDepth(const SceneFeatures& features, int requested, bool uber);
AssembledShader assembleTracer(const SceneFeatures& features, const ShaderOptions& options);
// `bvhlab trace`'s compute shader: the kernel over its storage, layout and robustness modules plus
// trace_rays.glsl (closest hit, or any hit), with or without the traversal counters. A kernel that
// does not walk `layout` is refused (std::invalid_argument naming the layout's kernels).
// A triangle format that cannot run the robustness variant's triangle test is refused likewise
// (checkTriangleFormat).
// twoLevel: over a two-level tree (layout/pack_two_level.hpp); refused (std::invalid_argument) for a
// layout or kernel without a two-level walk (checkTwoLevel).
// COMPUTE_LANES = kComputeLanes is trace_rays.glsl's workgroup size.
// persistentThreads: trace_rays.glsl's persistent-threads loop (the caller decides: persistentThreadsOn,
// traversal/kernels.hpp).
constexpr int kComputeLanes = 64;
AssembledShader assembleRayTracer(const std::string& kernel, Storage storage, Robustness robust, int bvhStackSize,
                                  bool anyHit, bool countStats, const std::string& layout = "v1",
                                  const std::string& triangles = "raw", bool twoLevel = false,
                                  bool persistentThreads = false);
// The traversal alone (defines, common.glsl, storage, layout, ray tests, triangle format, kernel;
// for a two-level tree the kernel twice around two_level.glsl): traceClosest and traceAny, for a
// caller's own main (the ray tracer's trace_rays.glsl, tests). `defines`: extra #define lines.
AssembledShader assembleTraversal(const std::string& kernel, Storage storage, Robustness robust, int bvhStackSize,
                                  const std::string& defines, const std::string& layout = "v1",
                                  const std::string& triangles = "raw", bool twoLevel = false);
// Throws std::invalid_argument unless `layout` packs two-level trees and `kernel` (walking it; "" =
// the layout's default) has a two-level walk, naming the valid ones.
void checkTwoLevel(const std::string& layout, const std::string& kernel);
// A single-module full-screen pass (e.g. SMAA): `#version 450 core` + `defines` + the module.
AssembledShader assembleModule(const std::string& defines, const std::string& module);
std::string fullscreenVertexShader();

// Name -> text of every embedded .glsl module (generated at build time from shaders/ and traversal/).
const std::map<std::string, std::string>& glslSources();
const std::string& glslModule(const std::string& name);  // throws std::out_of_range naming it

}  // namespace bvhlab
