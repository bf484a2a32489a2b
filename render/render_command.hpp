// `bvhlab render`: one scene, one configuration, timed frames, image + JSON out.
#pragma once
#include <optional>
#include <string>

#include <glm/glm.hpp>

namespace bvhlab {

struct RenderCommand {
  std::string input;
  std::string output;       // image path ('' = none)
  std::string visitsOutput; // heatmap path ('' = none)
  bool json = false;
  std::optional<int> width, height, depth;
  int frames = 5, warmup = 2;
  std::string backend = "osmesa";
  std::string view = "shaded";  // shaded|normal|depth|primid|visits
  bool uber = false;
  std::string builder = "sah-binned";
  std::string layout = "v1";  // texture layout the tree is packed in (layout/layouts.hpp)
  std::string kernel;         // traversal kernel; "" = the layout's default (stack-ordered for v1)
  std::string triangles = "raw";  // triangle format (layout/triangle_formats.hpp), any layout
  int leafSize = 4;
  int bins = 0;
  std::string optimize;    // post-pass after the builder: "" | "reinsert"
  float sbvhAlpha = 1e-5f; // sbvh: spatial splits only where object-split children overlap more than this
  float sbvhBudget = 2.0f; // sbvh: at most this many leaf references per primitive (BuildOptions::sbvhReferenceBudget)
  int plocRadius = 16;     // ploc: nearest-neighbour search radius
  int plocTopDown = 0;     // ploc: the last n / F clusters split top-down by binned SAH (0 = cluster to the end)
  int mortonSizeBits = 0;  // ploc, lbvh: primitive-size bits in the Morton codes (builders/morton.hpp)
  std::string mortonGrid = "cube";  // ploc, lbvh: the Morton codes' grid, cube | axes (BuildOptions::mortonGrid)
  std::string storage = "tbo";
  std::string branching = "full";
  std::optional<glm::dvec3> eye, target;  // world coordinates (a far scene is stored relative to its origin)
  std::optional<glm::vec3> up;
  std::optional<float> fov;
  std::optional<float> exposure;
  std::string aa = "none";          // none | smaa | smaa-PRESET | ssaa4 | ssaa16 (regular 2x2 / 4x4 grid in the tracer)
  std::string smaaPreset = "high";  // low | medium | high | ultra
  std::string smaaEdges = "luma";   // luma | color | geometry: what SMAA's edge detection compares
  std::string textureLod = "none";  // none | cones | cones-aniso (shaders/texture_lod.glsl)
  std::string robust = "watertight";  // one of robustnessNames(); the default is ShaderOptions's (see there)
  bool cpu = false;  // render with the C++ mirror instead of GL
  // A recorded camera path (render/fly_camera.hpp): warm-up and timed frame i use pose i mod N, the
  // saved image and the statistics pose 0. Excludes --eye/--target/--up/--fov.
  std::string cameraPath;
  // An animated scene's clip, frame by frame (render/render_clip.hpp, render/trace_clip.hpp): the
  // tree kept up to date by this update strategy (builders/update.hpp spec; "" = frame 0 only).
  std::string update;
  int updateRepeats = 1;  // timed updates per frame, each by its own copy of the strategy
  bool epo = false;       // trace --update: per-frame EPO (seconds per frame on large meshes)
  // A shorter clip: frames 0, clipStep, 2 clipStep, ... of the scene's clip, at most clipFrames of
  // them (0 = as many as the clip has).
  int clipFrames = 0, clipStep = 1;
  // A GPU builder with --json: this many GL-timed builds of the scene after a warm-up, recorded as
  // gpu_build_ms and its interval (render/gpu_build_timing.hpp); 0 = none.
  int gpuBuilds = 0;
};

// Runs it; prints the JSON object on stdout when asked. Returns the process exit code.
int runRender(const RenderCommand& cmd);

}  // namespace bvhlab
