#include "render/measure_command.hpp"

#include <algorithm>
#include <cstdio>
#include <chrono>
#include <limits>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <numeric>
#include <random>

#include "datasets/scene_io.hpp"
#include "render/frame_stats.hpp"
#include "render/render_cli.hpp"
#include "render/program_cache.hpp"
#include "render/render_job.hpp"
#include "render/trace_group.hpp"
#include "traversal/kernels.hpp"

namespace bvhlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// The A/A controls of a group's first run: `Program` draws it with a second, separately compiled copy
// of its program (what two runs with different shaders see: their own JIT code placement, and the
// machine); `Shared` draws it with the very same program (the group's ProgramCache) but its own
// buffers (what two runs with one shader text see: builders, leaf sizes).
enum class Control { None, Program, Shared };

// One entry of the round-robin: a run of the group (copy 0), one more program copy of a run
// (program_copies), or an A/A control of the first run.
struct Entry {
  std::string key;
  RenderCommand cmd;
  RenderSetup setup;
  std::shared_ptr<const PreparedScene> prepared;
  std::unique_ptr<GpuJob> job;
  FrameTimes times;
  std::string error;
  Control control = Control::None;
  int copy = 0;                  // which program copy draws it (0: the run itself)
  std::vector<double> copy0Ms;   // a run with copies: its own frames (times.ms becomes the copies' median per round)
  bool alive() const { return job != nullptr && error.empty(); }
};

// Another entry drawing what `original` draws (its scene, tree, settings), with a program of its own
// kind: an A/A control or a program copy.
std::unique_ptr<Entry> repeatOf(const Entry& original) {
  auto c = std::make_unique<Entry>();
  c->key = original.key;
  c->cmd = original.cmd;
  c->setup.shader = original.setup.shader;
  c->setup.path = original.setup.path;
  c->setup.smaaOn = original.setup.smaaOn;
  c->setup.smaa = original.setup.smaa;
  c->prepared = original.prepared;
  return c;
}

// Per round, the median over the copies' frames (all the same length): robust to one copy's frame
// meeting a hiccup of the machine, as a mean is not.
std::vector<double> medianPerRound(const std::vector<const std::vector<double>*>& lists) {
  std::vector<double> out(lists.front()->size());
  std::vector<double> round(lists.size());
  for (size_t i = 0; i < out.size(); ++i) {
    for (size_t k = 0; k < lists.size(); ++k) round[k] = (*lists[k])[i];
    out[i] = medianOf(round);
  }
  return out;
}

// Half-width of the run's 95% interval of the median, in % of the median; +inf when there is none.
double intervalPct(const std::vector<double>& ms) {
  const auto ci = medianInterval(ms);
  if (!ci || !(ci->estimate > 0.0)) return std::numeric_limits<double>::infinity();
  return 50.0 * (ci->high - ci->low) / ci->estimate;
}

std::string elapsed(std::chrono::steady_clock::time_point since) {
  return std::to_string(
             int(std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count() + 0.5)) +
         " s";
}

}  // namespace

json measureGroup(const GroupSpec& spec) {
  const GroupSettings& g = spec.settings;
  if (spec.command == "trace") return traceGroup(spec);
  const int minFrames = g.minFrames, maxFrames = g.maxFrames, programCopies = g.programCopies;
  const double targetPct = g.targetPct, maxSeconds = g.maxSeconds;
  const bool wantControl = g.wantControl, sharePrograms = spec.sharePrograms;
  const std::string& session = g.session;
  const auto start = std::chrono::steady_clock::now();

  // ---- set up and build every run (CPU): one scene load per input, one tree per tree key --------
  std::vector<std::unique_ptr<Entry>> entries;
  std::map<std::string, Scene> scenes;
  std::map<std::string, std::shared_ptr<const PreparedScene>> trees;
  for (const GroupRunSpec& run : spec.runs) {
    auto e = std::make_unique<Entry>();
    e->key = run.key;
    try {
      if (!run.error.empty()) throw InputError(run.error);
      e->cmd = parseRenderArgs(run.args);
      if (e->cmd.cpu) throw std::invalid_argument("--cpu runs are not timed by measure (render them alone)");
      auto scene = scenes.find(e->cmd.input);
      if (scene == scenes.end()) scene = scenes.emplace(e->cmd.input, loadInput(e->cmd.input)).first;
      e->setup = setupRender(e->cmd, &scene->second);
      for (const std::string& w : e->setup.buildReview.warnings)
        std::fprintf(stderr, "bvhlab: warning: run %s: %s\n", e->key.c_str(), w.c_str());
      const std::string tk = treeKey(e->cmd);
      auto tree = trees.find(tk);
      if (tree == trees.end())
        tree = trees.emplace(tk, prepareScene(std::move(e->setup.scene), e->cmd.builder, e->setup.build,
                                                e->setup.shader.layout, e->setup.shader.triangles)).first;
      e->prepared = tree->second;
    } catch (const std::exception& ex) {
      e->error = ex.what();
    }
    entries.push_back(std::move(e));
  }
  scenes.clear();  // every tree holds its own copy

  // With shared programs, every run of a layout gets the largest stack any of its trees needs, so
  // that runs differing only in their tree (builder, leaf size, options) assemble one shader text.
  std::map<std::string, int> stackSizes;
  if (sharePrograms)
    for (const auto& e : entries)
      if (e->error.empty()) {
        int& size = stackSizes[e->setup.shader.layout];
        size = std::max(size, stackSizeFor(e->prepared->packed));
      }
  auto stackSizeOf = [&](const Entry& e) {
    auto it = stackSizes.find(e.setup.shader.layout);
    return it == stackSizes.end() ? 0 : it->second;
  };

  // ---- GL: one context, one program per entry ------------------------------------------------------
  const Backend backend = entries.front()->error.empty() ? entries.front()->setup.backend : Backend::OSMesa;
  std::unique_ptr<GlContext> ctx = createContext(backend);
  const std::string renderer = ctx->renderer();
  // One cache per program copy; declared after the context: destroyed while it is still current.
  std::vector<std::unique_ptr<ProgramCache>> caches;
  for (int k = 0; k < programCopies; ++k) caches.push_back(std::make_unique<ProgramCache>());
  ProgramCache& programs = *caches.front();
  for (auto& e : entries) {
    if (!e->error.empty()) continue;
    if (e->setup.backend != backend) {
      e->error = "a group shares one GL context: every run needs the same --backend";
      continue;
    }
    try {
      e->job = std::make_unique<GpuJob>(e->cmd, e->setup, e->prepared, sharePrograms ? &programs : nullptr,
                                        stackSizeOf(*e));
    } catch (const std::exception& ex) {
      e->error = std::string(dynamic_cast<const ShaderError*>(&ex) ? "shader error: " : "") + ex.what();
    }
  }
  // The program copies 1..K-1 of every run that works.
  const size_t runCount = entries.size();
  for (int k = 1; k < programCopies; ++k)
    for (size_t i = 0; i < runCount; ++i) {
      const Entry& original = *entries[i];
      if (!original.alive()) continue;
      auto c = repeatOf(original);
      c->copy = k;
      try {
        c->job = std::make_unique<GpuJob>(c->cmd, c->setup, c->prepared, sharePrograms ? caches[size_t(k)].get() : nullptr,
                                          stackSizeOf(original));
      } catch (const std::exception& ex) {
        c->error = ex.what();
      }
      entries.push_back(std::move(c));
    }
  // The A/A controls: the first run that works, measured a second time by a second program and,
  // with shared programs, a third time by its own program over its own buffers.
  Entry* controlled = nullptr;
  if (wantControl) {
    auto first = std::find_if(entries.begin(), entries.end(), [](const auto& e) { return e->alive(); });
    if (first != entries.end()) {
      controlled = first->get();
      for (const Control kind : {Control::Program, Control::Shared}) {
        if (kind == Control::Shared && !sharePrograms) continue;
        const Entry& original = *controlled;
        auto c = repeatOf(original);
        c->control = kind;
        try {
          c->job = std::make_unique<GpuJob>(c->cmd, c->setup, c->prepared,
                                            kind == Control::Shared ? &programs : nullptr, stackSizeOf(original));
          entries.push_back(std::move(c));
        } catch (const std::exception& ex) {
          std::cerr << "bvhlab measure: warning: no A/A control: " << ex.what() << "\n";
        }
      }
    }
  }
  std::cerr << "bvhlab measure: " << entries.size() << " entries ready (" << elapsed(start) << ")\n";

  // ---- warm-up, then rounds in a shuffled order until every interval is narrow enough -------------
  auto draw = [&](Entry& e, int index, bool timed) {
    try {
      double aaMs = 0.0;
      const double ms = e.job->frame(index, aaMs);
      if (timed) {
        e.times.ms.push_back(ms);
        if (e.setup.smaaOn) e.times.aaMs.push_back(aaMs);
      }
    } catch (const std::exception& ex) {
      e.error = std::string("frame failed: ") + ex.what();
      e.job.reset();
    }
  };
  int warmup = 0;
  for (auto& e : entries)
    if (e->alive()) warmup = std::max(warmup, e->cmd.warmup);
  for (int w = 0; w < warmup; ++w)
    for (auto& e : entries)
      if (e->alive() && w < e->cmd.warmup) draw(*e, w, false);

  std::vector<size_t> order(entries.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::mt19937_64 rng(0x5eed);  // fixed: the same group draws in the same orders every time
  int rounds = 0;
  std::string stop = minFrames == maxFrames ? "fixed" : "max_frames";
  const auto roundsStart = std::chrono::steady_clock::now();
  while (rounds < maxFrames) {
    shuffleRound(order, rng);
    for (size_t i : order)
      if (entries[i]->alive()) draw(*entries[i], rounds, true);
    ++rounds;
    if (rounds < minFrames || minFrames == maxFrames) continue;
    double widest = 0.0;
    for (auto& e : entries)
      if (e->alive()) widest = std::max(widest, intervalPct(e->times.ms));
    if (rounds % 10 == 0)
      std::cerr << "bvhlab measure: round " << rounds << ": widest interval ±" << widest << "% (" << elapsed(start)
                << ")\n";
    if (widest <= targetPct) {
      stop = "target";
      break;
    }
    if (maxSeconds > 0.0 && std::chrono::duration<double>(std::chrono::steady_clock::now() - roundsStart).count() >= maxSeconds) {
      stop = "max_seconds";
      break;
    }
  }

  // ---- images, counts, JSON --------------------------------------------------------------------------
  json out = {{"session", session}, {"rounds", rounds}, {"stop", stop}, {"renderer", renderer},
              {"gpu", !isSoftwareRenderer(renderer)}, {"share_programs", sharePrograms}};
  json runs = json::object();
  std::map<Control, const Entry*> controls;
  std::map<std::string, std::vector<const Entry*>> copiesOf;  // run key -> its copies 1..K-1
  for (const auto& e : entries)
    if (e->copy > 0) copiesOf[e->key].push_back(e.get());
  for (auto& e : entries) {
    if (e->control != Control::None) {
      controls[e->control] = e.get();
      continue;
    }
    if (e->copy > 0) continue;
    for (const Entry* c : copiesOf[e->key])
      if (e->error.empty() && !c->error.empty()) e->error = "program copy " + std::to_string(c->copy) + ": " + c->error;
    if (!e->error.empty()) {
      runs[e->key] = {{"error", e->error}};
      continue;
    }
    json copyFrames;
    if (programCopies > 1) {  // the run's time: per round, the median over its copies
      std::vector<const std::vector<double>*> ms{&e->times.ms}, aa{&e->times.aaMs};
      copyFrames = json::array({e->times.ms});
      for (const Entry* c : copiesOf[e->key]) {
        ms.push_back(&c->times.ms);
        aa.push_back(&c->times.aaMs);
        copyFrames.push_back(c->times.ms);
      }
      e->copy0Ms = e->times.ms;
      e->times.ms = medianPerRound(ms);
      if (!e->times.aaMs.empty()) e->times.aaMs = medianPerRound(aa);
    }
    try {
      e->times.stop = stop;
      e->times.targetCiPct = minFrames == maxFrames ? 0.0 : targetPct;
      const bool wantStats = e->cmd.json || e->cmd.view == "visits" || !e->cmd.visitsOutput.empty();
      e->job->finish(wantStats);
      json r = finishRender(e->cmd, e->setup, *e->prepared, e->job->frameOptions(), std::move(e->job->image),
                            e->job->stats, e->job->boxTests, e->times, renderer, false);
      r["session"] = session;
      r["rounds"] = rounds;
      // Runs of one session with the same `program` drew with one compiled program.
      r["program"] = e->job->programIndex() >= 0 ? json(e->job->programIndex()) : json();
      r["bvh_stack_size"] = e->job->shader().bvhStackSize;
      if (programCopies > 1) {
        r["program_copies"] = programCopies;
        r["frame_ms_copies"] = std::move(copyFrames);  // copy 0 (the run's own program) first
      }
      const uint64_t overflows = stackOverflowPixels(e->job->stats);
      e->job.reset();
      if (overflows > 0)
        runs[e->key] = {{"error", "traversal stack overflowed in " + std::to_string(overflows) + " pixels"},
                        {"result", r}};
      else
        runs[e->key] = std::move(r);
    } catch (const std::exception& ex) {
      runs[e->key] = {{"error", ex.what()}};
    }
  }
  if (controlled && runs[controlled->key].contains("frame_ms")) {
    json& r = runs[controlled->key];
    const std::vector<double>& own = controlled->copy0Ms.empty() ? controlled->times.ms : controlled->copy0Ms;
    for (const auto& [kind, control] : controls) {
      if (!control->error.empty()) continue;
      // original / control from paired rounds: an interval that excludes 1 would mean the round-robin
      // itself favours one program (the report prints it as the sweep's noise floor).
      const std::string prefix = kind == Control::Program ? "aa_control" : "aa_shared_control";
      r[prefix + "_frame_ms_all"] = control->times.ms;
      if (const auto ratio = pairedRatio(own, control->times.ms)) {
        r[prefix + "_ratio"] = ratio->estimate;
        r[prefix + "_ci_low"] = ratio->low;
        r[prefix + "_ci_high"] = ratio->high;
      }
    }
  }
  for (auto& e : entries) e->job.reset();  // before the program cache and the context go
  out["programs"] = programs.size();
  out["program_copies"] = programCopies;
  out["runs"] = std::move(runs);
  out["wall_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

int runMeasure(const MeasureCommand& cmd) {
  std::cout << measureGroup(readGroupSpec(cmd.spec)).dump() << std::endl;
  return 0;
}

}  // namespace bvhlab
