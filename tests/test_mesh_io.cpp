// datasets/ mesh files: every format loads, bad and corrupted files give clear errors, far coordinates
// keep double precision, absurd declared counts are refused before allocation.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <OpenImageIO/imageio.h>

#include "datasets/image_io.hpp"
#include "datasets/mesh_io.hpp"
#include "datasets/procedural.hpp"
#include "datasets_test_util.hpp"

using namespace bvhlab;
namespace fs = std::filesystem;

using namespace bvhlab::datasets_test;

// ---- mesh I/O -------------------------------------------------------------------------------------

namespace {

// One quad (two triangles after fan triangulation) and one triangle, in each format.
const char* kObjQuad =
    "# a quad with uvs and normals\n"
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
    "vn 0 0 1\n"
    "f 1/1/1 2/2/1 3/3/1 4/4/1\n";
const char* kOffQuad = "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
const char* kPlyQuad =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
const char* kStlTriangle =
    "solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 1 1 0\n"
    "  endloop\n endfacet\nendsolid t\n";

std::string binaryPly(bool truncated) {
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const float v[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  s.append(reinterpret_cast<const char*>(v), sizeof v);
  s.push_back(char(4));
  const int32_t idx[4] = {0, 1, 2, 3};
  s.append(reinterpret_cast<const char*>(idx), truncated ? 10 : sizeof idx);
  return s;
}

std::string binaryStl(uint32_t declared, uint32_t written, float badValue = 0.0f) {
  std::string s(80, ' ');
  s.append(reinterpret_cast<const char*>(&declared), 4);
  for (uint32_t i = 0; i < written; ++i) {
    const float rec[12] = {0, 0, 1, float(i), 0, 0, float(i) + 1, badValue, 0, float(i), 1, 0};
    s.append(reinterpret_cast<const char*>(rec), sizeof rec);
    s.append(2, '\0');
  }
  return s;
}

}  // namespace

TEST(MeshIo, EverySupportedFormatLoads) {
  TempDir tmp;
  writeFile(tmp / "q.obj", kObjQuad);
  writeFile(tmp / "q.off", kOffQuad);
  writeFile(tmp / "q.ply", kPlyQuad);
  writeFile(tmp / "qb.ply", binaryPly(false));
  writeFile(tmp / "t.stl", kStlTriangle);
  writeFile(tmp / "tb.STL", binaryStl(3, 3));  // upper-case extension too
  for (const char* name : {"q.obj", "q.off", "q.ply", "qb.ply"}) {
    SCOPED_TRACE(name);
    const Mesh m = loadMesh(tmp / name);
    EXPECT_EQ(m.name, (tmp / name).string());
    ASSERT_EQ(m.positions.size(), 4u);
    ASSERT_EQ(m.triangles.size(), 2u);  // the quad, fan-triangulated
    EXPECT_EQ(m.positions[2], glm::vec3(1, 1, 0));
    EXPECT_EQ(m.triangles[0], glm::uvec3(0, 1, 2));
    EXPECT_EQ(m.triangles[1], glm::uvec3(0, 2, 3));
  }
  const Mesh obj = loadMesh(tmp / "q.obj");
  ASSERT_EQ(obj.normals.size(), 4u);
  ASSERT_EQ(obj.uvs.size(), 4u);
  EXPECT_EQ(obj.normals[3], glm::vec3(0, 0, 1));
  EXPECT_EQ(obj.uvs[2], glm::vec2(1, 1));
  EXPECT_TRUE(loadMesh(tmp / "q.off").normals.empty());
  const Mesh stl = loadMesh(tmp / "t.stl");
  EXPECT_EQ(stl.triangles.size(), 1u);
  const Mesh stlb = loadMesh(tmp / "tb.STL");
  EXPECT_EQ(stlb.triangles.size(), 3u);
  expectIndicesInRange(stlb);
}

TEST(MeshIo, ObjWriterRoundTrips) {
  TempDir tmp;
  const Mesh sphere = makeUvSphere(8, 5);
  saveMeshObj(tmp / "out/s.obj", sphere);
  const Mesh back = loadMesh(tmp / "out/s.obj");
  EXPECT_EQ(back.positions, sphere.positions);
  EXPECT_EQ(back.triangles, sphere.triangles);
  ASSERT_EQ(back.uvs.size(), sphere.uvs.size());
  ASSERT_EQ(back.normals.size(), sphere.normals.size());
  // The sphere has two vertices no triangle uses (a pole's seam copies); the loader gives those
  // placeholders, so compare the attributes triangles actually use.
  for (const glm::uvec3& t : sphere.triangles)
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(back.uvs[t[k]], sphere.uvs[t[k]]);
      EXPECT_NEAR(glm::distance(back.normals[t[k]], sphere.normals[t[k]]), 0.0f, 1e-6f);
    }
}

TEST(MeshIo, BadFilesGiveOneLineInputErrorsWithPathAndLine) {
  TempDir tmp;
  struct Case {
    std::string file, content, expect;  // expect: a substring after "PATH"
  };
  const std::vector<Case> cases = {
      {"missing.obj", "", ": mesh file not found"},
      {"mesh.xyz", "1 2 3\n", ": unsupported mesh format '.xyz'"},
      {"mesh.dae", "<collada/>", "mesh.dae: cannot read the file (assimp: "},
      {"empty.off", "", ": empty file"},
      {"nofaces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", ": mesh has no faces"},
      {"nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", ":2: vertex: value 'nan' is NaN or infinite"},
      {"inf.off", "OFF\n3 1 0\n0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n", ":4: vertex: value 'inf' is NaN or infinite"},
      {"range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", ":4: face: vertex index 9 out of range"},
      {"zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", ":4: face: index 0"},
      {"range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", ":6: face: vertex index 3 out of range"},
      {"twocorners.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", ":3: face with 2 corners"},
      {"trunc.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n", "truncated: file ends after 1 of 2 faces"},
      {"truncline.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n", ":6: face: declares 3 vertices but lists 2"},
      {"hugecount.off", "OFF\n4000000000 1 0\n0 0 0\n", ":2: truncated: header declares 4000000000 vertices"},
      {"hugeface.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n1000000000 0 1 2\n", ":6: face: declares 1000000000"},
      {"binary.off", "OFF BINARY\n", ":1: binary OFF is not supported"},
      {"trunc.ply", std::string(kPlyQuad).substr(0, std::string(kPlyQuad).size() - 10), "truncated"},
      {"truncb.ply", binaryPly(true), "truncated"},
      {"nan.ply", std::string(kPlyQuad).replace(std::string(kPlyQuad).find("1 1 0"), 5, "1 nan 0"), "is NaN or infinite"},
      // OpenMesh reads the values as one stream: one extra shifts every later record (fuzz_ply: a hang).
      {"extra.ply", std::string(kPlyQuad).replace(std::string(kPlyQuad).find("1 1 0"), 5, "1 1 0 7"),
       ":12: vertex: 1 value(s) more than its properties declare"},
      {"trunc.stl", std::string(kStlTriangle).substr(0, 60), "truncated ASCII STL"},
      {"truncb.stl", binaryStl(5, 3), "binary STL size mismatch: header declares 5 triangles"},
      {"nanb.stl", binaryStl(2, 2, std::nanf("")), "triangle 0: vertex coordinate is NaN or infinite"},
      {"noheader.off", "3 1 0\n0 0 0\n", ":1: not an OFF file"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    const fs::path p = tmp / c.file;
    if (c.file != "missing.obj") writeFile(p, c.content);
    const std::string msg = inputErrorOf([&] { loadMesh(p); });
    EXPECT_EQ(msg.rfind(p.string(), 0), 0u) << msg;  // starts with the path
    EXPECT_NE(msg.find(c.expect), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

TEST(MeshIo, CorruptedFilesNeverCrash) {
  // Flipped bytes, cuts and inserted junk in small valid files of every format: each load either
  // succeeds with a well-formed mesh or throws InputError (a crash or another exception fails).
  TempDir tmp;
  const std::vector<std::pair<std::string, std::string>> seeds = {
      {".obj", kObjQuad}, {".off", kOffQuad}, {".ply", kPlyQuad}, {".ply", binaryPly(false)},
      {".stl", kStlTriangle}, {".stl", binaryStl(4, 4)}};
  const char* junk[] = {"9999999999", "-1", "nan", " ", "\n", "/", "3 ", "\xff\xff\xff\x7f", "1e39"};
  SplitMix64 rng(2024);
  int loaded = 0, rejected = 0;
  for (const auto& [ext, seed] : seeds)
    for (int k = 0; k < 60; ++k) {
      std::string s = seed;
      const int mode = int(rng.next() % 3);
      if (mode == 0) {
        s.resize(rng.next() % s.size());
      } else if (mode == 1) {
        for (int j = 0; j < 3; ++j) s[rng.next() % s.size()] = char(rng.next() & 0xff);
      } else {
        const char* piece = junk[rng.next() % std::size(junk)];  // drawn first: GCC's order for the two arguments
        s.insert(rng.next() % s.size(), piece);
      }
      const fs::path p = tmp / ("f" + std::to_string(k) + ext);
      writeFile(p, s);
      try {
        const Mesh m = loadMesh(p);
        EXPECT_TRUE(allFinite(m));
        expectIndicesInRange(m);
        ++loaded;
      } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()).rfind(p.string(), 0), 0u);
        ++rejected;
      }
    }
  EXPECT_GT(rejected, 0);
  EXPECT_EQ(loaded + rejected, int(seeds.size()) * 60);
}

// ---- far meshes: positions stay double until rebased ---------------------------------------------

namespace {

// A small mesh with coordinates that need every bit of a float near the origin (thirds, sevenths).
const std::vector<glm::dvec3> kNearCorners = {
    {0.0, 0.0, 0.0}, {1.0 / 3.0, 0.0, 1.0 / 7.0}, {0.1, 0.2, 0.3}, {-0.25, 1.0 / 3.0, 0.05}};
const std::vector<glm::uvec3> kNearTriangles = {{0, 1, 2}, {0, 2, 3}, {1, 3, 2}};

std::string g17(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// The mesh moved by `offset`, in `format`, every coordinate with 17 significant digits.
std::string farMeshFile(const std::string& format, glm::dvec3 offset) {
  std::string s;
  auto xyz = [&](glm::dvec3 p) { return g17(p.x) + " " + g17(p.y) + " " + g17(p.z); };
  if (format == "obj") {
    for (const glm::dvec3& p : kNearCorners) s += "v " + xyz(offset + p) + "\n";
    for (const glm::uvec3& t : kNearTriangles)
      s += "f " + std::to_string(t.x + 1) + " " + std::to_string(t.y + 1) + " " + std::to_string(t.z + 1) + "\n";
  } else if (format == "off") {
    s = "OFF\n" + std::to_string(kNearCorners.size()) + " " + std::to_string(kNearTriangles.size()) + " 0\n";
    for (const glm::dvec3& p : kNearCorners) s += xyz(offset + p) + "\n";
    for (const glm::uvec3& t : kNearTriangles)
      s += "3 " + std::to_string(t.x) + " " + std::to_string(t.y) + " " + std::to_string(t.z) + "\n";
  } else if (format == "ply" || format == "plyb") {
    const bool binary = format == "plyb";
    s = std::string("ply\nformat ") + (binary ? "binary_little_endian" : "ascii") + " 1.0\nelement vertex " +
        std::to_string(kNearCorners.size()) + "\nproperty double x\nproperty double y\nproperty double z\n" +
        "element face " + std::to_string(kNearTriangles.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const glm::dvec3& p : kNearCorners) {
      const glm::dvec3 q = offset + p;
      if (binary) s.append(reinterpret_cast<const char*>(&q[0]), 3 * sizeof(double));  // little-endian host
      else s += xyz(q) + "\n";
    }
    for (const glm::uvec3& t : kNearTriangles) {
      if (binary) {
        s.push_back(char(3));
        const int32_t idx[3] = {int32_t(t.x), int32_t(t.y), int32_t(t.z)};
        s.append(reinterpret_cast<const char*>(idx), sizeof idx);
      } else {
        s += "3 " + std::to_string(t.x) + " " + std::to_string(t.y) + " " + std::to_string(t.z) + "\n";
      }
    }
  } else if (format == "stl") {
    s = "solid far\n";
    for (const glm::uvec3& t : kNearTriangles) {
      s += " facet normal 0 0 0\n  outer loop\n";
      for (int k = 0; k < 3; ++k) s += "   vertex " + xyz(offset + kNearCorners[t[k]]) + "\n";
      s += "  endloop\n endfacet\n";
    }
    s += "endsolid far\n";
  }
  return s;
}

}  // namespace

// Every text format, and binary PLY with `property double`, keeps far coordinates to double precision:
// at 1e6 (float spacing 0.0625) and 1e7 (spacing 1) the corners come back within 1e-8 of the file's
// values (double's spacing there is 1.2e-10 / 1.9e-9); a reader that narrows to float is off by up to
// half a float spacing (0.03 / 0.5), which these bounds reject.
TEST(MeshIo, FarCoordinatesKeepDoublePrecisionInEveryFormat) {
  TempDir tmp;
  for (double d : {1e6, 1e7}) {
    const glm::dvec3 offset = d * glm::dvec3(1.0, 0.5, -1.0);
    for (const std::string format : {"obj", "off", "ply", "plyb", "stl"}) {
      SCOPED_TRACE(format + " at " + g17(d));
      const fs::path p = tmp / ("far_" + format + (format == "plyb" ? ".ply" : "." + format.substr(0, 3)));
      writeFile(p, farMeshFile(format, offset));
      const MeshData m = loadMeshData(p);
      ASSERT_EQ(m.triangles.size(), kNearTriangles.size());
      ASSERT_EQ(m.positions.size(), kNearCorners.size());  // STL corners are welded back into 4 vertices
      for (size_t t = 0; t < kNearTriangles.size(); ++t)
        for (int k = 0; k < 3; ++k) {
          const glm::dvec3 got = m.positions[m.triangles[t][k]] - offset, want = kNearCorners[kNearTriangles[t][k]];
          EXPECT_LE(glm::length(got - want), 1e-8) << "triangle " << t << " corner " << k;
        }
      // Rebased at the bounding box centre (what loadMeshScene does), the float mesh keeps that precision.
      const glm::dvec3 centre = boundsCentre(m);
      const Mesh rebased = rebasedMesh(m, centre);
      for (size_t v = 0; v < m.positions.size(); ++v)
        EXPECT_LE(glm::length(glm::dvec3(rebased.positions[v]) - (m.positions[v] - centre)), 1e-6);
    }
  }
}

// Binary STL stores float: the double path adds no further rounding (the values come back bit-exact).
TEST(MeshIo, BinaryStlFloatsConvertExactly) {
  TempDir tmp;
  std::string s(80, ' ');
  const uint32_t one = 1;
  s.append(reinterpret_cast<const char*>(&one), 4);
  const float rec[12] = {0, 0, 1, 1e6f + 0.0625f, 5e5f, -1e6f, 1e6f + 0.125f, 5e5f, -1e6f, 1e6f, 5e5f + 0.0625f, -1e6f};
  s.append(reinterpret_cast<const char*>(rec), sizeof rec);
  s.append(2, '\0');
  writeFile(tmp / "f.stl", s);
  const MeshData m = loadMeshData(tmp / "f.stl");
  ASSERT_EQ(m.positions.size(), 3u);
  EXPECT_EQ(m.positions[0], glm::dvec3(1e6 + 0.0625, 5e5, -1e6));
  EXPECT_EQ(m.positions[2], glm::dvec3(1e6, 5e5 + 0.0625, -1e6));
}

// ---- resource limits: absurd claimed counts fail with a clear error before allocation ---------

TEST(MeshIo, AbsurdDeclaredCountsAreRefusedBeforeAllocation) {
  TempDir tmp;
  std::string stl(80, ' ');  // no "solid": a binary STL header claiming 4e9 triangles, one record present
  const uint32_t claimed = 4'000'000'000u;
  stl.append(reinterpret_cast<const char*>(&claimed), 4);
  stl.append(50, '\0');
  const std::string plyHead = "ply\nformat binary_little_endian 1.0\nelement vertex 2147483648\nproperty float x\n"
                              "property float y\nproperty float z\n";
  const std::string plyFaces = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                               "property float y\nproperty float z\nelement face 4000000000\n"
                               "property list uchar int vertex_indices\nend_header\n" + std::string(36, '\0') +
                               std::string("\x03\0\0\0\0\1\0\0\0\2\0\0\0", 13);
  struct Case {
    std::string file, content, expect;
  };
  const std::vector<Case> cases = {
      {"huge.stl", stl, ": binary STL size mismatch: header declares 4000000000 triangles (200000000084 bytes)"},
      {"hugev.ply", plyHead + "end_header\n" + std::string(36, '\0'),
       ": truncated: binary data too short for 2147483648 vertex records (12 bytes each"},
      {"hugev_ascii.ply", "ply\nformat ascii 1.0\nelement vertex 2147483648\nproperty float x\nproperty float y\n"
                          "property float z\nend_header\n0 0 0\n",
       ": truncated: file ends after 1 of 2147483648 vertex records"},
      {"hugef.ply", plyFaces, ": truncated: binary data ends inside face 1"},
      {"huge.off", "OFF\n2147483648 4000000000 0\n0 0 0\n", ":2: truncated: header declares 2147483648 vertices and "
                                                            "4000000000 faces but the file has only"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    const fs::path p = tmp / c.file;
    writeFile(p, c.content);
    const std::string msg = inputErrorOf([&] { loadMeshData(p); });
    EXPECT_EQ(msg.rfind(p.string(), 0), 0u) << msg;
    EXPECT_NE(msg.find(c.expect), std::string::npos) << msg;
    EXPECT_EQ(msg.find("out of memory"), std::string::npos) << msg;  // refused, not caught after bad_alloc
  }
}
