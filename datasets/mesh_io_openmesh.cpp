// OpenMesh's readers (OBJ, OFF, PLY) into a flat polygon soup (mesh_io_detail.hpp's Soup): faces,
// normals and UVs. OpenMesh narrows positions to float; loadMeshData replaces them with the double
// positions of our own pass over the file and uses these only to check that the two agree.
#include <algorithm>
#include <iostream>
#include <mutex>
#include <sstream>

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include "datasets/mesh_io_detail.hpp"

namespace bvhlab::meshio {
namespace {

using OpenMesh::EdgeHandle;
using OpenMesh::FaceHandle;
using OpenMesh::HalfedgeHandle;
using OpenMesh::Vec2f;
using OpenMesh::Vec3d;
using OpenMesh::Vec3f;
using OpenMesh::Vec3uc;
using OpenMesh::Vec4f;
using OpenMesh::Vec4uc;
using OpenMesh::VertexHandle;
using StatusInfo = OpenMesh::Attributes::StatusInfo;

// Collects what the readers report into flat arrays; topology calls (used only by OpenMesh's own
// .om format) are refused. Nothing here trusts a handle: out-of-range ones are recorded as errors.
class SoupImporter final : public OpenMesh::IO::BaseImporter {
 public:
  Soup soup;
  std::string firstError;

  VertexHandle add_vertex(const Vec3f& p) override { return addVertex(glm::vec3(p[0], p[1], p[2])); }
  VertexHandle add_vertex(const Vec3d& p) override { return addVertex(glm::vec3(glm::dvec3(p[0], p[1], p[2]))); }
  VertexHandle add_vertex() override { return addVertex(glm::vec3(0.0f)); }
  HalfedgeHandle add_edge(VertexHandle, VertexHandle) override { return error("half-edge input is not supported"), HalfedgeHandle(); }
  FaceHandle add_face(const VHandles& vs) override {
    if (vs.size() < 3) return error("face with fewer than 3 vertices"), FaceHandle();
    for (VertexHandle v : vs) soup.faceIndices.push_back(v.idx());
    soup.faceStart.push_back(uint32_t(soup.faceIndices.size()));
    return FaceHandle(int(soup.faceStart.size() - 2));
  }
  FaceHandle add_face(HalfedgeHandle) override { return error("half-edge input is not supported"), FaceHandle(); }
  void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<Vec2f>&) override {}
  void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<Vec3f>&) override {}
  void set_face_texindex(FaceHandle, int) override {}
  void set_point(VertexHandle v, const Vec3f& p) override {
    if (valid(v)) soup.positions[v.idx()] = glm::vec3(p[0], p[1], p[2]);
  }
  void set_halfedge(VertexHandle, HalfedgeHandle) override {}
  void set_normal(VertexHandle v, const Vec3f& n) override { setNormal(v, glm::vec3(n[0], n[1], n[2])); }
  void set_normal(VertexHandle v, const Vec3d& n) override { setNormal(v, glm::vec3(glm::dvec3(n[0], n[1], n[2]))); }
  void set_color(VertexHandle, const Vec3uc&) override {}
  void set_color(VertexHandle, const Vec4uc&) override {}
  void set_color(VertexHandle, const Vec3f&) override {}
  void set_color(VertexHandle, const Vec4f&) override {}
  void set_texcoord(VertexHandle v, const Vec2f& t) override {
    if (!valid(v)) return;
    soup.uvs[v.idx()] = glm::vec2(t[0], t[1]);
    soup.hasUv[v.idx()] = 1;
  }
  void set_status(VertexHandle, const StatusInfo&) override {}
  void set_next(HalfedgeHandle, HalfedgeHandle) override {}
  void set_face(HalfedgeHandle, FaceHandle) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(HalfedgeHandle, const Vec2f&) override {}
  void set_texcoord(VertexHandle, const Vec3f&) override {}
  void set_texcoord(HalfedgeHandle, const Vec3f&) override {}
  void set_status(HalfedgeHandle, const StatusInfo&) override {}
  void set_color(EdgeHandle, const Vec3uc&) override {}
  void set_color(EdgeHandle, const Vec4uc&) override {}
  void set_color(EdgeHandle, const Vec3f&) override {}
  void set_color(EdgeHandle, const Vec4f&) override {}
  void set_status(EdgeHandle, const StatusInfo&) override {}
  void set_normal(FaceHandle, const Vec3f&) override {}
  void set_normal(FaceHandle, const Vec3d&) override {}
  void set_color(FaceHandle, const Vec3uc&) override {}
  void set_color(FaceHandle, const Vec4uc&) override {}
  void set_color(FaceHandle, const Vec3f&) override {}
  void set_color(FaceHandle, const Vec4f&) override {}
  void set_status(FaceHandle, const StatusInfo&) override {}
  void add_texture_information(int, std::string) override {}
  // Readers pass header counts straight to reserve(); our own pass has bounded them by the file size,
  // and the caps (2^24 vertices, 2^26 indices) bound them again.
  void reserve(unsigned nV, unsigned, unsigned nF) override {
    soup.positions.reserve(std::min(nV, 1u << 24));
    soup.faceIndices.reserve(std::min(uint64_t(nF) * 3, uint64_t(1) << 26));
  }
  size_t n_vertices() const override { return soup.positions.size(); }
  size_t n_faces() const override { return soup.faceCount(); }
  size_t n_edges() const override { return 0; }

 private:
  bool valid(VertexHandle v) const { return v.idx() >= 0 && size_t(v.idx()) < soup.positions.size(); }
  void error(const char* what) {
    if (firstError.empty()) firstError = what;
  }
  VertexHandle addVertex(glm::vec3 p) {
    soup.positions.push_back(p);
    soup.normals.emplace_back(0.0f);
    soup.uvs.emplace_back(0.0f);
    soup.hasNormal.push_back(0);
    soup.hasUv.push_back(0);
    return VertexHandle(int(soup.positions.size() - 1));
  }
  void setNormal(VertexHandle v, glm::vec3 n) {
    if (!valid(v)) return;
    soup.normals[v.idx()] = n;
    soup.hasNormal[v.idx()] = 1;
  }
};

// OpenMesh's readers keep state in a process-wide singleton and print to a global stream.
std::mutex& openMeshMutex() {
  static std::mutex m;
  return m;
}

// OpenMesh's error stream, taken off std::cerr and into one capture stream, once per process (call
// with openMeshMutex() held). OpenMesh 9's multiplex_streambuf::disconnect() drops the target that
// connect() allocated without deleting it, so connecting a stream per file leaked two per read. The
// stream is never destroyed: omerr() still points at it during static destruction. OpenMesh is only
// used by readWithOpenMesh, so nothing else printed to omerr() is lost from the terminal.
std::ostringstream& openMeshErrors() {
  static std::ostringstream* const captured = [] {
    auto* s = new std::ostringstream;
    OpenMesh::mostream& err = ::omerr();
    err.disconnect(std::cerr);
    err.connect(*s);
    return s;
  }();
  return *captured;
}

}  // namespace

// Runs OpenMesh on the file with its error stream captured; a failure becomes a MeshFileError with
// OpenMesh's first error line.
Soup readWithOpenMesh(const std::string& path) {
  SoupImporter importer;
  std::string message;
  bool ok = false;
  {
    std::lock_guard<std::mutex> lock(openMeshMutex());
    std::ostringstream& captured = openMeshErrors();
    captured.str("");
    captured.clear();
    OpenMesh::mostream& err = ::omerr();
    OpenMesh::mostream& log = ::omlog();
    const bool logWasEnabled = log.is_enabled();
    log.disable();
    OpenMesh::IO::Options opt(OpenMesh::IO::Options::VertexNormal | OpenMesh::IO::Options::VertexTexCoord);
    try {
      ok = OpenMesh::IO::IOManager().read(path, importer, opt);
    } catch (...) {
      ok = false;
    }
    err.flush();
    if (logWasEnabled) log.enable();
    message = captured.str();
    const size_t nl = message.find('\n');
    if (nl != std::string::npos) message.resize(nl);
  }
  if (!ok) fail("OpenMesh cannot read the file" + (message.empty() ? std::string() : " (" + message + ")"));
  if (!importer.firstError.empty()) fail(importer.firstError);
  return std::move(importer.soup);
}

}  // namespace bvhlab::meshio
