#include "experiments/generated_scenes.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <iostream>
#include <map>
#include <sstream>

#include "datasets/bench_generators.hpp"
#include "datasets/procedural.hpp"
#include "experiments/config.hpp"
#include "experiments/sweep_dir.hpp"

namespace bvhlab {

namespace fs = std::filesystem;

const std::vector<std::string>& generatedMeshKinds() {
  static const std::vector<std::string> kinds = [] {
    std::vector<std::string> k = {"large", "soup"};
    for (const BenchGenerator& g : benchGenerators()) k.push_back(g.name);
    return k;
  }();
  return kinds;
}

Mesh generateMesh(const nlohmann::json& spec) {
  const std::string kind = spec.at("generate");
  const size_t triangles = spec.at("triangles").get<size_t>();
  const uint64_t seed = spec.value("seed", uint64_t(1));
  if (kind == "large") return makeLargeMesh(triangles, seed);
  if (kind == "soup") return makeTriangleSoup(triangles, seed);
  for (const BenchGenerator& g : benchGenerators())
    if (g.name == kind) return generateBenchMesh(kind, int64_t(std::min<size_t>(triangles, size_t(INT64_MAX))), seed);
  throw std::invalid_argument("unknown mesh generator '" + kind + "'");
}

void writePly(const fs::path& path, const Mesh& mesh) {
  std::ostringstream out(std::ios::binary);
  out << "ply\nformat " << (std::endian::native == std::endian::little ? "binary_little_endian" : "binary_big_endian")
      << " 1.0\ncomment bvhlab generated mesh\nelement vertex " << mesh.positions.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << mesh.triangles.size()
      << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const glm::vec3& p : mesh.positions) out.write(reinterpret_cast<const char*>(&p[0]), 3 * sizeof(float));
  for (const glm::uvec3& t : mesh.triangles) {
    const unsigned char three = 3;
    const int32_t idx[3] = {int32_t(t.x), int32_t(t.y), int32_t(t.z)};
    out.write(reinterpret_cast<const char*>(&three), 1);
    out.write(reinterpret_cast<const char*>(idx), sizeof idx);
  }
  writeFileAtomic(path, out.str());
}

std::vector<fs::path> materializeGeneratedScenes(ExperimentConfig& config, const fs::path& dir) {
  std::vector<fs::path> written;
  std::map<std::string, fs::path> files;  // spec dump -> file
  for (RunSpec& run : config.runs)
    for (auto& [axis, value] : run.axes) {
      if (axis != "scene" || !value.value.contains("generate")) continue;
      nlohmann::json spec = {{"generate", value.value["generate"]},
                             {"triangles", value.value["triangles"]},
                             {"seed", value.value["seed"]}};
      const std::string id = spec.dump();
      auto it = files.find(id);
      if (it == files.end()) {
        const fs::path file = dir / "generated" /
                              (spec["generate"].get<std::string>() + "-" + std::to_string(spec["triangles"].get<size_t>()) +
                               "-seed" + std::to_string(spec["seed"].get<uint64_t>()) + ".ply");
        if (!fs::exists(file)) {
          std::cerr << "bvhlab run: generating " << file.string() << "\n";
          writePly(file, generateMesh(spec));
          written.push_back(file);
        }
        it = files.emplace(id, file).first;
      }
      value.file = fs::absolute(it->second).lexically_normal();
    }
  return written;
}

}  // namespace bvhlab
