// One traced run's parts (render/trace_run.hpp) that need no GL context: the yardstick's key, which a
// trace group compares before it builds an Embree scene for a run's batch, against the batches
// themselves (TraceYardstick::sameAs, bit for bit).
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli_run.hpp"
#include "render/trace_run.hpp"

namespace {

using namespace bvhlab;
using namespace bvhlab::clitest;

[[maybe_unused]] ::testing::Environment* const kRemoveTestDir = ::testing::AddGlobalTestEnvironment(new RemoveTestDir);

// A small closed mesh (a tetrahedron) that primary rays hit, so secondary workloads have rays.
const char* const kTetrahedron = "OFF\n4 4 0\n-1 -1 -1\n1 -1 -1\n0 1 -1\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 2 0 3\n";

struct Traced {
  TraceCommand cmd;
  TraceSetup setup;
};

// A run over `mesh` with these options (each replacing the default of the same name).
Traced traced(const std::string& mesh, const std::map<std::string, std::string>& options = {}) {
  std::map<std::string, std::string> all{{"--rays", "diffuse"}, {"--count", "256"}, {"--embree-threads", "1"},
                                         {"--eye", "0,0,6"},    {"--target", "0,0,0"}};
  for (const auto& [name, value] : options) all[name] = value;
  std::vector<std::string> args{mesh};
  for (const auto& [name, value] : all) args.insert(args.end(), {name, value});
  Traced t;
  t.cmd = parseTraceArgs(args);
  t.setup = setupTrace(t.cmd);
  return t;
}

std::string keyOf(const std::string& mesh, const std::map<std::string, std::string>& options = {}) {
  const Traced t = traced(mesh, options);
  return TraceYardstick::key(t.cmd, t.setup);
}

TEST(TraceYardstickKey, EqualForRunsThatDifferOnlyInTheTreeOrTheKernel) {
  const std::string mesh = writeTemp("trace_run/tet.off", kTetrahedron).string();
  const std::string base = keyOf(mesh);
  EXPECT_EQ(base, keyOf(mesh, {{"--builder", "median"}}));
  EXPECT_EQ(base, keyOf(mesh, {{"--layout", "bvh2-cb"}}));
  EXPECT_EQ(base, keyOf(mesh, {{"--leaf-size", "1"}, {"--frames", "3"}}));
  // Equal keys stand for equal batches: the yardsticks built for two such runs trace the same bits.
  const Traced a = traced(mesh), b = traced(mesh, {{"--builder", "median"}, {"--layout", "bvh2-cb"}});
  const TraceYardstick ya(a.cmd, a.setup), yb(b.cmd, b.setup);
  EXPECT_FALSE(ya.rays().rays.empty());
  EXPECT_TRUE(ya.sameAs(yb));
}

TEST(TraceYardstickKey, DiffersWhenTheRaysOrTheYardsticksModeCouldDiffer) {
  const std::string mesh = writeTemp("trace_run/tet.off", kTetrahedron).string();
  // The same triangle count, one vertex moved: only the positions' hash tells the two apart.
  const std::string moved =
      writeTemp("trace_run/moved.off", "OFF\n4 4 0\n-1 -1 -1\n1 -1 -1\n0 1 -1\n0 0 1.5\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 2 0 3\n")
          .string();
  const std::string base = keyOf(mesh);
  EXPECT_NE(base, keyOf(moved));
  const std::map<std::string, std::string> changes[] = {
      {{"--rays", "ao"}},          {{"--seed", "2"}},   {{"--count", "128"}},         {{"--ao-radius", "0.2"}},
      {{"--eye", "0.5,0,6"}},      {{"--fov", "30"}},   {{"--embree-threads", "2"}},  {{"--robust", "fast"}}};
  for (const auto& change : changes) EXPECT_NE(base, keyOf(mesh, change)) << change.begin()->first;
}

}  // namespace
