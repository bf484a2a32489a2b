// `bvhlab view`: an interactive first-person viewer (GLFW window, Dear ImGui overlay) over the same
// GpuRenderer that `bvhlab render` uses, with live switching of builder, kernel, leaf size, depth,
// view, anti-aliasing and robustness variant. Keys, script format and camera-path format:
// docs/viewer.md.
#pragma once
#include <optional>
#include <stdexcept>
#include <string>

#include <glm/glm.hpp>

namespace bvhlab {

struct ViewerOptions {
  std::string input;                  // scene .toml or mesh file
  std::optional<int> width, height;   // window size (default: the scene's image size)
  std::string builder = "sah-binned";
  std::string optimize;  // post-pass after every (re)build: "" | "reinsert"
  std::string layout = "v1";          // texture layout of the tree (layout/layouts.hpp), for the session
  std::string triangles = "raw";      // triangle format (layout/triangle_formats.hpp), for the session
  std::string kernel;                 // "" = the layout's default kernel (K cycles through its kernels)
  int leafSize = 4;
  std::optional<int> depth;
  std::string view = "shaded";        // shaded | normal | depth | primid | visits
  float resolutionScale = 1.0f;       // render at this fraction of the window, upscaled (0.05..1)
  std::string aa = "none";            // none | smaa-low|medium|high|ultra | ssaa4 | ssaa16
  std::string robust = "watertight";  // one of robustnessNames() (traversal/kernels.hpp); default as render's
  std::string textureLod = "none";    // none | cones | cones-aniso (shaders/texture_lod.glsl), as render's
  bool readbackPresent = false;       // display through a CPU read-back + upload (the old path; for
                                      // measuring what the direct blit saves)
  std::optional<glm::dvec3> eye, target;  // world coordinates (a far scene is stored relative to its origin)
  std::optional<glm::vec3> up;
  std::optional<float> fov;
  std::string script;      // scripted input (docs/viewer.md); '' = interactive
  int frames = 0;          // stop after this many frames (0 = when the window closes / the script ends)
  std::string screenshot;  // write the last frame's image here (the render, without the overlay)
  std::string record;      // record the camera path here (one pose per frame; R toggles)
  std::string replay;      // replay a recorded camera path from the first frame
  // An animated scene (a [clip]) plays in the viewer: each clip frame the tree is kept up to date by
  // this update strategy (builders/update.hpp spec; U cycles, script `set update SPEC`). Unset: rebuild.
  // Refused for a static scene, as `render --update` refuses it.
  std::optional<std::string> update;
  bool paused = false;     // start the clip paused (Space plays / pauses)
  bool json = false;       // print the final state and every switch as one JSON object on stdout
  bool overlay = true;
};

// No display to open a window on. The message says what to do instead.
struct NoDisplayError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Opens the window and runs until it closes (or the script / --frames ends). Returns the exit code.
// Throws NoDisplayError without a display, InputError / std::invalid_argument for bad options.
int runViewer(const ViewerOptions& options);

// False when this binary was built without GLFW and Dear ImGui (runViewer then throws).
bool viewerAvailable();

}  // namespace bvhlab
