#include "render/trace_group.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "datasets/scene_io.hpp"
#include "render/frame_stats.hpp"
#include "render/gl_context.hpp"
#include "render/ray_tracer_gl.hpp"
#include "render/trace_clip.hpp"
#include "render/trace_run.hpp"

namespace bvhlab {

using nlohmann::json;

namespace {

// A run of the group (or the A/A control of the first run that works): its kernel over its tree,
// tracing its yardstick's batch, by one or more separately compiled copies of its program.
struct Run {
  std::string key;
  TraceCommand cmd;
  std::optional<TraceSetup> setup;
  size_t yardstick = 0;
  std::vector<std::unique_ptr<GlRayTracer>> copies;  // copy 0 gives the answers and the counts
  std::vector<std::vector<double>> copyMs;           // per copy, its timed passes
  std::vector<double> ms;                            // per round, the median over the copies
  std::string error;
  bool control = false;
  bool alive() const { return !copies.empty() && error.empty(); }
};

// One trace of a round: copy `copy` of run `run`, or (embree) yardstick `run`.
struct Slot {
  size_t run = 0, copy = 0;
  bool embree = false;
};

struct Yardstick {
  std::unique_ptr<TraceYardstick> tracer;
  std::vector<double> ms;
  std::vector<std::string> keys;  // TraceYardstick::key of every run that shares it
};

// A trace group holds every run's tree and GL buffers at once (llvmpipe's buffers are host memory),
// where runs traced alone held one each: a 10M-triangle tree takes gigabytes on the CPU and its packed
// bytes again in GL. So a run set up once the group's resident memory plus the GL uploads to come
// would pass this fraction of the machine's physical memory is handed back to the runner
// ("deferred"), which traces it in a later group; the first run is always kept. Half leaves room
// for llvmpipe's compiled code, Embree's builds and the runner beside the group. The environment
// variable BVHLAB_TRACE_GROUP_MEMORY_FRACTION (in (0, 1]) replaces it: for a machine shared with other
// work, and for the test that checks the hand-back.
constexpr double kGroupMemoryFraction = 0.5;

double groupMemoryFraction() {
  const char* text = std::getenv("BVHLAB_TRACE_GROUP_MEMORY_FRACTION");
  if (!text || !*text) return kGroupMemoryFraction;
  char* end = nullptr;
  const double f = std::strtod(text, &end);
  if (*end != '\0' || !(f > 0.0 && f <= 1.0))
    throw std::invalid_argument(std::string("BVHLAB_TRACE_GROUP_MEMORY_FRACTION: '") + text + "' is not in (0, 1]");
  return f;
}

uint64_t residentBytes() {
  std::ifstream statm("/proc/self/statm");
  uint64_t size = 0, resident = 0;
  statm >> size >> resident;  // pages
  return resident * uint64_t(sysconf(_SC_PAGESIZE));
}

double intervalPct(const std::vector<double>& ms) {
  const auto ci = medianInterval(ms);
  if (!ci || !(ci->estimate > 0.0)) return std::numeric_limits<double>::infinity();
  return 50.0 * (ci->high - ci->low) / ci->estimate;
}

}  // namespace

json traceGroup(const GroupSpec& spec) {
  const GroupSettings& g = spec.settings;
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&start] {
    return std::to_string(int(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() + 0.5)) + " s";
  };

  // ---- set up every run (CPU): one scene load per input, its tree, its batch (shared when equal) ----
  std::vector<std::unique_ptr<Run>> runs;
  std::vector<Yardstick> yardsticks;
  std::map<std::string, Scene> scenes;
  std::map<std::string, std::shared_ptr<const PreparedScene>> trees;  // runs with one treeKey share it
  json deferred = json::object();
  json clips = json::object();  // runs with --update: their clips' results
  std::vector<std::unique_ptr<TraceClip>> clipRuns;
  std::vector<std::string> clipKeys;
  const double fraction = groupMemoryFraction();
  const double budget = fraction * double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGESIZE));
  uint64_t uploads = 0;  // GL bytes the runs set up so far will upload (tree and rays)
  for (const GroupRunSpec& item : spec.runs) {
    auto r = std::make_unique<Run>();
    r->key = item.key;
    try {
      if (!item.error.empty()) throw InputError(item.error);
      r->cmd = parseTraceArgs(item.args);
      if (!r->cmd.render.update.empty()) {
        // A clip (`trace --update`): set up here, traced below with the group's other clips in
        // lockstep, frame by frame, in a GL context of their own (traceClipsInterleaved).
        clipRuns.push_back(std::make_unique<TraceClip>(r->cmd));
        clipKeys.push_back(r->key);
        continue;
      }
      auto scene = scenes.find(r->cmd.render.input);
      if (scene == scenes.end()) scene = scenes.emplace(r->cmd.render.input, loadInput(r->cmd.render.input)).first;
      r->setup.emplace(setupTrace(r->cmd, &scene->second, &trees));
      const uint64_t upload = (r->setup->prepared->stats.bytes + uint64_t(r->cmd.count) * 2 * sizeof(BatchRay)) *
                              uint64_t(g.programCopies);
      if (!runs.empty() && double(residentBytes() + uploads + upload) > budget) {
        deferred[r->key] = {{"deferred", "the group's memory would pass " + std::to_string(100 * fraction) +
                                             "% of physical memory"}};
        // Its tree goes too, unless a run kept before shares it.
        if (auto t = trees.find(treeKey(r->cmd.render)); t != trees.end() && t->second.use_count() <= 2) trees.erase(t);
        continue;
      }
      uploads += upload;
      for (const std::string& w : r->setup->setup.buildReview.warnings)
        std::fprintf(stderr, "bvhlab: warning: run %s: %s\n", r->key.c_str(), w.c_str());
      // A run whose batch follows from the same inputs shares its yardstick without building one;
      // otherwise a candidate is built and compared bit for bit (different inputs, same rays).
      const std::string key = TraceYardstick::key(r->cmd, *r->setup);
      auto same = std::find_if(yardsticks.begin(), yardsticks.end(), [&](const Yardstick& y) {
        return std::find(y.keys.begin(), y.keys.end(), key) != y.keys.end();
      });
      if (same == yardsticks.end()) {
        auto candidate = std::make_unique<TraceYardstick>(r->cmd, *r->setup);
        same = std::find_if(yardsticks.begin(), yardsticks.end(),
                            [&](const Yardstick& y) { return y.tracer->sameAs(*candidate); });
        if (same == yardsticks.end()) {
          yardsticks.push_back(Yardstick{std::move(candidate), {}, {}});
          same = yardsticks.end() - 1;
        }
        same->keys.push_back(key);
      }
      r->yardstick = size_t(same - yardsticks.begin());
    } catch (const std::exception& ex) {
      r->error = ex.what();
    }
    runs.push_back(std::move(r));
  }
  if (!clipRuns.empty()) {
    // The clips' A/A control (experiments/findings_clip.hpp): the first clip stepped a second time,
    // interleaved with the others as if it were another strategy.
    const bool control = g.clipControl;
    if (control) clipRuns.push_back(std::make_unique<TraceClip>(clipRuns.front()->command()));
    std::vector<uint64_t> overflows;
    std::vector<json> results;
    try {
      results = traceClipsInterleaved(clipRuns, overflows);
    } catch (const std::exception& ex) {
      for (const std::string& key : clipKeys) clips[key] = {{"error", ex.what()}};
    }
    if (control && !results.empty()) {
      const json& c = results.back();
      results.front()["aa_clip_control"] = {{"frame_total_ms", c["clip"]["frame_total_ms"]},
                                            {"total_ms", c["clip"]["total_ms"]},
                                            {"total_ms_ci_low", c["clip"]["total_ms_ci_low"]},
                                            {"total_ms_ci_high", c["clip"]["total_ms_ci_high"]}};
      results.pop_back();
      overflows.pop_back();
    }
    for (size_t k = 0; k < results.size(); ++k) {
      results[k]["session"] = g.session;
      results[k]["program"] = nullptr;
      if (overflows[k] > 0)
        clips[clipKeys[k]] = {{"error", "traversal stack overflowed on " + std::to_string(overflows[k]) + " rays"},
                              {"result", results[k]}};
      else
        clips[clipKeys[k]] = std::move(results[k]);
    }
    clipRuns.clear();
  }
  scenes.clear();  // every tree holds its own copy
  trees.clear();   // the runs hold theirs
  if (!deferred.empty())
    std::cerr << "bvhlab measure: " << deferred.size() << " runs handed back for a later group (memory)\n";

  // ---- GL: one context, one program per run -----------------------------------------------------------
  const auto firstSet = std::find_if(runs.begin(), runs.end(), [](const auto& r) { return r->error.empty(); });
  const Backend backend = firstSet != runs.end() ? (*firstSet)->setup->setup.backend : Backend::OSMesa;
  std::unique_ptr<GlContext> ctx = createContext(backend);
  const std::string renderer = ctx->renderer();
  auto makeTracers = [&](Run& r, int copies) {
    try {
      if (r.setup->setup.backend != backend) throw std::invalid_argument("a group shares one GL context: every run needs the same --backend");
      for (int k = 0; k < copies; ++k) {
        r.copies.push_back(std::make_unique<GlRayTracer>(r.setup->prepared->packed, r.setup->tracer));
        r.copies.back()->setRays(yardsticks[r.yardstick].tracer->rays().rays);
      }
      r.copyMs.resize(r.copies.size());
    } catch (const std::exception& ex) {
      r.error = ex.what();
      r.copies.clear();
    }
  };
  for (auto& r : runs)
    if (r->error.empty()) makeTracers(*r, g.programCopies);
  // The A/A control: the first run that works, traced a second time by a second compiled program.
  Run* controlled = nullptr;
  if (g.wantControl) {
    auto first = std::find_if(runs.begin(), runs.end(), [](const auto& r) { return r->alive(); });
    if (first != runs.end()) {
      controlled = first->get();
      auto c = std::make_unique<Run>();
      c->key = controlled->key;
      c->cmd = controlled->cmd;
      c->setup = controlled->setup;
      c->yardstick = controlled->yardstick;
      c->control = true;
      makeTracers(*c, 1);  // repeats the run's copy 0
      if (c->alive())
        runs.push_back(std::move(c));
      else
        std::cerr << "bvhlab measure: warning: no A/A control: " << c->error << "\n";
    }
  }
  std::cerr << "bvhlab measure: " << runs.size() << " traced entries and " << yardsticks.size() << " Embree batches ready ("
            << elapsed() << ")\n";

  // ---- warm-up, then rounds in a shuffled order until every interval is narrow enough --------------
  // One sample length for the group (its runs come from one config): dispatches per timed sample
  // from the warm-up's shortest dispatch of any run, so paired rounds time alike-made samples.
  double minSampleMs = 0.0;
  for (auto& r : runs)
    if (r->alive()) minSampleMs = std::max(minSampleMs, resolveMinSampleMs(r->cmd.minSampleMs, renderer));
  double shortest = std::numeric_limits<double>::infinity();
  int dispatches = 1;
  auto traceCopy = [&](Run& r, size_t copy, bool timed) {
    try {
      const double ms = r.copies[copy]->trace(timed ? dispatches : 1);
      if (timed)
        r.copyMs[copy].push_back(ms);
      else
        shortest = std::min(shortest, ms);
    } catch (const std::exception& ex) {
      r.error = std::string("trace failed: ") + ex.what();
      r.copies.clear();
    }
  };
  int warmup = 0;
  for (auto& r : runs)
    if (r->alive()) warmup = std::max(warmup, r->cmd.render.warmup);
  // With a sample length, one more pass after the warm-up times the dispatches (the first pass may
  // hold a JIT compile).
  for (int w = 0; w < warmup + (minSampleMs > 0.0 ? 1 : 0); ++w) {
    for (auto& r : runs)
      for (size_t k = 0; r->alive() && k < r->copies.size(); ++k) traceCopy(*r, k, false);
    if (w < warmup)
      for (Yardstick& y : yardsticks) y.tracer->trace();
  }
  dispatches = dispatchesPerSample(minSampleMs, shortest);
  std::vector<Slot> order;
  for (size_t i = 0; i < runs.size(); ++i)
    for (size_t k = 0; k < runs[i]->copies.size(); ++k) order.push_back(Slot{i, k, false});
  for (size_t y = 0; y < yardsticks.size(); ++y) order.push_back(Slot{y, 0, true});
  std::mt19937_64 rng(0x7472616365677270ull);  // fixed: the same group traces in the same orders every time
  int rounds = 0;
  std::string stop = g.minFrames == g.maxFrames ? "fixed" : "max_frames";
  const auto roundsStart = std::chrono::steady_clock::now();
  std::vector<double> round;
  while (rounds < g.maxFrames) {
    shuffleRound(order, rng);
    for (const Slot& slot : order) {
      if (slot.embree)
        yardsticks[slot.run].ms.push_back(yardsticks[slot.run].tracer->trace());
      else if (runs[slot.run]->alive())
        traceCopy(*runs[slot.run], slot.copy, true);
    }
    // A run's time of the round: the median over its copies (one copy: its time).
    for (auto& r : runs) {
      if (!r->alive()) continue;
      round.clear();
      for (const std::vector<double>& ms : r->copyMs) round.push_back(ms.back());
      r->ms.push_back(medianOf(round));
    }
    ++rounds;
    if (rounds < g.minFrames || g.minFrames == g.maxFrames) continue;
    double widest = 0.0;
    for (auto& r : runs)
      if (r->alive()) widest = std::max(widest, intervalPct(r->ms));
    if (rounds % 10 == 0)
      std::cerr << "bvhlab measure: round " << rounds << ": widest interval ±" << widest << "% (" << elapsed() << ")\n";
    if (widest <= g.targetPct) {
      stop = "target";
      break;
    }
    if (g.maxSeconds > 0.0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - roundsStart).count() >= g.maxSeconds) {
      stop = "max_seconds";
      break;
    }
  }

  // ---- counts, answers, JSON ----------------------------------------------------------------------------
  json out = {{"session", g.session}, {"rounds", rounds}, {"stop", stop}, {"renderer", renderer},
              {"gpu", !isSoftwareRenderer(renderer)}, {"command", "trace"}, {"yardsticks", yardsticks.size()},
              {"dispatches_per_sample", dispatches}, {"min_sample_ms", minSampleMs}};
  json results = json::object();
  const Run* control = nullptr;
  for (auto& r : runs) {
    if (r->control) {
      control = r.get();
      continue;
    }
    if (!r->error.empty()) {
      results[r->key] = {{"error", r->error}};
      continue;
    }
    try {
      TraceRounds tr;
      tr.glMs = r->ms;
      if (r->copies.size() > 1) tr.copyMs = r->copyMs;
      tr.embreeMs = yardsticks[r->yardstick].ms;
      tr.stop = stop;
      tr.targetCiPct = g.minFrames == g.maxFrames ? 0.0 : g.targetPct;
      tr.warmup = warmup;
      tr.minSampleMs = minSampleMs;
      tr.dispatches = dispatches;
      uint64_t overflows = 0;
      json j = traceResult(r->cmd, *r->setup, *yardsticks[r->yardstick].tracer, *r->copies.front(), tr, renderer, overflows);
      // With copies, findings take a comparison's interval across them (per copy the paired ratio of
      // two runs' rounds): `frame_ms_copies` as `measure` writes it, copy 0 first.
      if (r->copies.size() > 1) j["frame_ms_copies"] = r->copyMs;
      j["session"] = g.session;
      j["rounds"] = rounds;
      j["program"] = nullptr;  // every run of a trace group compiles its own program
      j["yardstick"] = r->yardstick;
      if (overflows > 0)
        results[r->key] = {{"error", "traversal stack overflowed on " + std::to_string(overflows) + " rays"}, {"result", j}};
      else
        results[r->key] = std::move(j);
    } catch (const std::exception& ex) {
      results[r->key] = {{"error", ex.what()}};
    }
  }
  if (controlled && control && control->error.empty() && results[controlled->key].contains("frame_ms")) {
    // original / control from paired rounds: its interval is the session's noise band (findings).
    json& j = results[controlled->key];
    // The control repeats copy 0 (findings compare it with copy 0's rounds, as for `measure`).
    j["aa_control_frame_ms_all"] = control->ms;
    if (const auto ratio = pairedRatio(controlled->copyMs.front(), control->ms)) {
      j["aa_control_ratio"] = ratio->estimate;
      j["aa_control_ci_low"] = ratio->low;
      j["aa_control_ci_high"] = ratio->high;
    }
  }
  for (auto& r : runs) r->copies.clear();  // before the context goes
  results.update(deferred);
  results.update(clips);
  out["runs"] = std::move(results);
  out["wall_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace bvhlab
