// PLY (ASCII and binary): our structural pass (mesh_io_detail.hpp) — the header, then ASCII lines or
// binary records that fit the declared elements exactly. The vertex element's x, y, z are decoded in
// double (a `property double x` keeps all its digits; float/int types convert exactly).
#include <algorithm>
#include <cstring>

#include "datasets/mesh_io_detail.hpp"

namespace bvhlab::meshio {
namespace {

enum class Kind { None, Int, Uint, Float };
struct Type {
  Kind kind = Kind::None;
  int bytes = 0;
};
Type typeOf(std::string_view t) {
  if (t == "char" || t == "int8") return {Kind::Int, 1};
  if (t == "uchar" || t == "uint8") return {Kind::Uint, 1};
  if (t == "short" || t == "int16") return {Kind::Int, 2};
  if (t == "ushort" || t == "uint16") return {Kind::Uint, 2};
  if (t == "int" || t == "int32") return {Kind::Int, 4};
  if (t == "uint" || t == "uint32") return {Kind::Uint, 4};
  if (t == "float" || t == "float32") return {Kind::Float, 4};
  if (t == "double" || t == "float64") return {Kind::Float, 8};
  return {};
}

struct Property {
  bool list = false;
  Type count, item, scalar;
  std::string name;
  int axis = -1;  // vertex x, y, z -> 0, 1, 2
};
struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> props;
};

// The raw bytes of one binary value, in file order, as an unsigned integer of `bytes` bytes.
uint64_t rawBits(const char* at, int bytes, bool big) {
  uint8_t b[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  std::memcpy(b, at, size_t(bytes));
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= uint64_t(big ? b[bytes - 1 - i] : b[i]) << (8 * i);
  return v;
}

double decode(const char* at, Type t, bool big) {
  const uint64_t bits = rawBits(at, t.bytes, big);
  switch (t.kind) {
    case Kind::Float:
      if (t.bytes == 4) {
        const uint32_t b32 = uint32_t(bits);
        float f;
        std::memcpy(&f, &b32, 4);
        return f;
      } else {
        double d;
        std::memcpy(&d, &bits, 8);
        return d;
      }
    case Kind::Int: {
      const int shift = 64 - 8 * t.bytes;  // sign-extend
      return double(int64_t(bits << shift) >> shift);
    }
    case Kind::Uint: return double(bits);
    case Kind::None: break;
  }
  return 0.0;
}

}  // namespace

Scanned scanPly(std::string_view text) {
  LineScanner sc{text};
  std::string_view line;
  sc.next(line);
  if (tokens(line).empty() || tokens(line)[0] != "ply") failAt(1, "not a PLY file (no 'ply' magic)");
  std::string format;
  std::vector<Element> elements;
  bool ended = false;
  while (sc.next(line)) {
    // The header is text: a control character (a NUL, say) means a damaged file, and OpenMesh's PLY
    // probe loops forever on some (a NUL in the format line: tests/fuzz/regressions/ply/).
    for (char c : line)
      if ((unsigned char)c < 0x20 && c != '\t' && c != '\r') failAt(sc.lineNo, "control character in the PLY header");
    auto t = tokens(line);
    if (t.empty() || t[0] == "comment" || t[0] == "obj_info") continue;
    if (t[0] == "format") {
      if (t.size() != 3 || t[2] != "1.0")
        failAt(sc.lineNo, "bad format line (expected 'format ascii|binary_little_endian|binary_big_endian 1.0')");
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
        p.count = typeOf(t[2]);
        p.item = typeOf(t[3]);
        if (p.count.kind == Kind::None || p.count.kind == Kind::Float || p.item.kind == Kind::None || p.count.bytes > 4)
          failAt(sc.lineNo, "bad list property types " + quoted(t[2]) + " " + quoted(t[3]));
        p.name = printable(t[4]);
      } else if (t.size() == 3) {
        p.scalar = typeOf(t[1]);
        if (p.scalar.kind == Kind::None) failAt(sc.lineNo, "unknown property type " + quoted(t[1]));
        p.name = printable(t[2]);
        if (elements.back().name == "vertex" && p.name.size() == 1 && p.name[0] >= 'x' && p.name[0] <= 'z')
          p.axis = p.name[0] - 'x';
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
  Scanned out;
  for (const Element& e : elements) {
    if (e.name == "vertex") {
      if (out.vertices) fail("PLY file has two vertex elements");
      out.vertices = e.count;
      bool axes[3] = {false, false, false};
      for (const Property& p : e.props)
        if (p.axis >= 0) axes[p.axis] = true;
      if (!(axes[0] && axes[1] && axes[2])) fail("PLY vertex element lacks one of the properties x, y, z");
    }
    if (e.name == "face") out.faces = e.count;
  }
  if (!out.vertices) fail("PLY file has no vertex element");

  if (format == "ascii") {
    std::vector<double> value;
    for (const Element& e : elements)
      for (uint64_t i = 0; i < e.count; ++i) {
        do {
          if (!sc.next(line))
            fail("truncated: file ends after " + std::to_string(i) + " of " + std::to_string(e.count) + " " + e.name +
                 " records");
        } while (tokens(line).empty());
        auto t = tokens(line);
        size_t k = 0;
        glm::dvec3 position(0.0);
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
            value.clear();
            expectReals(t, k, 1, sc.lineNo, (e.name + " " + p.name).c_str(), &value);
            if (p.axis >= 0) position[p.axis] = value[0];
            ++k;
          }
        }
        // OpenMesh reads an ASCII body as one stream of values, not line by line: an extra value shifts
        // every later record (fuzz_ply: a face line with one value too many made the next face's list
        // length read "-1", and OpenMesh looped pushing 2^32 vertex handles).
        if (k != t.size())
          failAt(sc.lineNo, e.name + ": " + std::to_string(t.size() - k) + " value(s) more than its properties declare");
        if (e.name == "vertex") out.positions.push_back(position);
      }
    return out;
  }

  // Binary: walk the records; decode vertex positions and list lengths (other values are checked
  // after OpenMesh). Every count is compared with the bytes left before anything is reserved.
  const bool big = format == "binary_big_endian";
  size_t at = sc.pos;
  for (const Element& e : elements) {
    const bool allScalar = std::all_of(e.props.begin(), e.props.end(), [](const Property& p) { return !p.list; });
    if (allScalar) {
      uint64_t stride = 0;
      for (const Property& p : e.props) stride += uint64_t(p.scalar.bytes);
      // Resource limit: a record of `stride` bytes each, so a claimed count the file cannot hold (e.g.
      // 'element vertex 2147483648' in a small file) is refused here, before anything is allocated.
      if (stride != 0 && e.count > (text.size() - at) / stride)
        fail("truncated: binary data too short for " + std::to_string(e.count) + " " + e.name + " records (" +
             std::to_string(stride) + " bytes each, " + std::to_string(text.size() - at) + " bytes left)");
      if (e.name == "vertex") {
        out.positions.reserve(size_t(e.count));
        for (uint64_t i = 0; i < e.count; ++i) {
          glm::dvec3 position(0.0);
          for (const Property& p : e.props) {
            if (p.axis >= 0) position[p.axis] = decode(text.data() + at, p.scalar, big);
            at += size_t(p.scalar.bytes);
          }
          out.positions.push_back(position);
        }
      } else {
        at += size_t(e.count * stride);
      }
      continue;
    }
    if (e.name == "vertex") fail("PLY vertex element with a list property is not supported");
    for (uint64_t i = 0; i < e.count; ++i)
      for (const Property& p : e.props) {
        if (!p.list) {
          if (text.size() - at < size_t(p.scalar.bytes)) fail("truncated: binary data ends inside " + e.name + " " + std::to_string(i));
          at += size_t(p.scalar.bytes);
          continue;
        }
        if (text.size() - at < size_t(p.count.bytes)) fail("truncated: binary data ends inside " + e.name + " " + std::to_string(i));
        // Read unsigned: a negative signed count becomes huge and fails the size check.
        const uint64_t n = rawBits(text.data() + at, p.count.bytes, big);
        at += size_t(p.count.bytes);
        if (n > (text.size() - at) / size_t(p.item.bytes))
          fail("truncated or corrupt: " + e.name + " " + std::to_string(i) + " declares a list of " + std::to_string(n) +
               " items past the end of the file");
        if (e.name == "face" && n < 3) fail("face " + std::to_string(i) + " has " + std::to_string(n) + " vertices (need at least 3)");
        at += size_t(n) * size_t(p.item.bytes);
      }
  }
  return out;
}

}  // namespace bvhlab::meshio
