// `bvhlab render --update SPEC` on an animated scene (datasets/animation.hpp): the clip drawn frame by
// frame, the tree kept up to date by an update strategy (builders/update.hpp), as `trace --update`
// traces it (render/trace_clip.hpp, docs/animation.md).
//
// Per frame f: the scene set to f; its triangles gathered; the tree updated by every copy of the
// strategy (--update-repeats), each timed (update_ms); packed into the run's layout and triangle
// format (pack_ms) and the frame's renderer made over it (upload_ms: the pack plus the renderer's
// upload of the scene — tree streams, uniform block, textures — bracketed by glFinish and timed by
// steady_clock: render re-creates its renderer per frame, so this is the whole upload, not only the
// tree's); its program comes from one cache for the clip (a deeper tree's longer stack compiles
// another, `programs_compiled`); then --warmup untimed and --frames timed frames (ms, as a static
// render's frame_ms), and one frame with the counters (ray_cost, as `render --json` gives it; the
// frame's epo too, a pass over its tree). -o writes the last frame's image.
// A camera path (--camera-path) is refused with --update: the clip moves the camera.
// --update two-level[:...]: the two-level tree (render/clip_update.hpp ClipTwoLevel) drawn through the
// kernel's two-level walk (ShaderOptions::twoLevel; shading in world space: shaders/scene.glsl), with
// trace's per-frame two-level keys (blas_update_ms, tlas_update_ms, tlas_sah_cost, instances, blases)
// and no epo; the counters' node visits are the TLAS's and the BLASes' together.
#pragma once
#include <cstdint>

#include <nlohmann/json.hpp>

#include "render/render_command.hpp"

namespace bvhlab {

// The object `render --json --update` prints (a `frames` array and a `clip` object as trace's);
// `overflows`: pixels whose traversal stack overflowed, over every frame.
nlohmann::json renderClip(const RenderCommand& cmd, uint64_t& overflows);
// Runs it and prints it. Returns the process exit code.
int runRenderClip(const RenderCommand& cmd);

}  // namespace bvhlab
