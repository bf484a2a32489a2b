// Keeping a tree up to date over an animation clip: the update strategies, their registry, and the
// per-frame driver (runClip).
//
// A clip gives, per frame, the triangles of that frame (FrameTriangles: the same count and order in
// every frame). A strategy owns the tree: its first update builds it with the configured builder
// (builders/builder.hpp), each later one rebuilds, refits (builders/refit.hpp) or refits with
// rotations (builders/rotate.hpp) as the strategy says. Strategies are named by a spec string:
//   rebuild               rebuild every frame with UpdateOptions::builder and ::build
//   refit                 refit every frame (the first frame's tree keeps its topology)
//   refit+rebuild:K       rebuild on frames 0, K, 2K, ... and refit between (K >= 1)
//   refit+rebuild:sah>R   refit, then rebuild when the refit tree's SAH exceeds R x the SAH of the tree
//                         made by the last rebuild (R >= 1): every frame kept without a rebuild has an
//                         SAH <= R x that of the last rebuild
//   refit+rotate          refit with tree rotations (Kopta et al. 2012)
//   two-level[:OPTIONS]   a top-level tree (TLAS) rebuilt every frame over per-object trees (BLASes);
//                         OPTIONS, comma-separated: blas=static|refit|rebuild (what happens to the BLAS
//                         of an object whose own triangles change; default static), tlas=BUILDER (the
//                         TLAS's builder; default UpdateOptions::builder). It keeps a tree per object,
//                         so it runs over a scene's instances (layout/two_level_update.hpp), not over
//                         FrameTriangles: makeUpdateStrategy refuses it.
// Adding a strategy: one builders/update_NAME.cpp with its factory, and one line in
// builders/update_registry.cpp.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "builders/bvh.hpp"
#include "builders/refit.hpp"

namespace bvhlab {

// What a spec string says (parseUpdateSpec).
struct UpdateSpec {
  std::string name;       // the registry entry: "rebuild", "refit", "refit+rebuild:K", "refit+rebuild:sah>R", "refit+rotate"
  std::string text;       // the spec as given, e.g. "refit+rebuild:8"
  uint32_t every = 0;     // refit+rebuild:K: K
  double sahRatio = 0.0;  // refit+rebuild:sah>R: R
  std::string blas = "static";  // two-level: "static", "refit" or "rebuild"
  std::string tlasBuilder;      // two-level: the TLAS's builder ("" = UpdateOptions::builder)
};

// How a strategy builds (frame 0 and every rebuild): a registered builder and its options. The SAH
// the strategies compare (and the records report) uses build.cost.
struct UpdateOptions {
  std::string builder = "sah-binned";
  BuildOptions build;
};

class UpdateStrategy {
 public:
  virtual ~UpdateStrategy() = default;
  // Brings the tree to `frame`: the first call builds it, every later call updates it. Returns true
  // when the tree was (re)built from scratch this frame. Every frame must have the first's triangle
  // count (std::invalid_argument otherwise); bad triangles throw InputError (datasets/scene.hpp).
  virtual bool update(const FrameTriangles& frame) = 0;
  // The tree of the last update (empty before the first).
  virtual const Bvh& tree() const = 0;
  // Rotations made by the last update (refit+rotate; 0 for the others).
  virtual uint32_t rotations() const { return 0; }
  virtual const UpdateSpec& spec() const = 0;
  virtual const UpdateOptions& options() const = 0;
};

struct UpdateStrategyInfo {
  std::string name;         // as in a spec; K and R stand for the number the spec gives
  std::string description;  // one line
  std::function<std::unique_ptr<UpdateStrategy>(const UpdateSpec&, const UpdateOptions&)> make;
  std::string options = {};  // what may follow the name (two-level's ":blas=...,tlas=..."), for messages
};
const std::vector<UpdateStrategyInfo>& updateStrategies();

// Parses a spec string. Throws std::invalid_argument naming the valid forms for an unknown name, and
// naming the bad number for K < 1 (or not a whole number) and R < 1 (or not a finite number), and for
// two-level an unknown or repeated option, a BLAS policy other than static/refit/rebuild and an
// unknown TLAS builder (naming the valid ones).
UpdateSpec parseUpdateSpec(const std::string& text);

// parseUpdateSpec, then the strategy. Throws std::invalid_argument as parseUpdateSpec does, for
// an unknown builder or bad build options (builders/builder.hpp reviewBuildOptions), and for two-level
// (a tree per object: layout/two_level_update.hpp runs it).
std::unique_ptr<UpdateStrategy> makeUpdateStrategy(const std::string& spec, const UpdateOptions& options);

// ---- the per-frame driver -------------------------------------------------------------------------

struct UpdateRecord {
  uint32_t frame = 0;
  bool rebuilt = false;
  // Wall time of UpdateStrategy::update (std::chrono::steady_clock), in ms: box computation, build,
  // refit, rotations, and the SAH a refit+rebuild:sah>R strategy computes to decide.
  double updateMs = 0.0;
  double sahCost = 0.0;       // sahCost(tree, options.build.cost), computed after the timing
  std::optional<double> epo;  // builders/epo.hpp, when ClipOptions::epo (after the timing)
  uint32_t rotations = 0;     // refit+rotate
  // layout/tree_hash.hpp packedTreeHash of the packed tree: the layout library sits above this one,
  // so runClip leaves it empty for the caller's onFrame to fill (it packs the tree anyway).
  std::string treeHash;
};

struct ClipOptions {
  bool epo = false;         // EPO per frame: seconds per frame on 100k triangles, hence off by default
  unsigned epoThreads = 0;  // endPointOverlap's workers (0 = hardware concurrency; the value is the same)
};

// The clip's frames, one at a time: frame(f) for f in [0, frameCount). The spans must stay valid
// until the next call.
using FrameSource = std::function<FrameTriangles(uint32_t frame)>;
// Called once per frame after its record is made: the tree of that frame (valid until the next
// update) and the record, which the caller may complete (treeHash) or extend.
using FrameCallback = std::function<void(uint32_t frame, const Bvh& tree, UpdateRecord& record)>;

// Runs `strategy` over the clip's frames in order and returns one record per frame. The strategy
// should be fresh (its first update builds); a strategy that already holds a tree continues from it.
// Throws std::invalid_argument when a frame's triangle count differs from frame 0's (naming both).
std::vector<UpdateRecord> runClip(UpdateStrategy& strategy, uint32_t frameCount, const FrameSource& frame,
                                  const ClipOptions& options = {}, const FrameCallback& onFrame = {});
std::vector<UpdateRecord> runClip(UpdateStrategy& strategy, std::span<const FrameTriangles> frames,
                                  const ClipOptions& options = {}, const FrameCallback& onFrame = {});

}  // namespace bvhlab
