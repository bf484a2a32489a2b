// The `two-level` update strategy (builders/update.hpp: its spec and options): a two-level tree
// (layout/pack_two_level.hpp) kept up to date over an animated scene's clip.
//
// Instances: one per mesh object of the scene (datasets/animation.hpp objectInstances), in object
// order; an object's instance id is its index among the mesh objects, and its triangles are the range
// [firstTriangle, firstTriangle + count) of gatherTriangles(scene) (flatTriangle maps a two-level hit
// back to that order). Analytic objects have no triangles and no instance.
//
// BLASes, built on the first update with UpdateOptions::builder and ::build over the object's
// object-space triangles (localMeshAt):
//   - objects whose own triangles never change (rigid, moving or not) share one BLAS per rest mesh
//     (SceneAnimation::localMeshes; a static mesh object, stored in world space, has its own BLAS
//     placed by the identity). Such a BLAS is built once and never touched again, whatever the policy:
//     its triangles are the same every frame.
//   - an object that deforms has a BLAS of its own, which the policy updates every frame:
//       blas=static   refused (std::invalid_argument naming the object): its tree would not contain its
//                     triangles after frame 0
//       blas=refit    refit (builders/refit.hpp), the first frame's topology kept
//       blas=rebuild  rebuilt with the builder
// TLAS: rebuilt every update over the instances' world boxes (transformBox of each BLAS's root box
// under the frame's transform) with spec.tlasBuilder (default: UpdateOptions::builder) and
// UpdateOptions::build's options, one instance per TLAS leaf at most maxLeafSize.
//
// An update's parts, each timed on its own (steady_clock): blasMs (the BLAS updates), tlasMs (the TLAS
// build and writing its nodes and instance records: repackTopLevel), and packMs (packing changed
// BLASes into the layout and the BLASES region: the part of `upload` a flat tree's pack is). The
// object-space triangles of deforming objects are evaluated before the clock starts, as a flat
// strategy's triangles are gathered before its update.
//
// Deterministic: the same scene, spec and options give the same streams for any BuildOptions::threads.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "builders/update.hpp"
#include "datasets/scene.hpp"
#include "layout/pack_two_level.hpp"

namespace bvhlab {

class TwoLevelUpdater {
 public:
  // spec: parseUpdateSpec of a two-level spec (std::invalid_argument for another); layout: a layout
  // with a two-level walk (std::invalid_argument naming them otherwise). Checks the builders and
  // options as makeUpdateStrategy does.
  TwoLevelUpdater(const UpdateSpec& spec, const UpdateOptions& options, const std::string& layout);
  ~TwoLevelUpdater();
  TwoLevelUpdater(const TwoLevelUpdater&) = delete;
  TwoLevelUpdater& operator=(const TwoLevelUpdater&) = delete;

  struct Step {
    bool blasBuilt = false;             // some BLAS was built from scratch (the first update; blas=rebuild)
    uint32_t blasUpdated = 0;           // BLASes built, refit or rebuilt by this update
    double blasMs = 0.0, tlasMs = 0.0;  // the update's two parts (update = their sum)
    double packMs = 0.0;                // BLAS packing (0 when no BLAS changed)
  };
  // Brings the two-level tree to `scene` as it stands at `frame` (setFrame(scene, frame) done by the
  // caller). Every update must see the same objects and triangle counts as the first
  // (std::invalid_argument otherwise). Throws std::invalid_argument for blas=static with a deforming
  // object, and InputError for bad triangles (as the flat strategies).
  Step update(const Scene& scene, int frame);

  const PackedTwoLevel& packed() const { return packed_; }
  size_t instanceCount() const { return instances_.size(); }
  size_t blasCount() const { return blases_.size(); }
  size_t nodeCount() const;  // the TLAS's nodes and every BLAS's (each shared BLAS once)
  // The two-level tree's cost estimate under the surface-area model (build.cost): the TLAS's inner
  // nodes at Ct x their area, and each instance reference at its world box's area x its BLAS's own
  // sahCost (which is normalised to the BLAS's root), all over the TLAS root's area. The BLAS term
  // takes a ray that meets the instance's world box to meet the BLAS as a ray of its object space
  // would: exact for translations, an estimate under rotation and scale.
  double sahCost() const;
  // The tree's SAH parts: the TLAS's own sahCost (instances at Ci each) and the BLASes' mean sahCost.
  double tlasSahCost() const;
  // The triangle of gatherTriangles(scene) order that instance `instance`'s triangle `triangle` is.
  uint32_t flatTriangle(uint32_t instance, uint32_t triangle) const;
  const UpdateSpec& spec() const { return spec_; }

 private:
  struct Blas;
  UpdateSpec spec_;
  UpdateOptions options_;
  TopLevelBuild top_;
  std::string layout_;
  std::vector<std::unique_ptr<Blas>> blases_;
  std::vector<Instance> instances_;
  std::vector<int> instanceObject_;       // per instance: its object
  std::vector<uint32_t> instanceFirst_;   // per instance: its first triangle in gatherTriangles order
  std::vector<uint32_t> instanceCount_;   // per instance: its triangles
  PackedTwoLevel packed_;
  std::vector<PackedBvh> packedBlases_;
  bool first_ = true;
};

}  // namespace bvhlab
