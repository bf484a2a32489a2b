#include "render/trace_command.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <random>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/frame_stats.hpp"
#include "render/gl_context.hpp"
#include "render/ray_tracer_gl.hpp"
#include "render/render_job.hpp"
#include "render/workloads.hpp"
#include "traversal/embree_tracer.hpp"

namespace bvhlab {

namespace {

// Two tracers' closest hits on different triangles at the same distance are a tie, not a mismatch:
// rays through a shared edge or vertex, or coplanar overlapping triangles. "Same distance" allows
// the two intersection algorithms' rounding of t: each is within a few ulps of the exact value
// (Woop et al. 2013 for the watertight test), so 2^-16 relative is far above it and far below any
// gap between distinct surfaces the scenes have.
constexpr double kTieRelativeT = 0x1.0p-16;

struct Agreement {
  uint64_t mismatches = 0;  // hit vs miss, or different triangles at different distances
  uint64_t ties = 0;        // different triangles at the same distance
  uint64_t hitMiss = 0;     // of the mismatches: one found a hit, the other none
};

Agreement compare(const std::vector<BatchHit>& a, const std::vector<BatchHit>& b, bool anyHit) {
  Agreement r;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].hit != b[i].hit) {
      ++r.mismatches;
      ++r.hitMiss;
    } else if (!anyHit && a[i].hit && a[i].prim != b[i].prim) {
      const double ta = a[i].t, tb = b[i].t;
      // NaN compares false here and counts as a mismatch.
      if (std::abs(ta - tb) <= kTieRelativeT * std::max(std::abs(ta), std::abs(tb)))
        ++r.ties;
      else
        ++r.mismatches;
    }
  }
  return r;
}

}  // namespace

void addTraceOptions(CLI::App& app, TraceCommand& c, RenderCliText& text) {
  RenderCommand& rc = c.render;
  rc.frames = 11;  // enough rounds for a 95% interval of the paired ratio (>= 6)
  app.option_defaults()->always_capture_default();
  app.add_option("input", rc.input, "scene .toml or mesh file")
      ->required()
      ->check(notADirectory("a scene .toml or a mesh file (OBJ/OFF/PLY/STL)"));
  app.add_option("--rays", c.rays, "workload: primary | shadow | specular | diffuse | ao");
  app.add_option("--count", c.count, "rays (secondary workloads: one per primary hit chosen)");
  app.add_option("--seed", c.seed, "seed of the secondary rays' random numbers");
  app.add_option("--ao-radius", c.aoRadius, "ao ray length, as a fraction of the scene's diagonal");
  app.add_flag("--json", rc.json, "print one JSON object");
  app.add_option("--frames", rc.frames, "timed rounds (one GLSL and one Embree trace each, in a shuffled order)");
  app.add_option("--warmup", rc.warmup, "untimed rounds first (llvmpipe compiles at the first dispatch)");
  app.add_option("--backend", rc.backend, "osmesa | egl");
  addTreeOptions(app, rc);
  app.add_option("--robust", rc.robust,
                 "triangle/box tests as render --robust (the offset is the generator's); Embree runs in robust mode with watertight triangles, in its default mode with fast ones");
  app.add_option("--max-frames", c.maxFrames, "go on past --frames until --target-ci-pct is met, up to this many (0 = fixed)");
  app.add_option("--target-ci-pct", c.targetCiPct, "stop when the GLSL time's 95% interval is within +-this % of its median");
  app.add_option("--max-seconds", c.maxSeconds, "stop the rounds after this long (0 = no limit)");
  app.add_option("--embree-threads", c.embreeThreads, "Embree's threads (0 = every core)");
  app.add_option("--program-copies", c.programCopies,
                 "trace with this many separately compiled copies of the kernel's program, each once per round; "
                 "from 6 the ratio to Embree's interval spans them")
      ->check(CLI::Range(1, 64));
  app.add_option("--eye", text.eye, "camera position x,y,z");
  app.add_option("--target", text.target, "camera target x,y,z");
  app.add_option("--up", text.up, "camera up x,y,z");
  app.add_option("--fov", rc.fov, "vertical field of view in degrees");
}

int runTrace(const TraceCommand& c) {
  const Workload workload = parseWorkload(c.rays);  // bad names fail before anything is loaded
  if (c.render.frames < 1 || c.render.warmup < 0) throw std::invalid_argument("--frames must be >= 1 and --warmup >= 0");
  if (c.maxFrames < 0 || !(c.targetCiPct >= 0.0) || !(c.maxSeconds >= 0.0))
    throw std::invalid_argument("--max-frames, --target-ci-pct and --max-seconds must be >= 0");
  const RenderCommand& rc = c.render;
  RenderSetup setup = setupRender(rc);
  for (const std::string& w : setup.buildReview.warnings) std::cerr << "bvhlab: warning: " << w << '\n';
  std::shared_ptr<const PreparedScene> prepared = prepareScene(std::move(setup.scene), rc.builder, setup.build, setup.shader.layout,
                                                               setup.shader.triangles);
  const TriangleSoup& soup = prepared->soup;
  if (soup.size() == 0) throw InputError(rc.input + ": no triangles to trace rays against");

  // The workload's secondary rays start from Embree's robust-mode hits whatever --robust says, so
  // every setting traces the same rays; the yardstick then runs Embree in the mode that matches the
  // kernel's triangle test (robust against watertight, its default test against the fast one: each
  // costs its tracer about the same, docs/layouts.md), a second scene only when they differ.
  EmbreeTracer generator(soup, c.embreeThreads);
  const bool embreeRobust = setup.shader.robust.triangle == TriangleTest::Watertight;
  std::optional<EmbreeTracer> matching;
  if (!embreeRobust) matching.emplace(soup, c.embreeThreads, false);
  const EmbreeTracer& embree = matching ? *matching : generator;
  WorkloadRequest req;
  req.workload = workload;
  req.count = c.count;
  req.seed = c.seed;
  req.aoRadius = c.aoRadius;
  req.width = prepared->scene.settings.width;
  req.height = prepared->scene.settings.height;
  const RayWorkload rays = generateWorkload(req, prepared->scene, soup, [&generator](const std::vector<BatchRay>& r) {
    std::vector<BatchHit> hits;
    generator.closest(r, hits);
    return hits;
  });
  const bool anyHit = isAnyHit(workload);

  std::unique_ptr<GlContext> ctx = createContext(setup.backend);
  RayTracerOptions to;
  to.kernel = setup.shader.kernel;
  to.storage = setup.shader.storage;
  to.robust = setup.shader.robust;
  to.anyHit = anyHit;
  // Copy 0 gives the hits and the counts; every copy is timed.
  std::vector<std::unique_ptr<GlRayTracer>> copies;
  for (int k = 0; k < c.programCopies; ++k) {
    copies.push_back(std::make_unique<GlRayTracer>(prepared->packed, to));
    copies.back()->setRays(rays.rays);
  }
  GlRayTracer& gl = *copies.front();

  std::vector<BatchHit> embreeHits;
  auto embreeTrace = [&] { return anyHit ? embree.occluded(rays.rays, embreeHits) : embree.closest(rays.rays, embreeHits); };
  for (int i = 0; i < rc.warmup; ++i) {
    for (auto& copy : copies) copy->trace();
    embreeTrace();
  }
  // Rounds: one trace of each copy and of Embree, in an order drawn per round (fixed seed), so drift
  // hits them alike and round i's times pair up.
  std::vector<double> glMs, embreeMs;
  std::vector<std::vector<double>> copyMs(copies.size());
  std::mt19937_64 order(0x7261795f74726163ull);
  const int maxFrames = std::max(rc.frames, c.maxFrames);
  const auto started = std::chrono::steady_clock::now();
  std::string stop = maxFrames > rc.frames ? "max_frames" : "fixed";
  for (int i = 0; i < maxFrames; ++i) {
    if (i >= rc.frames) {
      const auto ci = medianInterval(glMs);
      if (c.targetCiPct > 0.0 && ci && ci->estimate > 0.0 && 50.0 * (ci->high - ci->low) / ci->estimate <= c.targetCiPct) {
        stop = "target";
        break;
      }
      if (c.maxSeconds > 0.0 &&
          std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count() >= c.maxSeconds) {
        stop = "max_seconds";
        break;
      }
    }
    // Every copy and Embree once, in a shuffled order; the round's GLSL time is the median over the
    // copies (one copy: its time).
    std::vector<size_t> slots(copies.size() + 1);  // slot copies.size() is Embree
    for (size_t k = 0; k < slots.size(); ++k) slots[k] = k;
    shuffleRound(slots, order);
    std::vector<double> round;
    for (size_t slot : slots) {
      if (slot == copies.size()) {
        embreeMs.push_back(embreeTrace());
      } else {
        copyMs[slot].push_back(copies[slot]->trace());
        round.push_back(copyMs[slot].back());
      }
    }
    glMs.push_back(medianOf(round));
  }
  const std::vector<BatchHit> glHits = gl.results();
  const Agreement agree = compare(glHits, embreeHits, anyHit);
  const std::vector<glm::uvec4> counts = gl.traceCounted();
  uint64_t visits = 0, tests = 0, boxTests = 0, overflows = 0, glFound = 0, embreeFound = 0;
  double visitsSq = 0.0, testsSq = 0.0, boxTestsSq = 0.0;
  for (const glm::uvec4& k : counts) {
    visits += k.x;
    tests += k.y;
    boxTests += k.w;
    visitsSq += double(k.x) * double(k.x);
    testsSq += double(k.y) * double(k.y);
    boxTestsSq += double(k.w) * double(k.w);
    overflows += k.z != 0u;
  }
  for (size_t i = 0; i < glHits.size(); ++i) {
    glFound += glHits[i].hit;
    embreeFound += embreeHits[i].hit;
  }

  const double n = double(rays.rays.size());
  const double ms = medianOf(glMs), eMs = medianOf(embreeMs);
  const auto ci = medianInterval(glMs), eCi = medianInterval(embreeMs);
  // The ratio to Embree: across the copies from 6 of them (per copy its paired ratio, then the median
  // of those with its order-statistic interval), else over the rounds.
  std::vector<double> copyRatios;
  if (copies.size() > 1)
    for (const std::vector<double>& m : copyMs)
      if (const auto r = pairedRatio(m, embreeMs)) copyRatios.push_back(r->estimate);
  const std::optional<Interval> acrossCopies =
      copyRatios.size() == copies.size() ? medianInterval(copyRatios) : std::nullopt;
  const auto ratio = acrossCopies ? acrossCopies : pairedRatio(glMs, embreeMs);
  const auto orNull = [](const std::optional<Interval>& i, bool high) {
    return i ? nlohmann::json(high ? i->high : i->low) : nlohmann::json();
  };
  const BuildStats& b = prepared->stats;
  const double visitsPerRay = n > 0 ? double(visits) / n : 0.0, testsPerRay = n > 0 ? double(tests) / n : 0.0;
  nlohmann::json j;
  j["input"] = rc.input;
  j["workload"] = workloadName(workload);
  j["any_hit"] = anyHit;
  j["rays"] = rays.rays.size();
  j["seed"] = c.seed;
  j["primary_grid"] = {rays.gridWidth, rays.gridHeight};
  j["primary_hits"] = rays.primaryHits;
  if (workload == Workload::Ao) j["ao_distance"] = rays.aoDistance;
  j["frames"] = glMs.size();
  j["measure_stop"] = stop;
  j["ci_target_pct"] = c.targetCiPct > 0.0 ? nlohmann::json(c.targetCiPct) : nlohmann::json();
  j["warmup"] = rc.warmup;
  j["ms"] = ms;
  j["ms_ci_low"] = orNull(ci, false);
  j["ms_ci_high"] = orNull(ci, true);
  j["ms_all"] = glMs;
  // The names the experiment tables share with render: one "frame" is one pass over the batch.
  j["frame_ms"] = ms;
  j["frame_ms_ci_low"] = j["ms_ci_low"];
  j["frame_ms_ci_high"] = j["ms_ci_high"];
  j["ci_pct"] = ci && ci->estimate > 0.0 ? nlohmann::json(50.0 * (ci->high - ci->low) / ci->estimate) : nlohmann::json();
  j["frame_ms_all"] = glMs;
  j["mrays_per_s"] = ms > 0 ? n / (ms * 1e3) : 0.0;
  j["embree_ms"] = eMs;
  j["embree_ms_ci_low"] = orNull(eCi, false);
  j["embree_ms_ci_high"] = orNull(eCi, true);
  j["embree_ms_all"] = embreeMs;
  j["embree_mrays_per_s"] = eMs > 0 ? n / (eMs * 1e3) : 0.0;
  j["embree_threads"] = embree.threads();
  j["embree_build_ms"] = embree.buildMs();
  j["embree_robust"] = embree.robust();
  j["ratio_to_embree"] = ratio ? nlohmann::json(ratio->estimate) : nlohmann::json(eMs > 0 ? ms / eMs : 0.0);
  j["ratio_ci_low"] = orNull(ratio, false);
  j["ratio_ci_high"] = orNull(ratio, true);
  j["ratio_interval_over"] = acrossCopies ? "program copies" : "rounds";
  j["program_copies"] = copies.size();
  if (copies.size() > 1) {
    j["ms_copies"] = copyMs;
    j["ratio_to_embree_copies"] = copyRatios;
  }
  j["node_visits_per_ray"] = visitsPerRay;
  j["triangle_tests_per_ray"] = testsPerRay;
  j["box_tests_per_ray"] = n > 0 ? double(boxTests) / n : 0.0;  // a wide node visit tests several boxes
  // 95% intervals of the per-ray means over this batch (normal approximation: the batch has
  // thousands of rays; the counts are bounded, so the central limit theorem applies). Another builder
  // traced with the same seed gets the same rays: comparing two such means with these intervals as if
  // independent is conservative (the per-ray counts are positively correlated).
  const auto meanInterval = [n](double sum, double sumSq, const char* key, nlohmann::json& out) {
    if (n < 2) {
      out[std::string(key) + "_ci_low"] = nullptr;
      out[std::string(key) + "_ci_high"] = nullptr;
      return;
    }
    const double mean = sum / n, var = std::max(0.0, (sumSq - n * mean * mean) / (n - 1.0));
    const double half = 1.959964 * std::sqrt(var / n);  // the normal distribution's 97.5% quantile
    out[std::string(key) + "_ci_low"] = mean - half;
    out[std::string(key) + "_ci_high"] = mean + half;
  };
  meanInterval(double(visits), visitsSq, "node_visits_per_ray", j);
  meanInterval(double(tests), testsSq, "triangle_tests_per_ray", j);
  meanInterval(double(boxTests), boxTestsSq, "box_tests_per_ray", j);
  j["ray_cost"] = prepared->cost.traversalCost * visitsPerRay + prepared->cost.intersectionCost * testsPerRay;
  j["stack_overflow_rays"] = overflows;
  j["hits"] = glFound;
  j["embree_hits"] = embreeFound;
  j["hit_mismatches"] = agree.mismatches;
  j["hit_miss_mismatches"] = agree.hitMiss;
  j["hit_ties"] = agree.ties;
  j["builder"] = rc.builder;
  j["layout"] = prepared->packed.layout;
  j["triangle_format"] = prepared->packed.triangleFormat;  // "triangles" is the triangle count
  j["kernel"] = to.kernel;
  j["leaf_size"] = setup.buildReview.leafSize;
  j["warnings"] = setup.buildReview.warnings;
  j["robust"] = robustnessName(to.robust);
  j["storage"] = storageName(to.storage);
  j["triangles"] = soup.size();
  j["build_ms"] = b.buildMs;
  j["sah_cost"] = b.sahCost;
  j["references"] = b.references;
  j["tree_hash"] = prepared->treeHash();
  j["epo"] = prepared->endPointOverlap();
  j["nodes"] = b.nodes;
  j["leaves"] = b.leaves;
  j["bvh_depth"] = b.depth;
  j["bytes"] = b.bytes;
  j["bytes_per_triangle"] = double(b.bytes) / double(soup.size());
  j["optimize"] = rc.optimize.empty() ? nlohmann::json() : nlohmann::json(rc.optimize);
  j["sah_before_optimize"] = b.sahBeforeOptimize;
  j["optimize_ms"] = b.optimizeMs;
  j["backend"] = backendName(setup.backend);
  j["renderer"] = ctx->renderer();
  j["gpu"] = !ctx->software();
  if (rc.json) {
    std::cout << j.dump() << std::endl;
  } else {
    std::printf("%s: %zu %s rays, %s on %s over %s (leaf %u): %.2f ms (%.1f Mrays/s), Embree %.2f ms (%.1f Mrays/s, %u threads): "
                "%.2fx Embree's time; %.1f node visits + %.1f triangle tests per ray; %llu hit mismatches, %llu ties\n",
                rc.input.c_str(), rays.rays.size(), workloadName(workload), to.kernel.c_str(),
                prepared->packed.layout.c_str(), rc.builder.c_str(),
                setup.buildReview.leafSize, ms, j["mrays_per_s"].get<double>(), eMs, j["embree_mrays_per_s"].get<double>(),
                embree.threads(), j["ratio_to_embree"].get<double>(), visitsPerRay, testsPerRay,
                (unsigned long long)agree.mismatches, (unsigned long long)agree.ties);
  }
  if (overflows > 0) {
    std::cerr << "bvhlab: error: traversal stack overflowed on " << overflows << " rays\n";
    return 3;
  }
  return 0;
}

}  // namespace bvhlab
