// SMAA 1x as a post-process of the ray-traced frame (Jimenez et al., "SMAA: Enhanced Subpixel
// Morphological Antialiasing", CGF 31(2), 2012): edge detection, blending weights, neighbourhood
// blending, three full-screen passes into this object's own FBOs (shaders/smaa_*.glsl; textures from
// shaders/smaa_textures.hpp), with orthogonal and diagonal pattern detection.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace bvhlab {

enum class SmaaPreset { Low, Medium, High, Ultra };
// What the edge pass compares: luma (the paper's default), colour, or luma only between pixels whose
// primary rays hit different primitives (Geometry: needs the tracer's primary id, ShaderOptions::
// primaryIdOut). Geometry leaves the contrast inside a primitive alone: a texture's own edges, which
// texture LOD (--texture-lod) filters, are not blurred a second time.
enum class SmaaEdgeMode { Luma, Color, Geometry };
// "luma" | "color" | "geometry"; throws std::invalid_argument naming the valid ones.
SmaaEdgeMode parseSmaaEdgeMode(const std::string& name);

SmaaPreset parseSmaaPreset(const std::string& name);  // throws std::invalid_argument naming the valid ones
const char* smaaPresetName(SmaaPreset preset);

struct SmaaSettings {
  float threshold = 0.1f;        // minimum contrast of an edge (gamma-space luma or colour, 0..1)
  int maxSearchSteps = 16;       // bilinear fetches per search direction (2 pixels each)
  int cornerRounding = 25;       // percent of the area kept at sharp corners; 100 disables the test
  int maxDiagSearchSteps = 8;    // units searched along a diagonal each way (0 = no diagonal patterns)
  SmaaEdgeMode edgeMode = SmaaEdgeMode::Luma;
  // The SMAA reference presets (threshold, search steps, diagonal steps, corner rounding):
  // low 0.15/4/off/off, medium 0.1/8/off/off, high 0.1/16/8/25, ultra 0.05/32/16/25.
  static SmaaSettings preset(SmaaPreset preset);
};

class SmaaPass {
 public:
  // Needs a current GL 4.5 context. Compiles the three passes and creates the area/search textures
  // and the edges/weights/output targets for a width x height frame. Throws std::invalid_argument for a
  // bad size or setting, std::runtime_error (with the driver log) if a pass fails to compile.
  SmaaPass(int width, int height, const SmaaSettings& settings = SmaaSettings::preset(SmaaPreset::High));
  ~SmaaPass();
  SmaaPass(const SmaaPass&) = delete;
  SmaaPass& operator=(const SmaaPass&) = delete;

  // Runs the three passes on `colorTexture` (a GL_TEXTURE_2D, RGBA8 holding sRGB-encoded values, of
  // this pass's size, e.g. the tracer's colour attachment). Clears its targets first. Returns the
  // output texture (RGBA8, sRGB-encoded values), owned by this object. Does not wait for the GPU.
  // With SmaaEdgeMode::Geometry, `primaryIdTexture` is the tracer's R32UI primary id
  // (GpuRenderer::primaryIdTexture()); std::invalid_argument if it is 0 then.
  unsigned apply(unsigned colorTexture, unsigned primaryIdTexture = 0);
  // The same, waiting for each pass (glFinish) and returning its wall-clock ms: edges, weights, blend.
  // For profiling and the viewer's overlay; apply() leaves the passes pipelined.
  std::array<double, 3> applyProfiled(unsigned colorTexture, unsigned primaryIdTexture = 0);
  // Convenience: uploads RGBA8 bytes (bottom-up, 4*w*h), applies, waits and reads the result back.
  std::vector<uint8_t> apply(const std::vector<uint8_t>& rgbaBottomUp);

  std::vector<uint8_t> readOutput() const;      // RGBA8, bottom-up
  std::vector<glm::vec2> readEdges() const;     // per pixel (left edge, bottom edge) in {0, 1}
  std::vector<glm::vec4> readWeights() const;   // per pixel, layout in smaa_weights.glsl
  unsigned outputTexture() const { return outputTex_; }
  int width() const { return width_; }
  int height() const { return height_; }
  const SmaaSettings& settings() const { return settings_; }

 private:
  int width_, height_;
  SmaaSettings settings_;
  unsigned edgesProgram_ = 0, weightsProgram_ = 0, blendProgram_ = 0, vao_ = 0;
  unsigned edgesTex_ = 0, weightsTex_ = 0, outputTex_ = 0, areaTex_ = 0, searchTex_ = 0, uploadTex_ = 0;
  unsigned areaDiagTex_ = 0;
  unsigned edgesFbo_ = 0, weightsFbo_ = 0, outputFbo_ = 0;
  unsigned linearClamp_ = 0;  // sampler: bilinear, clamped (edges and area fetches)

  void runPass(int pass, unsigned colorTexture, unsigned primaryIdTexture);  // 0: edges, 1: weights, 2: blend
  void checkPrimaryId(unsigned primaryIdTexture) const;
};

}  // namespace bvhlab
