// glTF 2.0, COLLADA, FBX, 3DS and AC3D through the Open Asset Import Library (mesh_io_detail.hpp:
// readWithAssimp). assimp parses the file and triangulates; this file flattens the node graph in
// double precision, keeps normals, the first UV channel and the materials (mapped to the scene's
// material model), and applies the same limits as the other readers.
//
// Precision: Debian's libassimp is built without ASSIMP_DOUBLE_PRECISION (ai_real is float, checked
// below), so assimp itself stores positions, normals and node matrices as float. Positions here are
// those floats widened to double, with the node transforms applied in double: a model whose own
// vertices lie 1e5 or more from its origin has already lost its detail inside assimp -- the
// far-coordinate guarantee of the OBJ/OFF/PLY/STL readers does not hold for these formats.
#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <pugixml.hpp>

#include <algorithm>
#include <charconv>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <type_traits>
#include <unordered_map>
#include <utility>

#include "datasets/mesh_io_detail.hpp"

static_assert(std::is_same_v<ai_real, float>,
              "libassimp now stores double: update the precision notes here and in docs/scene-format.md");

namespace bvhlab::meshio {
namespace fs = std::filesystem;

namespace {

// Triangulate: polygons to triangles (assimp's ear clipping; points and lines stay and are skipped
// below). ValidateDataStructure: assimp checks indices and counts, so a broken file is its error
// message, not our crash (measured: free within noise). Not JoinIdenticalVertices: it would re-index
// the per-corner vertices COLLADA/FBX/AC3D importers emit (CG-57.ac: 352,821 -> 163,104 vertices),
// but it took 270-290 ms of a 65-80 ms import on that 180k-triangle file, and nothing downstream
// needs shared vertices (the renderer gathers a triangle soup). Not GenNormals: a mesh without
// normals renders with geometric normals, as the other formats do (and smoothing needs joined
// vertices).
constexpr unsigned kImportFlags = aiProcess_Triangulate | aiProcess_ValidateDataStructure;

// Vertices the flattened mesh may hold: 3 per triangle of the triangle limit (an indexed mesh has
// fewer; a file whose meshes are mostly unused vertices would otherwise escape the limit).
constexpr size_t kMaxMeshVertices = 3 * kMaxMeshTriangles;

// A squared normal length below which the normal carries no direction (as fromSoup in mesh_io.cpp):
// far below any normal a file stores on purpose, far above float underflow.
constexpr double kMinNormalLength2 = 1e-12;

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
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  const std::string bytes = std::move(text).str();
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
  std::erase(head, '\0');
  std::transform(head.begin(), head.end(), head.begin(), [](char c) { return char(std::tolower(uint8_t(c))); });
  if (ext == ".dae" || head.find("<collada") != std::string::npos) checkCollada(path);
}

glm::dmat4 toDmat4(const aiMatrix4x4& m) {
  // aiMatrix4x4 is row-major with column vectors (translation in a4, b4, c4); glm is column-major.
  glm::dmat4 r;
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 4; ++col) r[col][row] = double(m[row][col]);
  return r;
}

bool finite3(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

float clamp01(float v, float fallback) { return std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) : fallback; }

glm::vec3 colour(const aiColor4D& c) {
  return glm::vec3(clamp01(c.r, 0.8f), clamp01(c.g, 0.8f), clamp01(c.b, 0.8f));
}

// The nearest scene material (docs/scene-format.md, "Models with materials").
MeshMaterial mapMaterial(const aiScene& scene, const aiMaterial& m, const fs::path& folder, size_t index) {
  MeshMaterial out;
  Material& mat = out.material;
  aiString name;
  mat.name = m.Get(AI_MATKEY_NAME, name) == AI_SUCCESS && name.length ? std::string(name.C_Str())
                                                                       : "material" + std::to_string(index);
  // The bare-mesh look (scene_io.cpp) where the file says nothing.
  mat.color = glm::vec3(0.72f, 0.7f, 0.66f);
  mat.specular = 0.25f;
  mat.shininess = 48.0f;

  aiColor4D c;
  const bool hasBase = m.Get(AI_MATKEY_BASE_COLOR, c) == AI_SUCCESS;  // glTF baseColorFactor
  if (hasBase || m.Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS) mat.color = colour(c);

  float metallic = 0.0f, roughness = 1.0f, f = 0.0f;
  if (m.Get(AI_MATKEY_METALLIC_FACTOR, metallic) == AI_SUCCESS) {
    // Metallic-roughness (glTF): a mirror as far as the metal is smooth; glTF's defaults (metallic 1,
    // roughness 1) are a rough metal, which a Whitted tracer shows as diffuse, not as a mirror.
    m.Get(AI_MATKEY_ROUGHNESS_FACTOR, roughness);
    metallic = clamp01(metallic, 0.0f);
    roughness = clamp01(roughness, 1.0f);
    mat.reflectivity = metallic * (1.0f - roughness);
    mat.specular = 0.5f * (1.0f - roughness);
    // Blinn-Phong exponent of the same lobe width: 2/alpha^2 - 2 with alpha = roughness^2 (Walter et
    // al. 2007), kept in the scene format's (0, 10000].
    const float alpha2 = std::max(roughness * roughness * roughness * roughness, 2.0f / 10002.0f);
    mat.shininess = std::clamp(2.0f / alpha2 - 2.0f, 1.0f, 10000.0f);
  } else {
    if (m.Get(AI_MATKEY_REFLECTIVITY, f) == AI_SUCCESS) mat.reflectivity = clamp01(f, 0.0f);
    aiColor4D spec;
    if (m.Get(AI_MATKEY_COLOR_SPECULAR, spec) == AI_SUCCESS) {
      float strength = 1.0f;
      m.Get(AI_MATKEY_SHININESS_STRENGTH, strength);
      mat.specular = clamp01(std::max({spec.r, spec.g, spec.b}) * strength, mat.specular);
    }
    if (m.Get(AI_MATKEY_SHININESS, f) == AI_SUCCESS && f > 0.0f && f <= 10000.0f) mat.shininess = f;
  }

  // Glass: glTF's KHR_materials_transmission, else an opacity below 1 (COLLADA, FBX, 3DS, AC3D, and
  // glTF's alpha).
  float transparency = 0.0f;
  if (m.Get(AI_MATKEY_TRANSMISSION_FACTOR, f) == AI_SUCCESS) transparency = clamp01(f, 0.0f);
  if (m.Get(AI_MATKEY_OPACITY, f) == AI_SUCCESS) transparency = std::max(transparency, 1.0f - clamp01(f, 1.0f));
  mat.transparency = transparency;
  // reflectivity + transparency <= 1 (the scene's rule): the mirror is a fraction of the opaque part.
  mat.reflectivity *= 1.0f - transparency;
  if (m.Get(AI_MATKEY_REFRACTI, f) == AI_SUCCESS && std::isfinite(f) && f >= 1.0f && f <= 10.0f) mat.ior = f;

  aiColor4D e;
  if (m.Get(AI_MATKEY_COLOR_EMISSIVE, e) == AI_SUCCESS) {
    float intensity = 1.0f;
    m.Get(AI_MATKEY_EMISSIVE_INTENSITY, intensity);
    if (!std::isfinite(intensity) || intensity < 0.0f) intensity = 1.0f;
    for (int k = 0; k < 3; ++k) {
      const float v = (&e.r)[k] * intensity;
      mat.emission[k] = std::isfinite(v) && v > 0.0f ? v : 0.0f;
    }
  }

  // Base-colour texture (UV channel 0 only: the only one kept).
  for (aiTextureType type : {aiTextureType_BASE_COLOR, aiTextureType_DIFFUSE}) {
    if (m.GetTextureCount(type) == 0) continue;
    aiString path;
    unsigned uvIndex = 0;
    if (m.GetTexture(type, 0, &path, nullptr, &uvIndex) != AI_SUCCESS || uvIndex != 0 || !path.length) break;
    if (const aiTexture* t = scene.GetEmbeddedTexture(path.C_Str())) {
      if (t->mHeight == 0 && t->pcData) {  // a compressed image file (PNG, JPEG) in memory
        out.textureBytes.assign(reinterpret_cast<const char*>(t->pcData), t->mWidth);
        out.textureFormat = t->achFormatHint;
      }  // raw texels (mHeight > 0) come only from formats not read here
    } else {
      std::string p = path.C_Str();
      std::replace(p.begin(), p.end(), '\\', '/');  // FBX and 3DS written on Windows
      fs::path file = fs::path(p).is_absolute() ? fs::path(p) : folder / p;
      std::error_code ec;
      // Models moved from another machine keep the author's absolute path: try the bare file name
      // next to the model.
      if (!fs::exists(file, ec) && fs::exists(folder / fs::path(p).filename(), ec)) file = folder / fs::path(p).filename();
      out.texturePath = file.string();
    }
    // With a texture, a Phong format's diffuse colour is what the texture replaces: white, unless
    // the file states a base colour factor that multiplies it (glTF).
    if (!hasBase) mat.color = glm::vec3(1.0f);
    break;
  }
  return out;
}

struct Flattener {
  const aiScene& scene;
  MeshData& out;
  std::vector<uint8_t> meshHasNormals, meshHasUvs;
  bool anyNormals = false, anyUvs = false;

  static size_t triangleCount(const aiMesh& mesh) {
    size_t tris = 0;
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) tris += mesh.mFaces[f].mNumIndices == 3;
    return tris;
  }

  void addInstance(const aiMesh& mesh, const glm::dmat4& toWorld) {
    const size_t base = out.positions.size();
    const glm::dmat3 linear(toWorld);
    const double det = glm::determinant(linear);
    // Normals go through the cofactor matrix (det * inverse transpose; defined for singular
    // transforms too), its sign corrected so they keep their side.
    const double side = det < 0.0 ? -1.0 : 1.0;
    const glm::dmat3 normalMatrix(side * glm::cross(linear[1], linear[2]), side * glm::cross(linear[2], linear[0]),
                                  side * glm::cross(linear[0], linear[1]));
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      const glm::dvec3 q(toWorld * glm::dvec4(p.x, p.y, p.z, 1.0));
      if (!finite3(q)) fail("vertex position is NaN or infinite (mesh '" + std::string(mesh.mName.C_Str()) + "')");
      out.positions.push_back(q);
      glm::dvec3 n(0.0);
      if (mesh.mNormals) n = normalMatrix * glm::dvec3(mesh.mNormals[v].x, mesh.mNormals[v].y, mesh.mNormals[v].z);
      const double len2 = glm::dot(n, n);
      // A missing, zero or non-finite normal stays (0,0,0) here and is repaired below.
      out.normals.push_back(len2 > 0.0 && std::isfinite(len2) ? glm::vec3(n / std::sqrt(len2)) : glm::vec3(0.0f));
      glm::vec2 uv(0.0f);
      if (mesh.mTextureCoords[0]) {
        uv = glm::vec2(mesh.mTextureCoords[0][v].x, mesh.mTextureCoords[0][v].y);
        if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) fail("texture coordinate is NaN or infinite");
      }
      out.uvs.push_back(uv);
    }
    anyNormals = anyNormals || mesh.mNormals;
    anyUvs = anyUvs || mesh.mTextureCoords[0];

    const bool mirror = det < 0.0;  // keep the winding (and the geometric normal) outward, as bakeMesh
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;
      glm::uvec3 t;
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= mesh.mNumVertices)
          fail("face " + std::to_string(f) + " references vertex " + std::to_string(face.mIndices[k]) + " (mesh has " +
               std::to_string(mesh.mNumVertices) + ")");
        t[k] = unsigned(base + face.mIndices[k]);
      }
      if (mirror) std::swap(t.y, t.z);
      out.triangles.push_back(t);
      out.triangleMaterials.push_back(mesh.mMaterialIndex);
    }
  }

  void flatten() {
    // Every (mesh, transform) placement, depth first with an explicit stack (a file's node tree may
    // be deep); then the totals are checked against the limits before anything is allocated.
    std::vector<std::pair<const aiMesh*, glm::dmat4>> instances;
    std::vector<std::pair<const aiNode*, glm::dmat4>> stack{{scene.mRootNode, toDmat4(scene.mRootNode->mTransformation)}};
    std::vector<size_t> meshTriangles(scene.mNumMeshes);
    for (unsigned i = 0; i < scene.mNumMeshes; ++i) meshTriangles[i] = triangleCount(*scene.mMeshes[i]);
    size_t triangles = 0, vertices = 0;
    while (!stack.empty()) {
      auto [node, toWorld] = stack.back();
      stack.pop_back();
      for (unsigned i = 0; i < node->mNumMeshes; ++i) {
        const unsigned m = node->mMeshes[i];
        if (m >= scene.mNumMeshes) fail("node references a mesh that does not exist");
        if (meshTriangles[m] == 0) continue;  // points and lines (AC3D line surfaces, COLLADA lines)
        triangles += meshTriangles[m];
        vertices += scene.mMeshes[m]->mNumVertices;
        if (triangles > kMaxMeshTriangles)
          fail("more than " + std::to_string(kMaxMeshTriangles) + " triangles after instancing (kMaxMeshTriangles)");
        if (vertices > kMaxMeshVertices)
          fail("more than " + std::to_string(kMaxMeshVertices) + " vertices after instancing");
        instances.emplace_back(scene.mMeshes[m], toWorld);
      }
      for (unsigned c = node->mNumChildren; c-- > 0;)
        stack.emplace_back(node->mChildren[c], toWorld * toDmat4(node->mChildren[c]->mTransformation));
    }
    out.positions.reserve(vertices);
    out.normals.reserve(vertices);
    out.uvs.reserve(vertices);
    out.triangles.reserve(triangles);
    out.triangleMaterials.reserve(triangles);
    for (const auto& [mesh, toWorld] : instances) addInstance(*mesh, toWorld);
  }

  // Normals are kept when any mesh has them; a vertex without one (a mesh without normals, or a
  // zero/non-finite one) gets the normal of a triangle that uses it -- flat, as the renderer would
  // shade it without normals. Vertices only degenerate triangles use get +Z (they cover no pixel).
  void finishNormals() {
    if (!anyNormals) {
      out.normals.clear();
      return;
    }
    auto bad = [](const glm::vec3& n) { return !(double(glm::dot(n, n)) > kMinNormalLength2); };
    for (const glm::uvec3& t : out.triangles) {
      if (!bad(out.normals[t.x]) && !bad(out.normals[t.y]) && !bad(out.normals[t.z])) continue;
      const glm::dvec3 g = glm::cross(out.positions[t.y] - out.positions[t.x], out.positions[t.z] - out.positions[t.x]);
      const double len = glm::length(g);
      if (!(len > 0.0) || !std::isfinite(len)) continue;
      for (int k = 0; k < 3; ++k)
        if (bad(out.normals[t[k]])) out.normals[t[k]] = glm::vec3(g / len);
    }
    for (glm::vec3& n : out.normals)
      if (bad(n)) n = glm::vec3(0.0f, 0.0f, 1.0f);
  }
};

}  // namespace

const std::vector<std::string>& assimpExtensions() {
  static const std::vector<std::string> exts{".gltf", ".glb", ".dae", ".fbx", ".3ds", ".ac"};
  return exts;
}

void checkAc3dCounts(std::string_view text) {
  size_t totalLines = 0;
  std::string_view line;
  for (LineScanner all{text}; all.next(line);) ++totalLines;
  LineScanner lines{text};
  while (lines.next(line)) {
    // Most lines are vertices and refs rows: only lines starting with a count keyword are split.
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string_view::npos || (line[first] != 'n' && line[first] != 'r' && line[first] != 'k')) continue;
    const std::vector<std::string_view> toks = tokens(line);
    if (toks.size() < 2) continue;
    if (toks[0] != "numvert" && toks[0] != "numsurf" && toks[0] != "refs" && toks[0] != "kids") continue;
    const std::optional<long long> n = parseInt(toks[1]);
    if (!n || *n < 0) failAt(lines.lineNo, std::string(toks[0]) + ": expected a count, got " + quoted(toks[1]));
    if (size_t(*n) > totalLines - lines.lineNo)
      failAt(lines.lineNo, std::string(toks[0]) + " " + std::to_string(*n) + " but only " +
                               std::to_string(totalLines - lines.lineNo) + " lines follow (truncated or malformed)");
  }
}

MeshData readWithAssimp(const std::string& path) {
  Assimp::Importer importer;
  // AC3D 'subdiv N' asks for N Catmull-Clark steps (4^N triangles): a resource the file controls.
  // Kept off; the control mesh is used.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_AC_EVAL_SUBDIVISION, false);
  checkBeforeAssimp(path);
  const aiScene* scene = importer.ReadFile(path, kImportFlags);
  if (!scene) {
    std::string why = importer.GetErrorString();
    if (why.empty()) why = "unknown error";
    // assimp tries every reader when the one for the extension refuses the content.
    if (why.rfind("No suitable reader", 0) == 0)
      fail("not a readable " + fs::path(path).extension().string() + " file (assimp: no reader accepts its content)");
    fail("cannot read the file (assimp: " + why + ")");
  }
  if (!scene->mRootNode || scene->mNumMeshes == 0) fail("mesh has no faces (the file holds no meshes)");

  MeshData mesh;
  const fs::path folder = fs::path(path).parent_path();
  for (unsigned i = 0; i < scene->mNumMaterials; ++i) mesh.materials.push_back(mapMaterial(*scene, *scene->mMaterials[i], folder, i));
  if (mesh.materials.empty()) mesh.materials.emplace_back();  // assimp always adds a default; be safe

  Flattener flat{*scene, mesh, {}, {}};
  flat.flatten();
  for (uint32_t& m : mesh.triangleMaterials)
    if (m >= mesh.materials.size()) m = 0;  // ValidateDataStructure refuses this; never index past the end
  flat.finishNormals();
  if (!flat.anyUvs) mesh.uvs.clear();
  return mesh;
}

}  // namespace bvhlab::meshio
