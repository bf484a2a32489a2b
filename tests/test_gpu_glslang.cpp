// The GPU builders' compute shaders through glslang, the reference GLSL front end: every program the
// builders and the pack compile (lbvh-gpu, ploc-gpu, plocpp-gpu, hploc-gpu; their preludes and
// defines included), as the driver receives it, must compile there too. llvmpipe accepts what Mesa's
// front end accepts; this is the check that another vendor's compiler starts from the language.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "builders/gpu/gpu_builders.hpp"
#include "builders/gpu/gpu_compute.hpp"
#include "builders/gpu/gpu_hploc.hpp"
#include "builders/gpu/gpu_lbvh.hpp"
#include "builders/gpu/gpu_pack_wide.hpp"
#include "builders/gpu/gpu_ploc.hpp"
#include "render/gl_context.hpp"
#include "require.hpp"
#include "shaders/assemble.hpp"

namespace bvhlab {
namespace {

TEST(GpuBuilderGlsl, EveryComputeProgramCompilesWithGlslang) {
  if (std::system("command -v glslangValidator > /dev/null 2>&1") != 0)
    BVHLAB_SKIP_OR_FAIL("glslangValidator not found (Debian package glslang-tools)");
  registerGpuBuilders();
  const std::unique_ptr<GlContext> context = createContext(Backend::OSMesa);
  {  // every GPU builder's programs, the radix sort's and the pack's with them
    const gpubuild::GpuLbvh lbvh;
    const gpubuild::GpuPloc ploc, plocpp(std::nullopt, gpubuild::PlocPasses::Fused);
    const gpubuild::GpuHploc hploc;
    const gpubuild::WidePackPrograms wide;  // the cwbvh pack's, which a packer compiles at its first cwbvh pack
  }
  const auto sources = gpubuild::computeSourcesMade();
  // Every embedded builder module was among them, as a program or a prelude.
  for (const auto& [name, text] : glslSources()) {
    if (name.rfind("gpubuild_", 0) != 0) continue;
    bool used = false;
    for (const auto& [label, source] : sources) used = used || label.find(name) != std::string::npos;
    EXPECT_TRUE(used) << name << " was compiled by no GPU builder";
  }
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("bvhlab_test_gpu_glslang_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  size_t k = 0;
  for (const auto& [label, source] : sources) {
    const std::filesystem::path file = dir / (std::to_string(k) + ".comp"), log = dir / (std::to_string(k++) + ".log");
    std::ofstream(file) << source;
    const std::string cmd = "glslangValidator -S comp '" + file.string() + "' > '" + log.string() + "' 2>&1";
    const int rc = std::system(cmd.c_str());
    std::stringstream text;
    text << std::ifstream(log).rdbuf();
    EXPECT_EQ(rc, 0) << label << ":\n" << text.str();
  }
  EXPECT_GE(k, 20u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace bvhlab
