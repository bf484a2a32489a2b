// What assimp 5.2.5 must not see (mesh_io_detail.hpp: checkBeforeAssimp): our own passes over COLLADA
// and AC3D files, and the content checks that keep a file away from a reader other than its
// extension's. Each check here is a crash, an unbounded allocation or a memory error that fuzzing
// found inside libassimp (tests/fuzz/README.md lists them; each has a regression file under
// tests/fuzz/regressions/); the file is refused with a named error before assimp reads it.
#include <nlohmann/json.hpp>
#include <pugixml.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "datasets/mesh_io_detail.hpp"

namespace bvhlab::meshio {
namespace fs = std::filesystem;

namespace {

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return std::move(text).str();
}

// Most nodes a COLLADA file may expand to. assimp copies a node once per <instance_node> that names
// it, recursively, before we see the scene, so a chain of nodes each instancing the next twice doubles
// per link: measured with assimp 5.2.5 (Release, idle), 16 links gave 65,537 nodes, 87 MB, 0.8 s; 18
// links 262,145 nodes, 317 MB, 2.2 s (~1.2 KB per aiNode); 30 links would need over a terabyte. At
// 2^17 fuzz_dae found a file assimp took 5.3 s to expand (over libFuzzer's 10 s under ASan). 2^16 is
// far above the node count of any model this testbed renders (CG-57.ac: 443 objects).
constexpr uint64_t kMaxColladaNodes = uint64_t(1) << 16;

// A COLLADA count, stride or offset attribute against the file: each counted value, primitive or
// index takes at least one byte of it. assimp trusts them: measured, <polylist count="2000000000"> in a
// 2 KB file reserved past 2 GB (an OOM under ASan), and <accessor stride="2000000000"> made it read out
// of bounds (SIGSEGV). An accessor reads offset + count * stride values of its array.
void checkColladaCounts(const pugi::xml_node& element, size_t fileBytes) {
  uint64_t product = 1, offset = 0;
  const std::string_view name = element.name();
  const bool accessor = name == "accessor";
  // An array without its count: assimp 5.2.5 writes its values to an array it never sized (SIGSEGV,
  // found by fuzz_dae).
  if (name.size() > 6 && name.substr(name.size() - 6) == "_array" && !element.attribute("count"))
    fail("COLLADA <" + std::string(name) + ">: no count attribute");
  for (const char* key : {"count", "stride", "offset"}) {
    const pugi::xml_attribute a = element.attribute(key);
    if (!a) continue;
    const std::string_view text = a.value();
    uint64_t v = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || end != text.data() + text.size() || v > fileBytes)
      fail("COLLADA <" + std::string(element.name()) + " " + key + "=\"" + std::string(text) +
           "\">: expected a count no larger than the file (" + std::to_string(fileBytes) + " bytes)");
    if (std::string_view(key) == "offset") offset = v;
    else product *= std::max<uint64_t>(v, 1);  // both <= fileBytes: no overflow
  }
  if (accessor && offset + product > fileBytes)
    fail("COLLADA <accessor>: offset + count * stride = " + std::to_string(offset + product) +
         " values, more than the file could hold (" + std::to_string(fileBytes) + " bytes)");
}

// A COLLADA index list (<p>, <vcount>, <v>, <h>, <int_array>) holds integers only. fuzz_dae found
// assimp 5.2.5 allocating without bound (std::bad_alloc after gigabytes) on <p>0"1 2</p>: its index
// reader stops at a character that is not a digit without moving past it.
void checkColladaIntegers(const pugi::xml_node& element) {
  const std::string_view name = element.name();
  if (name != "p" && name != "vcount" && name != "v" && name != "h" && name != "int_array") return;
  for (const char c : std::string_view(element.child_value()))
    if (!std::isdigit(uint8_t(c)) && !std::isspace(uint8_t(c)) && c != '-' && c != '+')
      fail("COLLADA <" + std::string(name) + ">: expected integers, found '" + std::string(1, c) + "'");
}

// The node graph of a COLLADA document before assimp expands it: refuses an <instance_node> cycle
// (assimp recurses until its stack overflows: measured, a SIGSEGV on a 1 KB file) and a graph that
// expands to more than kMaxColladaNodes nodes. A reference is resolved as assimp resolves it: by id,
// else by name; one that names no node is skipped (assimp warns and skips it too). An id or name that
// several nodes share (COLLADA forbids it; fuzz_dae found assimp taking another one than the first)
// counts as all of them, so the check over-estimates and never misses. Every element's
// counts are checked on the way (checkColladaCounts).
void checkCollada(const std::string& path) {
  const std::string bytes = readAll(path);
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed = doc.load_buffer(bytes.data(), bytes.size());
  if (!parsed)
    fail("not a well-formed COLLADA (XML) file: " + std::string(parsed.description()) + " at byte " +
         std::to_string(parsed.offset));

  // Every <node>, in document order, without recursion (a file may nest nodes deeply).
  std::vector<pugi::xml_node> nodes;
  std::unordered_map<std::string, std::vector<size_t>> byId, byName;
  std::vector<pugi::xml_node> scenes, accessors;
  std::unordered_map<std::string, uint64_t> arrayCount;
  for (pugi::xml_node n = doc.first_child(); n;) {
    if (n.type() == pugi::node_element) {
      checkColladaCounts(n, bytes.size());
      checkColladaIntegers(n);
      const std::string name = n.name();
      if (name.size() > 6 && name.ends_with("_array") && *n.attribute("id").value())
        arrayCount[n.attribute("id").value()] = n.attribute("count").as_ullong();
      if (name == "accessor") accessors.push_back(n);
      if (name == "node") {
        byId[n.attribute("id").value()].push_back(nodes.size());
        byName[n.attribute("name").value()].push_back(nodes.size());
        nodes.push_back(n);
      } else if (name == "visual_scene") {
        scenes.push_back(n);
      }
    }
    if (n.first_child()) {
      n = n.first_child();
    } else {
      while (n && !n.next_sibling()) n = n.parent();
      if (n) n = n.next_sibling();
    }
  }
  // An accessor reads offset + count * stride values of its array: within the array's count (fuzz_dae
  // and fuzz_gltf: count="0" with an accessor of 3 made assimp 5.2.5 read out of bounds, SIGSEGV).
  for (const pugi::xml_node& a : accessors) {
    const std::string_view source = a.attribute("source").value();
    const auto it = source.size() > 1 ? arrayCount.find(std::string(source.substr(1))) : arrayCount.end();
    if (it == arrayCount.end()) continue;  // counts bounded by the file already (checkColladaCounts)
    const uint64_t reads = a.attribute("offset").as_ullong() +
                           a.attribute("count").as_ullong() * std::max<uint64_t>(a.attribute("stride").as_ullong(), 1);
    if (reads > it->second)
      fail("COLLADA <accessor source=\"" + std::string(source) + "\"> reads " + std::to_string(reads) +
           " values of an array of " + std::to_string(it->second));
  }
  byId.erase("");
  byName.erase("");
  std::unordered_map<const void*, size_t> indexOf;
  for (size_t i = 0; i < nodes.size(); ++i) indexOf.emplace(nodes[i].internal_object(), i);

  // Nodes a node holds: its child <node>s and the nodes its <instance_node>s name.
  auto successors = [&](size_t i) {
    std::vector<size_t> out;
    for (pugi::xml_node c : nodes[i].children()) {
      const std::string name = c.name();
      if (name == "node") {
        out.push_back(indexOf.at(c.internal_object()));
      } else if (name == "instance_node") {
        const std::string url = c.attribute("url").value();
        if (url.size() < 2 || url[0] != '#') continue;  // assimp refuses these itself
        const std::string ref = url.substr(1);
        if (auto it = byId.find(ref); it != byId.end()) out.insert(out.end(), it->second.begin(), it->second.end());
        else if (auto jt = byName.find(ref); jt != byName.end()) out.insert(out.end(), jt->second.begin(), jt->second.end());
      }
    }
    return out;
  };

  // Expanded size of every node (itself plus everything it holds, instances copied), depth first
  // with an explicit stack; sums saturate just above the limit.
  const uint64_t over = kMaxColladaNodes + 1;
  auto add = [&](uint64_t a, uint64_t b) { return std::min(over, a + b); };
  enum State : uint8_t { kNew, kOpen, kDone };
  std::vector<State> state(nodes.size(), kNew);
  std::vector<uint64_t> size(nodes.size(), 0);
  for (size_t root = 0; root < nodes.size(); ++root) {
    if (state[root] != kNew) continue;
    std::vector<std::pair<size_t, std::vector<size_t>>> stack;
    stack.emplace_back(root, successors(root));
    state[root] = kOpen;
    while (!stack.empty()) {
      auto& [i, next] = stack.back();
      if (next.empty()) {
        uint64_t total = 1;
        for (size_t j : successors(i)) total = add(total, size[j]);
        size[i] = total;
        state[i] = kDone;
        stack.pop_back();
        continue;
      }
      const size_t j = next.back();
      next.pop_back();
      if (state[j] == kOpen)
        fail("COLLADA <instance_node> cycle: node '" + std::string(nodes[j].attribute("id").value()) +
             "' instances itself through its own subtree");
      if (state[j] == kNew) {
        state[j] = kOpen;
        stack.emplace_back(j, successors(j));
      }
    }
  }
  for (const pugi::xml_node& scene : scenes) {
    uint64_t total = 1;
    for (pugi::xml_node c : scene.children("node")) total = add(total, size[indexOf.at(c.internal_object())]);
    if (total > kMaxColladaNodes)
      fail("COLLADA visual scene '" + std::string(scene.attribute("id").value()) + "' expands to more than " +
           std::to_string(kMaxColladaNodes) + " nodes through <instance_node> (kMaxColladaNodes)");
  }
}

// AC3D surface types (the low four bits of a SURF's flags; AC3D file format, "SURF"): a polygon,
// a closed line, an open line.
enum class AcSurface { kPolygon = 0, kClosedLine = 1, kOpenLine = 2 };

// A SURF's flags as assimp reads them (C-style: "0x" hex, a leading 0 octal, else decimal).
std::optional<unsigned long long> acFlags(std::string_view s) {
  int base = 10;
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) base = 16, s.remove_prefix(2);
  else if (s.size() > 1 && s[0] == '0') base = 8, s.remove_prefix(1);
  unsigned long long v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v, base);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

}  // namespace

void checkAc3d(std::string_view text) {
  // Every line is checked as a keyword line, also the rows a count claims: assimp's reading of a
  // malformed file can take any line for a keyword line (fuzz_ac: 'kids 0666666666666' as the third
  // row of a 'refs 4' that assimp never read as one; assimp reserved 212 GB), so no line is skipped.
  // A count is compared with the non-blank lines after it, since assimp skips blank lines: 'refs 1'
  // followed by a blank line and the end of the file gives assimp no row.
  std::vector<size_t> nonBlankAfter;  // [L]: non-blank lines among lines L+1.. (L 1-based)
  {
    std::vector<bool> blank;
    std::string_view line;
    for (LineScanner all{text}; all.next(line);) blank.push_back(line.find_first_not_of(" \t") == std::string_view::npos);
    nonBlankAfter.assign(blank.size() + 1, 0);
    // blank[k] is line k + 1, so the suffix sum from k counts the lines after line k.
    for (size_t k = blank.size(); k-- > 0;) nonBlankAfter[k] = nonBlankAfter[k + 1] + (blank[k] ? 0 : 1);
  }
  std::string_view line;
  size_t materials = 0;
  // The surface being read (assimp's grammar: SURF, then 'mat' and 'refs' lines until any other line).
  struct Open {
    size_t line = 0;  // 0: none
    AcSurface type = AcSurface::kPolygon;
    long long refs = -1;  // -1: no refs line yet
  } surf;
  auto close = [&] {
    if (!surf.line) return;
    if (surf.refs < 0) failAt(surf.line, "SURF without a 'refs' line");
    // An open line SURF without refs made assimp 5.2.5 write past the face array it had sized (fuzz_ac:
    // an ASan bad-free; valgrind on assimp alone: invalid writes of 4 and 8 bytes just past a 24-byte
    // block; its line code counts refs - 1 segments). A line of either kind needs two points to be a
    // segment, so fewer are refused for both.
    if (surf.type != AcSurface::kPolygon && surf.refs < 2)
      failAt(surf.line, "a line SURF with " + std::to_string(surf.refs) + " refs (a line needs at least 2)");
    surf.line = 0;
  };
  LineScanner lines{text};
  while (lines.next(line)) {
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string_view::npos) continue;  // assimp skips blank lines
    // A surface ends at the first line that is neither 'mat' nor 'refs', whatever it holds.
    const bool keyword = std::isalpha(uint8_t(line[first]));
    const std::vector<std::string_view> toks = keyword ? tokens(line) : std::vector<std::string_view>{};
    const std::string_view key = keyword ? toks[0] : std::string_view();
    if (key != "mat" && key != "refs") close();
    // Rows of vertices start with a number: only keyword lines matter from here.
    if (!keyword) continue;
    if (key == "MATERIAL") {
      ++materials;
      continue;
    }
    if (key == "SURF") {
      const std::optional<unsigned long long> flags = toks.size() > 1 ? acFlags(toks[1]) : std::nullopt;
      if (!flags) failAt(lines.lineNo, "SURF: expected flags (e.g. 0x10), got " + quoted(toks.size() > 1 ? toks[1] : ""));
      const unsigned type = unsigned(*flags & 0xF);
      if (type > unsigned(AcSurface::kOpenLine))
        failAt(lines.lineNo, "SURF: unknown surface type " + std::to_string(type) + " (0 polygon, 1 closed line, 2 line)");
      surf = {lines.lineNo, AcSurface(type), -1};
      continue;
    }
    if (key != "numvert" && key != "numsurf" && key != "refs" && key != "kids" && key != "mat") continue;
    // assimp reads a missing count from the next line (its number parser skips the line break).
    const std::optional<long long> n = toks.size() > 1 ? parseInt(toks[1]) : std::nullopt;
    if (!n || *n < 0) failAt(lines.lineNo, std::string(key) + ": expected a count, got " + quoted(toks.size() > 1 ? toks[1] : ""));
    if (key == "mat") {
      // assimp logs an out-of-range index and counts the surface's faces under material 0, but fills
      // faces by the index the file gives: a face stays empty (measured: its own validation then fails,
      // "mFaces[1].mIndices is nullptr"). Refused here with the line instead.
      if (size_t(*n) >= materials)
        failAt(lines.lineNo, "mat " + std::to_string(*n) + ": the file defines " + std::to_string(materials) +
                                 " MATERIAL(s) before this line");
      continue;
    }
    // assimp loops and allocates per claimed item (measured: 'numsurf 1e8' in a 1 KB file held 3.1 GB
    // for 5.8 s). Every counted item takes at least one line.
    const size_t left = nonBlankAfter[lines.lineNo];
    if (size_t(*n) > left)
      failAt(lines.lineNo, std::string(key) + " " + std::to_string(*n) + " but only " + std::to_string(left) +
                               " non-blank lines follow (truncated or malformed)");
    if (key == "refs" && surf.line) surf.refs = std::max<long long>(surf.refs, 0) + *n;
  }
  close();
}

// glTF 2.0 JSON as assimp's glTF 2 reader must accept it. Its CanRead (assimp 5.2.5) loads the
// document: when that throws, assimp offers the file to every other reader, and fuzz_glb found two of
// them reading past the buffer (ASan heap-buffer-overflow in strncmp inside libassimp). So the checks
// here are the conditions of that load: JSON (rapidjson stops at the first NUL of its buffer, so the
// text ends there), an object, and asset.version "2.x"; plus a nesting bound, since rapidjson parses
// recursively.
// Element `i` of an index accessor (componentType UNSIGNED_BYTE, SHORT or INT: glTF 2.0 spec, 3.7.2.1)
// when its bytes are at hand: the GLB's BIN chunk, or a buffer file beside the document; nullopt when
// they are not (a data: URI, a missing file) or the accessor does not cover element i. Any malformed
// member throws nlohmann's exception, which the caller reports.
std::optional<uint64_t> indexValue(const nlohmann::json& doc, const nlohmann::json& accessor, uint64_t i,
                                   const std::optional<std::string>& bin, const fs::path& folder) {
  const uint64_t componentType = accessor.at("componentType").get<uint64_t>();
  const uint64_t size = componentType == 5121 ? 1 : componentType == 5123 ? 2 : componentType == 5125 ? 4 : 0;
  if (size == 0 || i >= accessor.at("count").get<uint64_t>() || !accessor.contains("bufferView")) return std::nullopt;
  const nlohmann::json& view = doc.at("bufferViews").at(accessor.at("bufferView").get<size_t>());
  const nlohmann::json& buffer = doc.at("buffers").at(view.at("buffer").get<size_t>());
  const uint64_t stride = view.contains("byteStride") ? view.at("byteStride").get<uint64_t>() : size;
  const uint64_t at = view.value("byteOffset", uint64_t(0)) + accessor.value("byteOffset", uint64_t(0)) + i * stride;
  if (at + size > view.at("byteLength").get<uint64_t>() + view.value("byteOffset", uint64_t(0))) return std::nullopt;
  std::string bytes(size, '\0');
  if (!buffer.contains("uri")) {
    if (!bin || at + size > bin->size()) return std::nullopt;
    bytes = bin->substr(at, size);
  } else {
    const std::string uri = buffer.at("uri").get<std::string>();
    if (uri.rfind("data:", 0) == 0) return std::nullopt;
    std::ifstream in(folder / uri, std::ios::binary);
    if (!in.seekg(std::streamoff(at)) || !in.read(bytes.data(), std::streamsize(size))) return std::nullopt;
  }
  uint64_t v = 0;
  for (uint64_t k = size; k-- > 0;) v = v << 8 | uint8_t(bytes[k]);  // little-endian
  return v;
}

// What assimp 5.2.5 does with a primitive's mode (glTF 2.0 spec, 3.7.2.1: 0 points, 1 lines, 2 line
// loop, 3 line strip, 4 triangles, 5 triangle strip, 6 triangle fan), read here before it does:
// - strips and fans get count - 1 (line strip) or count - 2 faces in unsigned arithmetic, so fewer
//   vertices (or indices) than a segment or a triangle wrap to 2^32 faces (fuzz_glb: a fan without
//   attributes asked for 64 GB); a loop reads its indices 0 and 1 whatever its count;
// - a LINE_LOOP drops a segment with an index past the vertices, then closes the loop with the first
//   segment's first index: when that segment was dropped it reads through a null pointer (fuzz_glb,
//   SIGSEGV in plain assimp too). Its first two indices are read here (bvhlab skips lines anyway),
//   and an indexed loop whose indices cannot be read here is refused.
void checkPrimitives(const nlohmann::json& doc, const std::string& what, const std::optional<std::string>& bin,
                     const fs::path& folder) {
  if (!doc.contains("meshes")) return;
  const nlohmann::json& meshes = doc.at("meshes");
  for (size_t m = 0; m < meshes.size(); ++m) {
    const nlohmann::json& primitives = meshes.at(m).at("primitives");
    for (size_t p = 0; p < primitives.size(); ++p) {
      const nlohmann::json& prim = primitives.at(p);
      const uint64_t mode = prim.value("mode", uint64_t(4));
      const char* const names[] = {"", "", "LINE_LOOP", "LINE_STRIP", "", "TRIANGLE_STRIP", "TRIANGLE_FAN"};
      const uint64_t minimum = mode == 2 || mode == 3 ? 2 : mode == 5 || mode == 6 ? 3 : 0;
      if (minimum == 0) continue;
      const std::string where = what + ": meshes[" + std::to_string(m) + "].primitives[" + std::to_string(p) + "]";
      // Without POSITION assimp makes a mesh of 0 vertices (and drops every segment of a loop).
      const bool hasPosition = prim.contains("attributes") && prim.at("attributes").contains("POSITION");
      const uint64_t vertices =
          hasPosition ? doc.at("accessors").at(prim.at("attributes").at("POSITION").get<size_t>()).at("count").get<uint64_t>()
                      : 0;
      const bool indexed = prim.contains("indices");
      const uint64_t elements =
          indexed ? doc.at("accessors").at(prim.at("indices").get<size_t>()).at("count").get<uint64_t>() : vertices;
      if (elements < minimum)
        fail(where + ": a " + names[mode] + " of " + std::to_string(elements) + (indexed ? " indices" : " vertices") +
             " (needs " + std::to_string(minimum) + ")");
      if (mode != 2 || !indexed) continue;
      const nlohmann::json& indices = doc.at("accessors").at(prim.at("indices").get<size_t>());
      for (uint64_t i = 0; i < 2; ++i) {
        const std::optional<uint64_t> v = indexValue(doc, indices, i, bin, folder);
        if (!v) fail(where + ": a LINE_LOOP whose index " + std::to_string(i) + " cannot be read");
        if (*v >= vertices)
          fail(where + ": a LINE_LOOP whose index " + std::to_string(i) + " is " + std::to_string(*v) + " but it has " +
               std::to_string(vertices) + " vertices");
      }
    }
  }
}

void checkGltfJson(std::string_view text, const std::string& what, const std::optional<std::string>& bin,
                   const fs::path& folder) {
  text = text.substr(0, text.find('\0'));
  // A glTF 2.0 document nests about 6 levels (extensions and extras a few more); 256 keeps any real
  // document and bounds rapidjson's recursion far below a stack's size.
  constexpr int kMaxDepth = 256;
  int depth = 0;
  bool inString = false, escaped = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (inString) {
      if (escaped) escaped = false;
      else if (c == '\\') escaped = true;
      else if (c == '"') inString = false;
    } else if (c == '"') {
      inString = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxDepth)
        fail(what + ": JSON nested deeper than " + std::to_string(kMaxDepth) + " levels at byte " + std::to_string(i));
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    fail(what + ": not valid JSON (" + e.what() + ")");
  }
  if (!doc.is_object()) fail(what + ": the JSON is not an object");
  const auto asset = doc.find("asset");
  if (asset == doc.end() || !asset->is_object()) fail(what + ": no \"asset\" object (glTF 2.0 requires one)");
  const auto version = asset->find("version");
  if (version == asset->end() || !version->is_string() || version->get_ref<const std::string&>().rfind('2', 0) != 0)
    fail(what + ": asset.version is not \"2.x\" (only glTF 2.0 is read; convert glTF 1.0 files)");
  try {
    checkPrimitives(doc, what, bin, folder);
  } catch (const nlohmann::json::exception& e) {
    fail(what + ": malformed mesh, accessor or buffer (" + e.what() + ")");
  }
}

// A .glb (glTF 2.0 spec, "GLB File Format Specification"): a 12-byte header (magic "glTF", version 2,
// total length), a JSON chunk (length, type "JSON", text padded to 4 bytes), then an optional BIN
// chunk. assimp 5.2.5 sizes its buffers by the chunk lengths before reading them (fuzz_glb: a JSON
// chunk claiming gigabytes in a small file exhausted memory), and reads a BIN chunk header whenever the
// header's length leaves room for one; it reads no more of the header's length. Each is checked
// against the file's size, and the JSON chunk as above.
void checkGlb(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const uint64_t size = fs::file_size(path);
  auto u32 = [&](uint64_t at, const char* field) {
    uint8_t b[4] = {};
    if (at + 4 > size || !in.seekg(std::streamoff(at)) || !in.read(reinterpret_cast<char*>(b), 4))
      fail("binary glTF: the file ends before its " + std::string(field) + " (byte " + std::to_string(at) + ")");
    return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;  // little-endian
  };
  constexpr uint32_t kJson = 0x4E4F534Au, kBin = 0x004E4942u;  // "JSON", "BIN\0" read as little-endian
  const uint32_t version = u32(4, "header version");
  if (version != 2) fail("binary glTF version " + std::to_string(version) + " (only version 2 is read)");
  const uint64_t length = u32(8, "header length");
  if (length > size)
    fail("binary glTF header length " + std::to_string(length) + " but the file has " + std::to_string(size) + " bytes");
  const uint64_t jsonLength = u32(12, "JSON chunk length");
  if (u32(16, "JSON chunk type") != kJson) fail("binary glTF: the first chunk is not of type JSON");
  if (20 + jsonLength > size)
    fail("binary glTF JSON chunk of " + std::to_string(jsonLength) + " bytes but " + std::to_string(size - 20) +
         " follow its header");
  std::string json(jsonLength, '\0');
  in.seekg(20);
  in.read(json.data(), std::streamsize(jsonLength));
  const uint64_t body = 20 + (jsonLength + 3) / 4 * 4 + 8;  // assimp's test for a BIN chunk
  if (length >= body) {
    const uint64_t binLength = u32(body - 8, "BIN chunk length");
    if (u32(body - 4, "BIN chunk type") != kBin) fail("binary glTF: the second chunk is not of type BIN");
    if (body + binLength > size)
      fail("binary glTF BIN chunk of " + std::to_string(binLength) + " bytes but " + std::to_string(size - body) +
           " follow its header");
  }
  std::optional<std::string> bin;
  if (length >= body) {
    bin.emplace(u32(body - 8, "BIN chunk length"), '\0');
    in.seekg(std::streamoff(body));
    in.read(bin->data(), std::streamsize(bin->size()));
  }
  checkGltfJson(json, "binary glTF JSON chunk", bin, fs::path(path).parent_path());
}

// What assimp would read through a reader other than the extension's: when that reader refuses the
// content, assimp tries every reader on it, so a COLLADA document named .gltf reaches the COLLADA
// reader (it accepts any file with "<collada" in its first 200 bytes, NULs dropped, any case), and a
// zip archive holding a .dae reaches it too (.zae). None of the formats read here is a zip archive.
void checkBeforeAssimp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string head(4096, '\0');
  in.read(head.data(), std::streamsize(head.size()));
  head.resize(size_t(in.gcount()));
  if (head.rfind("PK\x03\x04", 0) == 0) fail("a zip archive, not a " + fs::path(path).extension().string() + " file");
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](char c) { return char(std::tolower(uint8_t(c))); });
  // A .glb starts with the magic "glTF" (glTF 2.0 spec, GLB header): anything else would go to
  // assimp's other readers, one of which read past a buffer on an 85-byte file (fuzz_glb, ASan
  // heap-buffer-overflow in strncmp inside libassimp).
  if (ext == ".glb" && head.rfind("glTF", 0) != 0) fail("not a binary glTF file (no 'glTF' magic)");
  if (ext == ".glb") checkGlb(path);
  if (ext == ".gltf") checkGltfJson(readAll(path), "glTF", std::nullopt, fs::path(path).parent_path());
  std::erase(head, '\0');
  std::transform(head.begin(), head.end(), head.begin(), [](char c) { return char(std::tolower(uint8_t(c))); });
  if (ext == ".dae" || head.find("<collada") != std::string::npos) checkCollada(path);
  // assimp's AC3D reader takes any file that starts with "AC3D", whatever its name.
  if (ext == ".ac" || head.rfind("ac3d", 0) == 0) checkAc3d(readAll(path));
}

}  // namespace bvhlab::meshio
