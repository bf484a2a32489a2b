#include "datasets/mesh_io.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <mutex>
#include <optional>
#include <sstream>
#include <string_view>

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/System/omstream.hh>

namespace bvhlab {
namespace fs = std::filesystem;

namespace {

// Larger files are refused rather than read into memory (the biggest shipped mesh is 4 MB).
constexpr uintmax_t kMaxFileBytes = uintmax_t(1) << 31;

struct MeshFileError {
  size_t line = 0;  // 1-based; 0 = no line
  std::string message;
};
[[noreturn]] void failAt(size_t line, std::string message) { throw MeshFileError{line, std::move(message)}; }
[[noreturn]] void fail(std::string message) { throw MeshFileError{0, std::move(message)}; }

std::string lowerExtension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

std::string readWholeFile(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) fail("mesh file not found");
  if (!fs::is_regular_file(path, ec)) fail("not a regular file");
  const uintmax_t size = fs::file_size(path, ec);
  if (ec) fail("cannot stat file (" + ec.message() + ")");
  if (size > kMaxFileBytes) fail("file too large (" + std::to_string(size) + " bytes)");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("cannot open file");
  std::string data(size, '\0');
  in.read(data.data(), std::streamsize(size));
  if (size_t(in.gcount()) != size) fail("cannot read file");
  return data;
}

// ---- a tiny line/token scanner for the text pre-checks ------------------------------------------

struct LineScanner {
  std::string_view text;
  size_t pos = 0, lineNo = 0;
  // Next line (without '\n' / '\r'); false at the end of the text.
  bool next(std::string_view& line) {
    if (pos >= text.size()) return false;
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    line = text.substr(pos, end - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = end + 1;
    ++lineNo;
    return true;
  }
};

bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

std::vector<std::string_view> tokens(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && isBlank(line[i])) ++i;
    size_t j = i;
    while (j < line.size() && !isBlank(line[j])) ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

// A file's token for a message: at most 32 characters, non-printable bytes as \xNN.
std::string printable(std::string_view token) {
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (size_t i = 0; i < token.size() && i < 32; ++i) {
    const unsigned char c = token[i];
    if (c >= 0x20 && c < 0x7f) {
      out += char(c);
    } else {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  if (token.size() > 32) out += "...";
  return out;
}
std::string quoted(std::string_view token) {
  std::string out(1, '\'');  // built with += : GCC 12 warns falsely (-Wrestrict) on "'" + s + "'"
  out += printable(token);
  out += '\'';
  return out;
}

std::optional<double> parseReal(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);  // from_chars rejects a leading '+'
  double v = 0.0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

std::optional<long long> parseInt(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  long long v = 0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

// `count` finite reals starting at toks[first]; `what` names them in the message.
void expectReals(const std::vector<std::string_view>& toks, size_t first, size_t count, size_t line,
                 const char* what) {
  if (toks.size() < first + count)
    failAt(line, std::string(what) + ": expected " + std::to_string(count) + " numbers, found " +
                     std::to_string(toks.size() > first ? toks.size() - first : 0));
  for (size_t i = first; i < first + count; ++i) {
    auto v = parseReal(toks[i]);
    if (!v) failAt(line, std::string(what) + ": " + quoted(toks[i]) + " is not a number");
    if (!std::isfinite(*v)) failAt(line, std::string(what) + ": value " + quoted(toks[i]) + " is NaN or infinite");
  }
}

// What a file promises, to detect truncation after OpenMesh has read it.
struct Declared {
  std::optional<size_t> vertices, faces;
};

// ---- pre-checks -----------------------------------------------------------------------------------

// ASCII OFF: "[ST][C][N]OFF" line, "nV nF nE" line, nV vertex lines, nF face lines "k i0 .. ik-1".
Declared precheckOff(std::string_view text) {
  LineScanner sc{text};
  std::string_view line;
  sc.next(line);
  auto head = tokens(line);
  const std::string_view magic = head.empty() ? std::string_view() : head[0];
  const size_t off = magic.rfind("OFF");
  if (off == std::string_view::npos || off + 3 != magic.size()) failAt(1, "not an OFF file (no 'OFF' header)");
  const std::string_view prefix = magic.substr(0, off);
  if (prefix.find_first_of("4n") != std::string_view::npos) failAt(1, "OFF with 4D or n-D vertices is not supported");
  if (prefix.find_first_not_of("STCN") != std::string_view::npos) failAt(1, "unknown OFF header " + quoted(magic));
  const bool hasNormals = prefix.find('N') != std::string_view::npos;
  if (head.size() > 1 && head[1] == "BINARY") failAt(1, "binary OFF is not supported");
  if (head.size() > 1) failAt(1, "the vertex/face counts must be on the line after " + quoted(magic));

  if (!sc.next(line)) fail("truncated: no vertex/face count line");
  auto counts = tokens(line);
  if (counts.size() < 2) failAt(sc.lineNo, "expected 'vertices faces edges' counts");
  auto nV = parseInt(counts[0]), nF = parseInt(counts[1]);
  if (!nV || !nF || *nV < 0 || *nF < 0) failAt(sc.lineNo, "bad vertex/face counts");
  // Each vertex line needs >= 6 bytes ("0 0 0\n"), each face line >= 8 ("3 0 1 2\n").
  if (uint64_t(*nV) * 6 + uint64_t(*nF) * 8 > text.size())
    failAt(sc.lineNo, "truncated: header declares " + std::to_string(*nV) + " vertices and " + std::to_string(*nF) +
                          " faces but the file has only " + std::to_string(text.size()) + " bytes");

  auto nextContentLine = [&](const char* what, long long i, long long n) {
    do {
      if (!sc.next(line))
        fail("truncated: file ends after " + std::to_string(i) + " of " + std::to_string(n) + " " + what);
    } while (tokens(line).empty());
  };
  for (long long i = 0; i < *nV; ++i) {
    nextContentLine("vertices", i, *nV);
    auto t = tokens(line);
    expectReals(t, 0, hasNormals ? 6 : 3, sc.lineNo, "vertex");
  }
  for (long long i = 0; i < *nF; ++i) {
    nextContentLine("faces", i, *nF);
    auto t = tokens(line);
    auto k = parseInt(t[0]);
    if (!k) failAt(sc.lineNo, "face: " + quoted(t[0]) + " is not a vertex count");
    if (*k < 3) failAt(sc.lineNo, "face with " + std::to_string(*k) + " vertices (need at least 3)");
    if (size_t(*k) + 1 > t.size())
      failAt(sc.lineNo, "face: declares " + std::to_string(*k) + " vertices but lists " + std::to_string(t.size() - 1));
    for (long long j = 1; j <= *k; ++j) {
      auto idx = parseInt(t[j]);
      if (!idx) failAt(sc.lineNo, "face: " + quoted(t[j]) + " is not a vertex index");
      if (*idx < 0 || *idx >= *nV)
        failAt(sc.lineNo, "face: vertex index " + std::to_string(*idx) + " out of range [0, " + std::to_string(*nV) + ")");
    }
  }
  return Declared{size_t(*nV), size_t(*nF)};
}

// OBJ: v / vt / vn lines hold finite numbers; f lines have >= 3 corners whose indices resolve.
Declared precheckObj(std::string_view text) {
  LineScanner sc{text};
  std::string_view line;
  long long nV = 0, nT = 0, nN = 0;
  size_t nF = 0;
  // Positive indices may point forward, so they are checked once all counts are known: keep, per
  // element kind, the largest index seen and the line that holds it.
  struct MaxRef { long long index = 0; size_t line = 0; };
  MaxRef maxRef[3];
  while (sc.next(line)) {
    auto t = tokens(line);
    if (t.empty() || t[0].front() == '#') continue;
    if (t[0] == "v") { expectReals(t, 1, 3, sc.lineNo, "vertex"); ++nV; }
    else if (t[0] == "vt") { expectReals(t, 1, 2, sc.lineNo, "texture coordinate"); ++nT; }
    else if (t[0] == "vn") { expectReals(t, 1, 3, sc.lineNo, "normal"); ++nN; }
    else if (t[0] == "f") {
      if (t.size() < 4) failAt(sc.lineNo, "face with " + std::to_string(t.size() - 1) + " corners (need at least 3)");
      for (size_t c = 1; c < t.size(); ++c) {
        // corner = v | v/vt | v//vn | v/vt/vn
        std::string_view corner = t[c];
        const long long counts[3] = {nV, nT, nN};
        for (int part = 0; part < 3 && !corner.empty(); ++part) {
          const size_t slash = corner.find('/');
          std::string_view field = corner.substr(0, slash);
          corner = slash == std::string_view::npos ? std::string_view() : corner.substr(slash + 1);
          if (field.empty()) {
            if (part == 0) failAt(sc.lineNo, "face corner " + quoted(t[c]) + " has no vertex index");
            continue;
          }
          auto idx = parseInt(field);
          if (!idx) failAt(sc.lineNo, "face: " + quoted(t[c]) + " is not a valid corner");
          if (*idx == 0) failAt(sc.lineNo, "face: index 0 in " + quoted(t[c]) + " (OBJ indices start at 1)");
          if (*idx < 0 && -*idx > counts[part])
            failAt(sc.lineNo, "face: relative index " + std::to_string(*idx) + " in " + quoted(t[c]) +
                                  " points before the first element");
          if (*idx > maxRef[part].index) maxRef[part] = {*idx, sc.lineNo};
        }
      }
      ++nF;
    }
  }
  const long long counts[3] = {nV, nT, nN};
  const char* what[3] = {"vertex", "texture coordinate", "normal"};
  for (int part = 0; part < 3; ++part)
    if (maxRef[part].index > counts[part])
      failAt(maxRef[part].line, std::string("face: ") + what[part] + " index " + std::to_string(maxRef[part].index) +
                                    " out of range (file has " + std::to_string(counts[part]) + ")");
  return Declared{size_t(nV), nF};
}

// STL: binary when the size is exactly 84 + 50 * count; otherwise ASCII "solid ... endsolid".
Declared precheckStl(std::string_view text, bool& binary) {
  if (text.size() >= 84) {
    uint32_t count = 0;
    std::memcpy(&count, text.data() + 80, 4);  // little-endian on every platform we build for
    if (84 + 50 * uint64_t(count) == text.size()) {
      binary = true;
      // OpenMesh merges STL vertices in a std::map keyed by position: NaN there breaks the ordering
      // the map relies on, so reject non-finite coordinates before it sees them.
      for (uint32_t i = 0; i < count; ++i)
        for (int k = 0; k < 9; ++k) {
          float v = 0.0f;
          std::memcpy(&v, text.data() + 84 + 50 * size_t(i) + 12 + 4 * k, 4);
          if (!std::isfinite(v)) fail("triangle " + std::to_string(i) + ": vertex coordinate is NaN or infinite");
        }
      return Declared{std::nullopt, size_t(count)};
    }
  }
  binary = false;
  const size_t first = text.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos || text.substr(first, 5) != "solid") {
    if (text.size() >= 84) {
      uint32_t count = 0;
      std::memcpy(&count, text.data() + 80, 4);
      fail("binary STL size mismatch: header declares " + std::to_string(count) + " triangles (" +
           std::to_string(84 + 50 * uint64_t(count)) + " bytes) but the file has " + std::to_string(text.size()) +
           " bytes (truncated?)");
    }
    fail("not an STL file (too short for binary, no 'solid' for ASCII)");
  }
  LineScanner sc{text};
  std::string_view line;
  size_t facets = 0, vertices = 0, endfacets = 0;
  bool ended = false;
  while (sc.next(line)) {
    auto t = tokens(line);
    if (t.empty()) continue;
    if (t[0] == "facet") {
      if (facets != endfacets) failAt(sc.lineNo, "'facet' before the previous facet's 'endfacet'");
      ++facets;
    } else if (t[0] == "vertex") {
      expectReals(t, 1, 3, sc.lineNo, "vertex");
      ++vertices;
    } else if (t[0] == "endfacet") {
      if (vertices != 3 * facets)
        failAt(sc.lineNo, "facet with " + std::to_string(vertices - 3 * (facets - 1)) + " vertices (need 3)");
      ++endfacets;
    } else if (t[0] == "endsolid") {
      ended = true;
      break;
    }
  }
  if (!ended || facets != endfacets) fail("truncated ASCII STL (no 'endsolid' after the last facet)");
  return Declared{std::nullopt, facets};
}

// PLY: header; then ASCII lines or binary records that fit the declared elements exactly.
Declared precheckPly(std::string_view text) {
  struct Property { bool list = false; int countBytes = 0, itemBytes = 0, bytes = 0; std::string name; };
  struct Element { std::string name; uint64_t count = 0; std::vector<Property> props; };
  auto typeBytes = [](std::string_view t) -> int {
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32") return 4;
    if (t == "double" || t == "float64") return 8;
    return 0;
  };
  LineScanner sc{text};
  std::string_view line;
  sc.next(line);
  if (tokens(line).empty() || tokens(line)[0] != "ply") failAt(1, "not a PLY file (no 'ply' magic)");
  std::string format;
  std::vector<Element> elements;
  bool ended = false;
  while (sc.next(line)) {
    auto t = tokens(line);
    if (t.empty() || t[0] == "comment" || t[0] == "obj_info") continue;
    if (t[0] == "format") {
      if (t.size() < 2) failAt(sc.lineNo, "bad format line");
      format = printable(t[1]);
      if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
        failAt(sc.lineNo, "unknown PLY format '" + format + "'");
    } else if (t[0] == "element") {
      auto n = t.size() == 3 ? parseInt(t[2]) : std::nullopt;
      if (!n || *n < 0) failAt(sc.lineNo, "bad element line (expected 'element NAME COUNT')");
      elements.push_back({printable(t[1]), uint64_t(*n), {}});
    } else if (t[0] == "property") {
      if (elements.empty()) failAt(sc.lineNo, "property before any element");
      Property p;
      if (t.size() == 5 && t[1] == "list") {
        p.list = true;
        p.countBytes = typeBytes(t[2]);
        p.itemBytes = typeBytes(t[3]);
        if (!p.countBytes || !p.itemBytes || p.countBytes > 4)
          failAt(sc.lineNo, "bad list property types " + quoted(t[2]) + " " + quoted(t[3]));
        p.name = printable(t[4]);
      } else if (t.size() == 3) {
        p.bytes = typeBytes(t[1]);
        if (!p.bytes) failAt(sc.lineNo, "unknown property type " + quoted(t[1]));
        p.name = printable(t[2]);
      } else {
        failAt(sc.lineNo, "bad property line");
      }
      elements.back().props.push_back(p);
    } else if (t[0] == "end_header") {
      ended = true;
      break;
    } else {
      failAt(sc.lineNo, "unknown PLY header keyword " + quoted(t[0]));
    }
  }
  if (!ended) fail("truncated PLY header (no end_header)");
  if (format.empty()) fail("PLY header has no format line");
  Declared declared;
  for (const Element& e : elements) {
    if (e.name == "vertex") declared.vertices = e.count;
    if (e.name == "face") declared.faces = e.count;
  }
  if (!declared.vertices) fail("PLY file has no vertex element");

  if (format == "ascii") {
    for (const Element& e : elements)
      for (uint64_t i = 0; i < e.count; ++i) {
        do {
          if (!sc.next(line))
            fail("truncated: file ends after " + std::to_string(i) + " of " + std::to_string(e.count) + " " + e.name +
                 " records");
        } while (tokens(line).empty());
        auto t = tokens(line);
        size_t k = 0;
        for (const Property& p : e.props) {
          if (k >= t.size()) failAt(sc.lineNo, e.name + ": too few values (missing '" + p.name + "')");
          if (p.list) {
            auto n = parseInt(t[k]);
            if (!n || *n < 0) failAt(sc.lineNo, e.name + ": bad list length " + quoted(t[k]));
            if (k + 1 + size_t(*n) > t.size())
              failAt(sc.lineNo, e.name + ": list '" + p.name + "' declares " + std::to_string(*n) + " items but has " +
                                    std::to_string(t.size() - k - 1));
            if (e.name == "face" && *n < 3) failAt(sc.lineNo, "face with " + std::to_string(*n) + " vertices (need at least 3)");
            expectReals(t, k + 1, size_t(*n), sc.lineNo, (e.name + " " + p.name).c_str());
            k += 1 + size_t(*n);
          } else {
            expectReals(t, k, 1, sc.lineNo, (e.name + " " + p.name).c_str());
            ++k;
          }
        }
      }
    return declared;
  }

  // Binary: walk the records without decoding values (NaN/range are checked after OpenMesh).
  const bool big = format == "binary_big_endian";
  auto readCount = [&](size_t at, int bytes) -> uint64_t {
    uint8_t b[4] = {0, 0, 0, 0};
    std::memcpy(b, text.data() + at, bytes);
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= uint64_t(big ? b[bytes - 1 - i] : b[i]) << (8 * i);
    return v;  // read unsigned: a negative signed count becomes huge and fails the size check
  };
  size_t at = sc.pos;
  for (const Element& e : elements) {
    bool allScalar = std::all_of(e.props.begin(), e.props.end(), [](const Property& p) { return !p.list; });
    if (allScalar) {
      uint64_t stride = 0;
      for (const Property& p : e.props) stride += p.bytes;
      if (stride != 0 && e.count > (text.size() - at) / stride)
        fail("truncated: binary data too short for " + std::to_string(e.count) + " " + e.name + " records");
      at += size_t(e.count * stride);
      continue;
    }
    for (uint64_t i = 0; i < e.count; ++i)
      for (const Property& p : e.props) {
        if (!p.list) {
          if (text.size() - at < size_t(p.bytes)) fail("truncated: binary data ends inside " + e.name + " " + std::to_string(i));
          at += p.bytes;
          continue;
        }
        if (text.size() - at < size_t(p.countBytes)) fail("truncated: binary data ends inside " + e.name + " " + std::to_string(i));
        const uint64_t n = readCount(at, p.countBytes);
        at += p.countBytes;
        if (n > (text.size() - at) / p.itemBytes)
          fail("truncated or corrupt: " + e.name + " " + std::to_string(i) + " declares a list of " + std::to_string(n) +
               " items past the end of the file");
        if (e.name == "face" && n < 3) fail("face " + std::to_string(i) + " has " + std::to_string(n) + " vertices (need at least 3)");
        at += size_t(n) * p.itemBytes;
      }
  }
  return declared;
}

// ---- OpenMesh -> triangle soup ----------------------------------------------------------------------

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
  std::vector<glm::vec3> positions, normals;
  std::vector<glm::vec2> uvs;
  std::vector<uint8_t> hasNormal, hasUv;
  std::vector<uint32_t> faceStart{0};  // polygon p = faceIndices[faceStart[p] .. faceStart[p+1])
  std::vector<int> faceIndices;
  std::string firstError;

  VertexHandle add_vertex(const Vec3f& p) override { return addVertex(glm::vec3(p[0], p[1], p[2])); }
  VertexHandle add_vertex(const Vec3d& p) override { return addVertex(glm::vec3(glm::dvec3(p[0], p[1], p[2]))); }
  VertexHandle add_vertex() override { return addVertex(glm::vec3(0.0f)); }
  HalfedgeHandle add_edge(VertexHandle, VertexHandle) override { return error("half-edge input is not supported"), HalfedgeHandle(); }
  FaceHandle add_face(const VHandles& vs) override {
    if (vs.size() < 3) return error("face with fewer than 3 vertices"), FaceHandle();
    for (VertexHandle v : vs) faceIndices.push_back(v.idx());
    faceStart.push_back(uint32_t(faceIndices.size()));
    return FaceHandle(int(faceStart.size() - 2));
  }
  FaceHandle add_face(HalfedgeHandle) override { return error("half-edge input is not supported"), FaceHandle(); }
  void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<Vec2f>&) override {}
  void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<Vec3f>&) override {}
  void set_face_texindex(FaceHandle, int) override {}
  void set_point(VertexHandle v, const Vec3f& p) override {
    if (valid(v)) positions[v.idx()] = glm::vec3(p[0], p[1], p[2]);
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
    uvs[v.idx()] = glm::vec2(t[0], t[1]);
    hasUv[v.idx()] = 1;
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
  // Readers pass header counts straight to reserve(); the pre-check has bounded them, but cap anyway.
  void reserve(unsigned nV, unsigned, unsigned nF) override {
    positions.reserve(std::min(nV, 1u << 24));
    faceIndices.reserve(std::min(uint64_t(nF) * 3, uint64_t(1) << 26));
  }
  size_t n_vertices() const override { return positions.size(); }
  size_t n_faces() const override { return faceStart.size() - 1; }
  size_t n_edges() const override { return 0; }

 private:
  bool valid(VertexHandle v) const { return v.idx() >= 0 && size_t(v.idx()) < positions.size(); }
  void error(const char* what) {
    if (firstError.empty()) firstError = what;
  }
  VertexHandle addVertex(glm::vec3 p) {
    positions.push_back(p);
    normals.emplace_back(0.0f);
    uvs.emplace_back(0.0f);
    hasNormal.push_back(0);
    hasUv.push_back(0);
    return VertexHandle(int(positions.size() - 1));
  }
  void setNormal(VertexHandle v, glm::vec3 n) {
    if (!valid(v)) return;
    normals[v.idx()] = n;
    hasNormal[v.idx()] = 1;
  }
};

// OpenMesh's readers keep state in a process-wide singleton and print to a global stream.
std::mutex& openMeshMutex() {
  static std::mutex m;
  return m;
}

// Runs OpenMesh on the file with its error stream captured; returns (ok, first captured line).
std::pair<bool, std::string> readWithOpenMesh(const fs::path& path, SoupImporter& importer, bool binaryHint) {
  std::lock_guard<std::mutex> lock(openMeshMutex());
  std::ostringstream captured;
  OpenMesh::mostream& err = ::omerr();
  OpenMesh::mostream& log = ::omlog();
  const bool errWasOnCerr = err.disconnect(std::cerr);
  err.connect(captured);
  const bool logWasEnabled = log.is_enabled();
  log.disable();
  OpenMesh::IO::Options opt(OpenMesh::IO::Options::VertexNormal | OpenMesh::IO::Options::VertexTexCoord);
  if (binaryHint) opt += OpenMesh::IO::Options::Binary;
  bool ok = false;
  try {
    ok = OpenMesh::IO::IOManager().read(path.string(), importer, opt);
  } catch (...) {
    ok = false;
  }
  err.flush();
  err.disconnect(captured);
  if (errWasOnCerr) err.connect(std::cerr);
  if (logWasEnabled) log.enable();
  std::string msg = captured.str();
  const size_t nl = msg.find('\n');
  if (nl != std::string::npos) msg.resize(nl);
  return {ok, msg};
}

template <class V>
bool allFinite(const std::vector<V>& values) {
  return std::all_of(values.begin(), values.end(), [](const V& v) {
    for (int i = 0; i < V::length(); ++i)
      if (!std::isfinite(v[i])) return false;
    return true;
  });
}

Mesh loadMeshImpl(const fs::path& path) {
  const std::string ext = lowerExtension(path);
  if (!isMeshFile(path))
    fail("unsupported mesh format '" + ext + "' (supported: .obj .off .ply .stl)");
  const std::string text = readWholeFile(path);
  if (text.empty()) fail("empty file");

  Declared declared;
  bool stlBinary = false;
  if (ext == ".off") declared = precheckOff(text);
  else if (ext == ".obj") declared = precheckObj(text);
  else if (ext == ".ply") declared = precheckPly(text);
  else declared = precheckStl(text, stlBinary);

  SoupImporter soup;
  auto [ok, omMessage] = readWithOpenMesh(path, soup, stlBinary);
  if (!ok) fail("OpenMesh cannot read the file" + (omMessage.empty() ? std::string() : " (" + omMessage + ")"));
  if (!soup.firstError.empty()) fail(soup.firstError);
  const size_t nV = soup.positions.size(), nF = soup.n_faces();
  if (declared.vertices && nV != *declared.vertices)
    fail("truncated or malformed: declares " + std::to_string(*declared.vertices) + " vertices, read " + std::to_string(nV));
  if (declared.faces && nF != *declared.faces)
    fail("truncated or malformed: declares " + std::to_string(*declared.faces) + " faces, read " + std::to_string(nF));
  if (nF == 0) fail("mesh has no faces");
  if (!allFinite(soup.positions)) fail("vertex position is NaN or infinite");

  Mesh mesh;
  mesh.name = path.string();
  mesh.positions = std::move(soup.positions);
  for (size_t f = 0; f < nF; ++f) {
    const int* idx = soup.faceIndices.data() + soup.faceStart[f];
    const size_t n = soup.faceStart[f + 1] - soup.faceStart[f];
    for (size_t k = 0; k < n; ++k)
      if (idx[k] < 0 || size_t(idx[k]) >= nV)
        fail("face " + std::to_string(f) + " references vertex " + std::to_string(idx[k]) + " (file has " +
             std::to_string(nV) + " vertices)");
    for (size_t k = 1; k + 1 < n; ++k) mesh.triangles.emplace_back(idx[0], idx[k], idx[k + 1]);
  }

  // Attributes count as present when every vertex a triangle uses has one; vertices no triangle uses
  // (files have them) get a placeholder so the arrays stay parallel to the positions.
  std::vector<uint8_t> used(nV, 0);
  for (const glm::uvec3& t : mesh.triangles) used[t.x] = used[t.y] = used[t.z] = 1;
  auto everyUsed = [&](const std::vector<uint8_t>& has) {
    for (size_t v = 0; v < nV; ++v)
      if (used[v] && !has[v]) return false;
    return true;
  };
  if (everyUsed(soup.hasNormal)) {
    for (size_t v = 0; v < nV; ++v)
      if (!used[v]) soup.normals[v] = glm::vec3(0.0f, 0.0f, 1.0f);
    if (!allFinite(soup.normals)) fail("vertex normal is NaN or infinite");
    // A zero normal carries no direction: then the file's normals are unusable and we drop them all
    // (the renderer falls back to geometric normals). 1e-12 on the squared length: far below any
    // normal a file would store on purpose, far above float underflow.
    const bool usable = std::all_of(soup.normals.begin(), soup.normals.end(),
                                    [](const glm::vec3& n) { return glm::dot(n, n) > 1e-12f; });
    if (usable) {
      mesh.normals = std::move(soup.normals);
      for (glm::vec3& n : mesh.normals) n = glm::normalize(n);
    }
  }
  if (everyUsed(soup.hasUv)) {
    if (!allFinite(soup.uvs)) fail("texture coordinate is NaN or infinite");
    mesh.uvs = std::move(soup.uvs);  // unused vertices keep (0, 0)
  }
  return mesh;
}

std::string uniqueSuffix() {
  static std::atomic<unsigned> counter{0};
  return ".tmp" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
}

}  // namespace

const std::vector<std::string>& meshExtensions() {
  static const std::vector<std::string> exts{".obj", ".off", ".ply", ".stl"};
  return exts;
}

bool isMeshFile(const fs::path& path) {
  const std::string ext = lowerExtension(path);
  const auto& exts = meshExtensions();
  return std::find(exts.begin(), exts.end(), ext) != exts.end();
}

Mesh loadMesh(const fs::path& path) {
  try {
    return loadMeshImpl(path);
  } catch (const MeshFileError& e) {
    const std::string where = e.line ? path.string() + ":" + std::to_string(e.line) : path.string();
    throw InputError(where + ": " + e.message);
  } catch (const std::bad_alloc&) {
    throw InputError(path.string() + ": out of memory while reading the mesh");
  }
}

void saveMeshObj(const fs::path& path, const Mesh& mesh) {
  std::error_code ec;
  if (!path.parent_path().empty()) fs::create_directories(path.parent_path(), ec);
  fs::path tmp = path;
  tmp += uniqueSuffix();
  {
    std::ofstream out(tmp);
    if (!out) throw InputError(path.string() + ": cannot write file");
    out.precision(9);  // float round-trips exactly with 9 significant digits
    out << "# " << mesh.positions.size() << " vertices, " << mesh.triangles.size() << " triangles\n";
    for (const glm::vec3& p : mesh.positions) out << "v " << p.x << ' ' << p.y << ' ' << p.z << '\n';
    for (const glm::vec2& t : mesh.uvs) out << "vt " << t.x << ' ' << t.y << '\n';
    for (const glm::vec3& n : mesh.normals) out << "vn " << n.x << ' ' << n.y << ' ' << n.z << '\n';
    const bool hasT = !mesh.uvs.empty(), hasN = !mesh.normals.empty();
    for (const glm::uvec3& t : mesh.triangles) {
      out << 'f';
      for (int k = 0; k < 3; ++k) {
        const unsigned i = t[k] + 1;
        out << ' ' << i;
        if (hasT && hasN) out << '/' << i << '/' << i;
        else if (hasT) out << '/' << i;
        else if (hasN) out << "//" << i;
      }
      out << '\n';
    }
    out.flush();
    if (!out) {
      fs::remove(tmp, ec);
      throw InputError(path.string() + ": cannot write file");
    }
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw InputError(path.string() + ": cannot rename temporary file into place (" + ec.message() + ")");
  }
}

}  // namespace bvhlab
