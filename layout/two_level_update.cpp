// TwoLevelUpdater (layout/two_level_update.hpp): the `two-level` update strategy.
#include "layout/two_level_update.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <stdexcept>

#include "builders/builder.hpp"
#include "builders/refit.hpp"
#include "datasets/animation.hpp"
#include "layout/layouts.hpp"

namespace bvhlab {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point start) { return std::chrono::duration<double, std::milli>(Clock::now() - start).count(); }

// An object's object-space triangles as the packers want them (gatherTriangles over the one mesh:
// the same triangle order, normals and checks as the flat scene's).
TriangleSoup localSoup(const Scene& scene, int object, int frame) {
  Scene one;
  one.materials = scene.materials;
  one.meshes.push_back(localMeshAt(scene, object, frame));
  return gatherTriangles(one);
}

glm::mat4x3 affineOf(const glm::mat4& m) { return glm::mat4x3(m); }

}  // namespace

// One BLAS: its flat strategy (builders/update.hpp: refit or rebuild for a deforming object's, a
// strategy updated once for a rigid one's), the object it follows when it deforms, and its triangles.
struct TwoLevelUpdater::Blas {
  std::unique_ptr<UpdateStrategy> strategy;
  int deformingObject = -1;  // the object whose triangles it follows (-1: rigid, built once)
  TriangleSoup soup;         // the object-space triangles of the last update
  double sah = 0.0;          // sahCost of its tree (build.cost)
  bool changed = true;       // updated since it was last packed
};

TwoLevelUpdater::TwoLevelUpdater(const UpdateSpec& spec, const UpdateOptions& options, const std::string& layout)
    : spec_(spec), options_(options), layout_(findLayout(layout).name) {
  if (spec.name != "two-level") throw std::invalid_argument("TwoLevelUpdater: spec '" + spec.text + "' is not two-level");
  if (!twoLevelLayoutSupported(layout_))
    throw std::invalid_argument("update '" + spec.text + "': layout '" + layout_ +
                                "' has no two-level walk (layouts with one: v1, bvh2-cb)");
  reviewBuildOptions(options.builder, options.build);
  top_.builder = spec.tlasBuilder.empty() ? options.builder : spec.tlasBuilder;
  top_.options = options.build;
  reviewBuildOptions(top_.builder, top_.options);
}

TwoLevelUpdater::~TwoLevelUpdater() = default;

TwoLevelUpdater::Step TwoLevelUpdater::update(const Scene& scene, int frame) {
  Step step;
  const std::vector<ObjectInstance> objects = objectInstances(scene, frame);
  std::vector<const ObjectInstance*> meshObjects;
  for (const ObjectInstance& o : objects)
    if (o.mesh >= 0 && o.triangleCount > 0) meshObjects.push_back(&o);
  if (meshObjects.empty()) throw std::invalid_argument("update '" + spec_.text + "': the scene has no mesh objects");

  if (first_) {
    // One BLAS per rest mesh shared by rigid objects, one per deforming or static-world object.
    std::map<int, uint32_t> byLocalMesh;
    for (const ObjectInstance* o : meshObjects) {
      const std::string& name = scene.objects[size_t(o->object)].name;
      if (o->deforms && spec_.blas == "static")
        throw std::invalid_argument("update '" + spec_.text + "': object '" + name +
                                    "' deforms, so a static BLAS would not hold its triangles after frame 0; "
                                    "use two-level:blas=refit or two-level:blas=rebuild");
      uint32_t b;
      const bool shared = !o->deforms && o->localMesh >= 0;
      if (shared && byLocalMesh.count(o->localMesh)) {
        b = byLocalMesh[o->localMesh];
      } else {
        b = uint32_t(blases_.size());
        auto blas = std::make_unique<Blas>();
        const std::string flat = o->deforms ? spec_.blas : "refit";  // a rigid BLAS is updated once: built
        blas->strategy = makeUpdateStrategy(flat, options_);
        blas->deformingObject = o->deforms ? o->object : -1;
        blas->soup = localSoup(scene, o->object, frame);
        blases_.push_back(std::move(blas));
        if (shared) byLocalMesh[o->localMesh] = b;
      }
      instances_.push_back({b, affineOf(o->transform), uint32_t(std::max(0, scene.meshes[size_t(o->mesh)].material))});
      instanceObject_.push_back(o->object);
      instanceFirst_.push_back(o->firstTriangle);
      instanceCount_.push_back(o->triangleCount);
    }
    const auto start = Clock::now();
    for (auto& blas : blases_) {
      blas->strategy->update(FrameTriangles{blas->soup.v0, blas->soup.v1, blas->soup.v2});
      ++step.blasUpdated;
    }
    step.blasMs = msSince(start);
    step.blasBuilt = true;
  } else {
    if (meshObjects.size() != instances_.size())
      throw std::invalid_argument("update '" + spec_.text + "': " + std::to_string(meshObjects.size()) +
                                  " mesh objects after frames of " + std::to_string(instances_.size()));
    for (size_t i = 0; i < meshObjects.size(); ++i) {
      const ObjectInstance& o = *meshObjects[i];
      if (o.object != instanceObject_[i] || o.triangleCount != instanceCount_[i])
        throw std::invalid_argument("update '" + spec_.text + "': object " + std::to_string(o.object) +
                                    " changed its triangles between frames");
      instances_[i].objectToWorld = affineOf(o.transform);
    }
    // The deforming objects' triangles at this frame (the scene's animation, not the update).
    for (auto& blas : blases_)
      if (blas->deformingObject >= 0) blas->soup = localSoup(scene, blas->deformingObject, frame);
    const auto start = Clock::now();
    for (auto& blas : blases_) {
      if (blas->deformingObject < 0) continue;
      step.blasBuilt = blas->strategy->update(FrameTriangles{blas->soup.v0, blas->soup.v1, blas->soup.v2}) || step.blasBuilt;
      blas->changed = true;
      ++step.blasUpdated;
    }
    step.blasMs = msSince(start);
  }
  for (auto& blas : blases_)
    if (blas->changed) blas->sah = bvhlab::sahCost(blas->strategy->tree(), options_.build.cost);

  // Pack what changed (part of the upload, as a flat tree's pack is).
  if (step.blasUpdated > 0) {
    const auto start = Clock::now();
    const LayoutInfo& packer = findLayout(layout_);
    packedBlases_.resize(blases_.size());
    for (size_t b = 0; b < blases_.size(); ++b)
      if (blases_[b]->changed) {
        packedBlases_[b] = packer.pack(blases_[b]->strategy->tree(), blases_[b]->soup);
        blases_[b]->changed = false;
      }
    packed_ = packBottomLevel(packedBlases_);
    step.packMs = msSince(start);
  }
  const auto start = Clock::now();
  repackTopLevel(packed_, instances_, top_);
  step.tlasMs = msSince(start);
  first_ = false;
  return step;
}

double TwoLevelUpdater::tlasSahCost() const { return bvhlab::sahCost(packed_.tlas, options_.build.cost); }

double TwoLevelUpdater::sahCost() const {
  const Bvh& tlas = packed_.tlas;
  if (tlas.nodes.empty()) return 0.0;
  const double rootArea = tlas.nodes[0].bounds.halfArea();
  // A TLAS root of zero area (every instance a point) has no area ratios to weigh by.
  if (!(rootArea > 0.0)) return tlasSahCost();
  double sum = 0.0;
  for (const uint32_t n : refitOrder(tlas)) {  // every node reachable from the root
    const BvhNode& node = tlas.nodes[n];
    if (!node.isLeaf()) {
      sum += options_.build.cost.traversalCost * node.bounds.halfArea();
      continue;
    }
    for (uint32_t k = 0; k < node.count; ++k) {
      const uint32_t i = tlas.primIndices[node.first + k];
      const Instance& inst = instances_[i];
      sum += transformBox(packed_.blasBox[inst.blas], inst.objectToWorld).halfArea() * blases_[inst.blas]->sah;
    }
  }
  return sum / rootArea;
}

size_t TwoLevelUpdater::nodeCount() const {
  size_t n = packed_.tlas.nodes.size();
  for (const auto& blas : blases_) n += blas->strategy->tree().nodes.size();
  return n;
}

uint32_t TwoLevelUpdater::flatTriangle(uint32_t instance, uint32_t triangle) const {
  if (instance >= instanceFirst_.size() || triangle >= instanceCount_[instance])
    throw std::out_of_range("two-level hit: instance " + std::to_string(instance) + " triangle " +
                            std::to_string(triangle) + " does not exist");
  return instanceFirst_[instance] + triangle;
}

}  // namespace bvhlab
