// Scenes a config generates instead of naming a file:
//   scenes = [{ generate = "large", triangles = 1000000, seed = 1 }]
// The runner writes each one once, as a binary PLY under DIR/generated/, and renders that file
// (`bvhlab render` frames a bare mesh like any other). The run key hashes the generator spec, so a
// generated scene is the same run on every machine.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "datasets/scene.hpp"

namespace bvhlab {

struct ExperimentConfig;

// Generator names accepted in `generate` ("large": procedural.hpp's makeLargeMesh, a BVH-hostile
// bumpy sphere in a clustered cloud; "soup": makeTriangleSoup, random triangles in the unit cube;
// then datasets/bench_generators.hpp's "stadium", "interior", "hairball", "terrain", "scaling").
const std::vector<std::string>& generatedMeshKinds();

// The mesh for a scene value {"generate", "triangles", "seed"} (deterministic in them).
Mesh generateMesh(const nlohmann::json& spec);

// Binary PLY (host byte order, declared in the header): vertices and triangles only.
void writePly(const std::filesystem::path& path, const Mesh& mesh);

// Writes every generated scene of `config` that is not under `dir`/generated yet and points the
// runs' scene files at them. Returns the files written now.
std::vector<std::filesystem::path> materializeGeneratedScenes(ExperimentConfig& config,
                                                              const std::filesystem::path& dir);

}  // namespace bvhlab
