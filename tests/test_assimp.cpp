// datasets/mesh_io_assimp.cpp: glTF 2.0 (.gltf, .glb), COLLADA (.dae), FBX (.fbx), 3DS (.3ds) and
// AC3D (.ac) through assimp behind loadMeshData: tiny files written here (text formats by hand, binary
// ones by assimp's exporters from the hand-written glTF), loaded back and checked (triangles, bounds,
// normals, materials); bad files are one InputError naming the file; bare models become scenes with
// their materials and textures; a TOML mesh object takes the geometry; the CLI renders a .gltf.
#include <sys/resource.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/scene.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "datasets/image_io.hpp"
#include "datasets/mesh_io.hpp"
#include "datasets/scene_io.hpp"

using namespace bvhlab;
namespace fs = std::filesystem;

[[maybe_unused]] ::testing::Environment* const kRemoveTestDir =
    ::testing::AddGlobalTestEnvironment(new clitest::RemoveTestDir);

namespace {

fs::path dir() {
  const fs::path d = clitest::testDir() / "assimp";
  fs::create_directories(d);
  return d;
}

fs::path writeFile(const std::string& name, const std::string& bytes) {
  const fs::path p = dir() / name;
  std::ofstream(p, std::ios::binary) << bytes;
  return p;
}

std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

std::string base64(const std::string& bytes) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t v = uint32_t(uint8_t(bytes[i])) << 16;
    if (i + 1 < bytes.size()) v |= uint32_t(uint8_t(bytes[i + 1])) << 8;
    if (i + 2 < bytes.size()) v |= uint32_t(uint8_t(bytes[i + 2]));
    out += k[(v >> 18) & 63];
    out += k[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? k[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? k[v & 63] : '=';
  }
  return out;
}

template <class T>
void append(std::string& buf, std::initializer_list<T> values) {
  for (T v : values) buf.append(reinterpret_cast<const char*>(&v), sizeof v);
}

// A unit quad in the XY plane (normal +Z, UVs at the corners), two triangles with two materials
// ("red": base colour (0.8, 0.2, 0.1), rough dielectric; "chrome": smooth metal), placed twice:
// node A scaled by 2 and moved to x = 10; node B turned 90 degrees about +Y and moved to z = -5.
// Flattened: 4 triangles, bounds x [0, 12], y [0, 2], z [-6, 0]; A's normals +Z, B's +X.
// `material1` replaces the second material (glass, textures); `extra` is added at the top level.
std::string quadGltf(const std::string& material1 = R"({"name": "chrome", "pbrMetallicRoughness":
    {"baseColorFactor": [0.9, 0.9, 0.9, 1], "metallicFactor": 1, "roughnessFactor": 0}})",
                     const std::string& extra = "") {
  std::string buf;
  append<float>(buf, {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});  // positions, offset 0
  append<float>(buf, {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1});  // normals, offset 48
  append<float>(buf, {0, 0, 1, 0, 1, 1, 0, 1});              // uvs, offset 96
  append<uint16_t>(buf, {0, 1, 2, 0, 2, 3});                 // indices, offset 128
  const std::string attributes = R"({"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2})";
  const double h = std::sqrt(0.5);
  return R"({"asset": {"version": "2.0"},
  "buffers": [{"byteLength": )" + std::to_string(buf.size()) + R"(, "uri": "data:application/octet-stream;base64,)" +
         base64(buf) + R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 48},
                  {"buffer": 0, "byteOffset": 96, "byteLength": 32}, {"buffer": 0, "byteOffset": 128, "byteLength": 12}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
    {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
    {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
    {"bufferView": 3, "byteOffset": 0, "componentType": 5123, "count": 3, "type": "SCALAR"},
    {"bufferView": 3, "byteOffset": 6, "componentType": 5123, "count": 3, "type": "SCALAR"}],
  "materials": [{"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.2, 0.1, 1],
                 "metallicFactor": 0, "roughnessFactor": 0.5}}, )" +
         material1 + R"(],
  "meshes": [{"primitives": [{"attributes": )" + attributes + R"(, "indices": 3, "material": 0},
                             {"attributes": )" + attributes + R"(, "indices": 4, "material": 1}]}],
  "nodes": [{"name": "A", "mesh": 0, "translation": [10, 0, 0], "scale": [2, 2, 2]},
            {"name": "B", "mesh": 0, "translation": [0, 0, -5], "rotation": [0, )" +
         std::to_string(h) + ", 0, " + std::to_string(h) + R"(]}],
  "scenes": [{"nodes": [0, 1]}], "scene": 0)" + extra + "}\n";
}

// COLLADA 1.4.1: one quad as a <polylist> (triangulated on load), Phong material with a diffuse
// colour, reflectivity 0.3 and transparency 0.4 (A_ONE: opacity 0.6), placed by a <matrix> at x = 5.
const char* kQuadDae = R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Y_UP</up_axis></asset>
  <library_effects><effect id="fx"><profile_COMMON><technique sid="common"><phong>
    <diffuse><color>0.1 0.6 0.2 1</color></diffuse>
    <reflectivity><float>0.3</float></reflectivity>
    <transparent opaque="A_ONE"><color>1 1 1 1</color></transparent>
    <transparency><float>0.6</float></transparency>
    <index_of_refraction><float>1.33</float></index_of_refraction>
  </phong></technique></profile_COMMON></effect></library_effects>
  <library_materials><material id="green" name="green"><instance_effect url="#fx"/></material></library_materials>
  <library_geometries><geometry id="quad" name="quad"><mesh>
    <source id="pos"><float_array id="pos-a" count="12">0 0 0 1 0 0 1 1 0 0 1 0</float_array>
      <technique_common><accessor source="#pos-a" count="4" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
    <source id="nrm"><float_array id="nrm-a" count="3">0 0 1</float_array>
      <technique_common><accessor source="#nrm-a" count="1" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
    <vertices id="vtx"><input semantic="POSITION" source="#pos"/></vertices>
    <polylist material="mat" count="1">
      <input semantic="VERTEX" source="#vtx" offset="0"/><input semantic="NORMAL" source="#nrm" offset="1"/>
      <vcount>4</vcount><p>0 0 1 0 2 0 3 0</p></polylist>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="scene"><node id="n" name="n">
    <matrix>1 0 0 5 0 1 0 0 0 0 1 0 0 0 0 1</matrix>
    <instance_geometry url="#quad"><bind_material><technique_common>
      <instance_material symbol="mat" target="#green"/></technique_common></bind_material></instance_geometry>
  </node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
)";

// AC3D: a quad (one polygon surface, 2 triangles) and a line surface (skipped), moved by `loc` to
// (1, 2, 3); material "blue" with transparency 0.5.
const char* kQuadAc = R"(AC3Db
MATERIAL "blue" rgb 0.1 0.2 0.9  amb 0.2 0.2 0.2  emis 0 0 0  spec 0.5 0.5 0.5  shi 10  trans 0.5
OBJECT world
kids 1
OBJECT poly
name "quad"
loc 1 2 3
numvert 4
0 0 0
1 0 0
1 1 0
0 1 0
numsurf 2
SURF 0x10
mat 0
refs 4
0 0 0
1 1 0
2 1 1
3 0 1
SURF 0x02
mat 0
refs 2
0 0 0
2 0 0
kids 0
)";

// 3DS by hand (chunk = u16 id, u32 length including the 6-byte header): material "red" (diffuse
// 24-bit colour 204, 51, 25) and one object, a quad standing in the file's Z-up frame at y = 5:
// (2,5,0) (3,5,0) (3,5,1) (2,5,1), faces (0,1,2) (0,2,3) with smoothing group 1. assimp turns Z-up
// into Y-up, (x, y, z) -> (x, z, -y): bounds (2, 0, -5) .. (3, 1, -5), normal +Z.
std::string chunk(uint16_t id, const std::string& body) {
  std::string c;
  append<uint16_t>(c, {id});
  append<uint32_t>(c, {uint32_t(6 + body.size())});
  return c + body;
}
std::string quad3ds() {
  const std::string colour = chunk(0x0011, std::string("\xCC\x33\x19", 3));
  const std::string material = chunk(0xAFFF, chunk(0xA000, std::string("red", 4)) + chunk(0xA020, colour));
  std::string vertices;
  append<uint16_t>(vertices, {4});
  append<float>(vertices, {2, 5, 0, 3, 5, 0, 3, 5, 1, 2, 5, 1});
  std::string faces;
  append<uint16_t>(faces, {2, 0, 1, 2, 0, 0, 2, 3, 0});
  std::string faceMaterial("red", 4);
  append<uint16_t>(faceMaterial, {2, 0, 1});
  std::string smoothing;
  append<uint32_t>(smoothing, {1, 1});
  faces += chunk(0x4130, faceMaterial) + chunk(0x4150, smoothing);
  const std::string trimesh = chunk(0x4100, chunk(0x4110, vertices) + chunk(0x4120, faces));
  const std::string object = chunk(0x4000, std::string("quad", 5) + trimesh);
  return chunk(0x4D4D, chunk(0x3D3D, material + object));
}

struct Bounds {
  glm::dvec3 lo{1e300}, hi{-1e300};
};
Bounds boundsOf(const MeshData& m) {
  Bounds b;
  for (const glm::uvec3& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      b.lo = glm::min(b.lo, m.positions[t[k]]);
      b.hi = glm::max(b.hi, m.positions[t[k]]);
    }
  return b;
}

void expectNear3(glm::dvec3 a, glm::dvec3 b, double tol = 1e-5) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

const MeshMaterial* materialNamed(const MeshData& m, const std::string& name) {
  for (const MeshMaterial& mm : m.materials)
    if (mm.material.name == name) return &mm;
  return nullptr;
}

std::string inputErrorOf(const fs::path& p) {
  try {
    loadMeshData(p);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

// Exports the quad glTF through assimp's exporter `format` (e.g. "glb2", "3ds", "fbx") to `name`.
fs::path exported(const std::string& format, const std::string& name) {
  const fs::path src = writeFile("export-source.gltf", quadGltf());
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(src.string(), 0);
  EXPECT_NE(scene, nullptr) << importer.GetErrorString();
  const fs::path out = dir() / name;
  Assimp::Exporter exporter;
  EXPECT_EQ(exporter.Export(scene, format, out.string()), AI_SUCCESS) << exporter.GetErrorString();
  return out;
}

// ---- each format on a tiny file --------------------------------------------------------------------

TEST(AssimpFormats, GltfSceneGraphIsFlattenedWithNormalsUvsAndMaterials) {
  const MeshData m = loadMeshData(writeFile("quad.gltf", quadGltf()));
  ASSERT_EQ(m.triangles.size(), 4u);
  const Bounds b = boundsOf(m);
  expectNear3(b.lo, {0, 0, -6});
  expectNear3(b.hi, {12, 2, 0});
  ASSERT_EQ(m.normals.size(), m.positions.size());
  ASSERT_EQ(m.uvs.size(), m.positions.size());
  // Node A (x >= 10) keeps +Z normals; node B (x <= 1, turned about +Y) has +X normals.
  size_t a = 0, bCount = 0;
  for (size_t v = 0; v < m.positions.size(); ++v) {
    if (m.positions[v].x >= 10.0 - 1e-9) {
      expectNear3(m.normals[v], {0, 0, 1});
      ++a;
    } else {
      expectNear3(m.normals[v], {1, 0, 0});
      ++bCount;
    }
  }
  EXPECT_GT(a, 0u);
  EXPECT_GT(bCount, 0u);
  // glTF's v runs down the image; assimp turns it to GL's (v up): the corner (1,1,0) has uv (1, 0).
  for (size_t v = 0; v < m.positions.size(); ++v)
    if (glm::distance(m.positions[v], glm::dvec3(12, 2, 0)) < 1e-9) {
      EXPECT_NEAR(m.uvs[v].x, 1.0f, 1e-6f);
      EXPECT_NEAR(m.uvs[v].y, 0.0f, 1e-6f);
    }
  const MeshMaterial* red = materialNamed(m, "red");
  const MeshMaterial* chrome = materialNamed(m, "chrome");
  ASSERT_TRUE(red && chrome);
  expectNear3(red->material.color, {0.8, 0.2, 0.1});
  EXPECT_EQ(red->material.reflectivity, 0.0f);     // metallic 0
  EXPECT_NEAR(chrome->material.reflectivity, 1.0f, 1e-6f);  // metallic 1, roughness 0: a mirror
  ASSERT_EQ(m.triangleMaterials.size(), 4u);
  size_t redTris = 0;
  for (uint32_t t : m.triangleMaterials) redTris += &m.materials.at(t) == red;
  EXPECT_EQ(redTris, 2u);
}

TEST(AssimpFormats, ColladaPolygonIsTriangulatedAndItsPhongMaterialMapped) {
  const MeshData m = loadMeshData(writeFile("quad.dae", kQuadDae));
  ASSERT_EQ(m.triangles.size(), 2u);
  const Bounds b = boundsOf(m);
  expectNear3(b.lo, {5, 0, 0});
  expectNear3(b.hi, {6, 1, 0});
  ASSERT_FALSE(m.normals.empty());
  expectNear3(m.normals[m.triangles[0].x], {0, 0, 1});
  const MeshMaterial* green = materialNamed(m, "green");
  ASSERT_TRUE(green);
  expectNear3(green->material.color, {0.1, 0.6, 0.2});
  EXPECT_NEAR(green->material.transparency, 0.4f, 1e-6f);
  EXPECT_NEAR(green->material.reflectivity, 0.3f * 0.6f, 1e-6f);  // a fraction of the opaque part
  EXPECT_NEAR(green->material.ior, 1.33f, 1e-6f);
}

TEST(AssimpFormats, Ac3dPolygonIsReadAndLineSurfacesSkipped) {
  const MeshData m = loadMeshData(writeFile("quad.ac", kQuadAc));
  ASSERT_EQ(m.triangles.size(), 2u);  // the line surface adds none
  const Bounds b = boundsOf(m);
  expectNear3(b.lo, {1, 2, 3});
  expectNear3(b.hi, {2, 3, 3});
  EXPECT_TRUE(m.normals.empty());  // AC3D stores none: geometric normals
  EXPECT_TRUE(m.uvs.empty());      // assimp keeps AC3D's UVs only on textured surfaces
  const MeshMaterial* blue = materialNamed(m, "blue");
  ASSERT_TRUE(blue);
  expectNear3(blue->material.color, {0.1, 0.2, 0.9});
  EXPECT_NEAR(blue->material.transparency, 0.5f, 1e-6f);
}

TEST(AssimpFormats, ThreeDsIsTurnedToYUpWithItsMaterial) {
  const MeshData m = loadMeshData(writeFile("quad.3ds", quad3ds()));
  ASSERT_EQ(m.triangles.size(), 2u);
  const Bounds b = boundsOf(m);
  expectNear3(b.lo, {2, 0, -5});
  expectNear3(b.hi, {3, 1, -5});
  ASSERT_EQ(m.normals.size(), m.positions.size());  // from the smoothing groups
  expectNear3(m.normals[m.triangles[0].x], {0, 0, 1});
  const MeshMaterial* red = materialNamed(m, "red");
  ASSERT_TRUE(red);
  expectNear3(red->material.color, {204 / 255.0, 51 / 255.0, 25 / 255.0});
}

// GLB and FBX, written by assimp's exporters from the glTF above and read back. (Its 3DS exporter
// misplaces node transforms and its binary FBX writer produces files its own reader refuses,
// "FBX-Tokenize ... block offset is out of range": 3DS is written by hand above, FBX as ASCII.)
TEST(AssimpFormats, BinaryFormatsWrittenByAssimpReadBack) {
  for (const auto& [format, name] : {std::pair{"glb2", "quad.glb"}, {"fbxa", "quad.fbx"}}) {
    SCOPED_TRACE(name);
    const fs::path p = exported(format, name);
    const MeshData m = loadMeshData(p);
    ASSERT_EQ(m.triangles.size(), 4u);
    const Bounds b = boundsOf(m);
    expectNear3(b.lo, {0, 0, -6}, 1e-4);
    expectNear3(b.hi, {12, 2, 0}, 1e-4);
    ASSERT_EQ(m.normals.size(), m.positions.size());
    for (size_t v = 0; v < m.positions.size(); ++v)
      expectNear3(m.normals[v], m.positions[v].x >= 10.0 - 1e-4 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0), 1e-4);
    const MeshMaterial* red = materialNamed(m, "red");
    ASSERT_TRUE(red);
    expectNear3(red->material.color, {0.8, 0.2, 0.1}, 1e-4);
  }
}

// ---- bad files ---------------------------------------------------------------------------------------

TEST(AssimpErrors, TruncatedGarbageAndEmptyFilesNameTheFile) {
  std::vector<std::pair<std::string, std::string>> valid{
      {"t.gltf", quadGltf()}, {"t.dae", kQuadDae}, {"t.ac", kQuadAc},
      {"t.glb", readFile(exported("glb2", "src.glb"))}, {"t.fbx", readFile(exported("fbxa", "src.fbx"))},
      {"t.3ds", quad3ds()}};
  for (const auto& [name, bytes] : valid) {
    SCOPED_TRACE(name);
    const fs::path truncated = writeFile("truncated-" + name, bytes.substr(0, bytes.size() / 3));
    const std::string e1 = inputErrorOf(truncated);
    EXPECT_EQ(e1.rfind(truncated.string() + ": ", 0), 0u) << e1;
    std::string junk(bytes.size(), '\0');
    for (size_t i = 0; i < junk.size(); ++i) junk[i] = char((i * 2654435761u) >> 13);
    const fs::path garbage = writeFile("garbage-" + name, junk);
    const std::string e2 = inputErrorOf(garbage);
    EXPECT_EQ(e2.rfind(garbage.string() + ": ", 0), 0u) << e2;
    const fs::path empty = writeFile("empty-" + name, "");
    EXPECT_EQ(inputErrorOf(empty), empty.string() + ": empty file");
  }
}

TEST(AssimpErrors, AFileWithoutTrianglesIsAnError) {
  std::string linesOnly = kQuadAc;
  // Only the line surface stays.
  const size_t from = linesOnly.find("numsurf 2"), to = linesOnly.find("SURF 0x02");
  linesOnly.replace(from, to - from, "numsurf 1\n");
  const fs::path p = writeFile("lines.ac", linesOnly);
  const std::string e = inputErrorOf(p);
  EXPECT_EQ(e.rfind(p.string() + ": ", 0), 0u) << e;
  EXPECT_NE(e.find("no faces"), std::string::npos) << e;
}

// AC3D structure assimp 5.2.5 mishandles, refused by our pass before assimp reads it, with the line
// (mesh_io_prechecks.cpp: checkAc3d). A line surface without refs made assimp size its face array from
// refs - 1 in unsigned arithmetic and write past it (fuzz_ac: an ASan bad-free; valgrind: invalid writes;
// tests/fuzz/regressions/ac/). Each edit below breaks one rule of the valid quad file.
TEST(AssimpErrors, MalformedAc3dSurfacesAreRefusedWithTheirLine) {
  auto edit = [](const std::string& from, const std::string& to) {
    std::string t = kQuadAc;
    t.replace(t.find(from), from.size(), to);
    return t;
  };
  struct Case {
    const char* name;
    std::string text;
    size_t line;
    const char* says;
  };
  const Case cases[] = {
      {"line-no-refs.ac", edit("SURF 0x02\nmat 0\nrefs 2\n0 0 0\n2 0 0\n", "SURF 0x02\nmat 0\n"), 21, "without a 'refs' line"},
      {"line-one-ref.ac", edit("refs 2\n0 0 0\n2 0 0\n", "refs 1\n0 0 0\n"), 21, "at least 2"},
      {"refs-no-count.ac", edit("refs 2\n0 0 0", "refs\n0 0 0"), 23, "expected a count"},
      {"mat-out-of-range.ac", edit("SURF 0x02\nmat 0", "SURF 0x02\nmat 1"), 22, "defines 1 MATERIAL"},
      {"surf-type-5.ac", edit("SURF 0x02", "SURF 0x05"), 21, "unknown surface type 5"},
      {"surf-no-flags.ac", edit("SURF 0x02", "SURF zz"), 21, "expected flags"},
      // assimp's reader takes any file starting with "AC3D", whatever its name (here one the FBX reader
      // refuses; a .gltf or .glb must now be glTF before assimp sees it).
      {"ac3d-named.fbx", edit("SURF 0x02\nmat 0", "SURF 0x02\nmat 7"), 22, "defines 1 MATERIAL"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const fs::path p = writeFile(c.name, c.text);
    const std::string e = inputErrorOf(p);
    EXPECT_EQ(e.rfind(p.string() + ":" + std::to_string(c.line) + ": ", 0), 0u) << e;
    EXPECT_NE(e.find(c.says), std::string::npos) << e;
  }
  // The valid file with its line surface of 2 refs still reads (the guard refuses only what it names).
  EXPECT_EQ(loadMeshData(writeFile("quad-ok.ac", kQuadAc)).triangles.size(), 2u);
}

// Counts a file claims far beyond its size must not be allocated: each file is refused and the
// process's peak memory stays small (a vector of 2e9 vertices would be 24 GB).
TEST(AssimpErrors, HugeClaimedCountsAreRefusedWithoutAllocating) {
  std::string ac = kQuadAc;
  ac.replace(ac.find("numvert 4"), 9, "numvert 2000000000");
  std::string acSurf = kQuadAc;
  acSurf.replace(acSurf.find("numsurf 2"), 9, "numsurf 2000000000");
  std::string acSurfSmall = kQuadAc;  // small enough to allocate: assimp would loop 1e8 times
  acSurfSmall.replace(acSurfSmall.find("numsurf 2"), 9, "numsurf 100000000");
  std::string dae = kQuadDae;
  dae.replace(dae.find(R"(count="12")"), 10, R"(count="2000000000")");
  std::string gltf = quadGltf();
  gltf.replace(gltf.find(R"("count": 4, "type": "VEC3", "min")"), 10, R"("count": 2000000000)");
  for (const auto& [name, text] : {std::pair{"huge-v.ac", ac}, {"huge-s.ac", acSurf}, {"huge-s2.ac", acSurfSmall}, {"huge.dae", dae}, {"huge.gltf", gltf}}) {
    SCOPED_TRACE(name);
    const fs::path p = writeFile(name, text);
    const std::string e = inputErrorOf(p);
    EXPECT_EQ(e.rfind(p.string() + ":", 0), 0u) << e;  // AC3D's own check adds the line: "PATH:12: ..."
  }
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  EXPECT_LT(usage.ru_maxrss, 1L << 20) << "peak resident KiB";  // 1 GiB
}

// ---- models as scenes ---------------------------------------------------------------------------------

TEST(AssimpScenes, BareModelGetsOneMeshObjectPerMaterial) {
  const Scene s = loadMeshScene(writeFile("scene.gltf", quadGltf()));
  // red, chrome, ground
  ASSERT_EQ(s.materials.size(), 3u);
  EXPECT_EQ(s.materials[0].name, "red");
  EXPECT_EQ(s.materials[1].name, "chrome");
  ASSERT_EQ(s.meshes.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(s.meshes[i].triangles.size(), 2u);
    EXPECT_EQ(s.meshes[i].material, int(i));
  }
  EXPECT_EQ(s.triangleCount(), 4u);
  EXPECT_EQ(s.objects.size(), 3u);  // two meshes and the ground plane
}

TEST(AssimpScenes, GlassAndEmbeddedAndExternalTexturesMapToSceneMaterials) {
  // A 2x2 PNG (top-left texel red) written by our own writer, embedded as a data URI in one file
  // and referenced as a file next to another.
  std::vector<uint8_t> rgba{255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255};
  saveImageRgba8(dir() / "tex.png", 2, 2, rgba);
  const std::string png = readFile(dir() / "tex.png");
  const std::string glassTextured = R"({"name": "glass", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1],
      "baseColorTexture": {"index": 0}, "metallicFactor": 0},
      "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.9}}})";
  const std::string embedded = R"(, "textures": [{"source": 0}], "images": [{"uri": "data:image/png;base64,)" +
                               base64(png) + R"("}], "extensionsUsed": ["KHR_materials_transmission"])";
  const std::string external = R"(, "textures": [{"source": 0}], "images": [{"uri": "tex.png"}],
      "extensionsUsed": ["KHR_materials_transmission"])";
  for (const auto& [name, extra] : {std::pair{"embedded.gltf", embedded}, {"external.gltf", external}}) {
    SCOPED_TRACE(name);
    const Scene s = loadMeshScene(writeFile(name, quadGltf(glassTextured, extra)));
    ASSERT_EQ(s.materials.size(), 3u);
    const Material& glass = s.materials[1];
    EXPECT_EQ(glass.name, "glass");
    EXPECT_NEAR(glass.transparency, 0.9f, 1e-6f);
    ASSERT_EQ(glass.texture, 0);
    ASSERT_EQ(s.images.size(), 1u);
    EXPECT_EQ(s.images[0].width, 2);
    // Bottom-up in memory as saveImageRgba8 was given it: red at (0, 0), blue above it.
    EXPECT_NEAR(s.images[0].texels[0].r, 1.0f, 1e-6f);
    EXPECT_NEAR(s.images[0].texels[0].b, 0.0f, 1e-6f);
    EXPECT_NEAR(s.images[0].texels[2].b, 1.0f, 1e-6f);
    EXPECT_NEAR(s.images[0].texels[2].r, 0.0f, 1e-6f);
    EXPECT_EQ(s.materials[0].texture, -1);
  }
  // A texture file that does not exist: the base colour, no image (a warning on stderr).
  const std::string missing = R"(, "textures": [{"source": 0}], "images": [{"uri": "nowhere.png"}],
      "extensionsUsed": ["KHR_materials_transmission"])";
  const Scene s = loadMeshScene(writeFile("missing.gltf", quadGltf(glassTextured, missing)));
  EXPECT_EQ(s.materials[1].texture, -1);
  EXPECT_TRUE(s.images.empty());
  // One that exists but is not an image: an error naming the model and the material.
  writeFile("broken.png", "not a png");
  const std::string broken = R"(, "textures": [{"source": 0}], "images": [{"uri": "broken.png"}],
      "extensionsUsed": ["KHR_materials_transmission"])";
  const fs::path bp = writeFile("broken.gltf", quadGltf(glassTextured, broken));
  try {
    loadMeshScene(bp);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(bp.string() + ": material 'glass'", 0), 0u) << e.what();
  }
}

TEST(AssimpScenes, TomlMeshObjectTakesTheGeometryAndItsOwnMaterial) {
  writeFile("inscene.gltf", quadGltf());
  const fs::path toml = writeFile("scene.toml", R"(
[camera]
eye = [0, 2, 20]
target = [6, 1, -3]
[[material]]
name = "paint"
color = [0.2, 0.3, 0.4]
[[object]]
kind = "mesh"
mesh = "inscene.gltf"
material = "paint"
translate = [0, 1, 0]
)");
  const Scene s = loadScene(toml);
  ASSERT_EQ(s.meshes.size(), 1u);
  EXPECT_EQ(s.meshes[0].triangles.size(), 4u);
  EXPECT_EQ(s.materials.at(size_t(s.meshes[0].material)).name, "paint");
  float lo = 1e30f, hi = -1e30f;
  for (const glm::vec3& p : s.meshes[0].positions) lo = std::min(lo, p.y), hi = std::max(hi, p.y);
  EXPECT_NEAR(lo, 1.0f, 1e-6f);
  EXPECT_NEAR(hi, 3.0f, 1e-6f);
}

TEST(AssimpCli, RendersAGltfAndRefusesABrokenOne) {
  const fs::path p = writeFile("cli.gltf", quadGltf());
  const clitest::Result r =
      clitest::run("render " + p.string() + " --json --width 32 --height 32 --frames 1 --warmup 0");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("width"), 32);
  EXPECT_GT(j.at("frame_ms").get<double>(), 0.0);
  const fs::path bad = writeFile("cli-bad.gltf", "{\"asset\": ");
  const clitest::Result rb = clitest::run("render " + bad.string() + " --json --width 32 --height 32");
  EXPECT_NE(rb.code, 0);
  EXPECT_LT(rb.code, 128) << "killed by a signal";
  EXPECT_NE(rb.err.find(bad.string() + ": "), std::string::npos) << rb.err;
}

}  // namespace
