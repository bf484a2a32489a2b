// datasets/scene_io: shipped scenes load, every kind of bad scene is a one-line FILE:LINE InputError,
// transforms and mesh baking are right, images and meshes are loaded once, bare meshes are framed.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "datasets/image_io.hpp"
#include "datasets/mesh_io.hpp"
#include "datasets/procedural.hpp"
#include "datasets/scene_io.hpp"
#include "require.hpp"

using namespace bvhlab;
namespace fs = std::filesystem;

namespace {

const fs::path kSource = BVHLAB_SOURCE_DIR;

class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::temp_directory_path() / ("bvhlab_test_scene_io_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  fs::path operator/(const std::string& name) const { return path_ / name; }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

void writeFile(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

std::string readFile(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

template <class F>
std::string inputErrorOf(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("UNEXPECTED EXCEPTION: ") + e.what();
  }
  return "";
}

// A minimal valid scene; cases append to it or replace parts.
const std::string kCamera = "[camera]\neye = [0, 1, 5]\ntarget = [0, 0, 0]\n";
const std::string kSphere = "[[object]]\nkind = \"sphere\"\n";

const char* kTriangleObj =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3\n";

glm::vec3 apply(const glm::mat4& m, glm::vec3 p) { return glm::vec3(m * glm::vec4(p, 1.0f)); }

void expectNear(glm::vec3 a, glm::vec3 b, float tol = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

}  // namespace

// ---- shipped scenes --------------------------------------------------------------------------------

TEST(ShippedScenes, EveryOneLoadsAndIsWellFormed) {
  const bool cache = fs::exists(kSource / "datasets/cache/meshes/bunny00.off") &&
                     fs::exists(kSource / "datasets/cache/worlds/courtyard.exr");
  size_t count = 0, skipped = 0;
  for (const auto& entry : fs::directory_iterator(kSource / "datasets/scenes")) {
    if (entry.path().extension() != ".toml") continue;
    ++count;
    SCOPED_TRACE(entry.path().filename().string());
    if (!cache && readFile(entry.path()).find("../cache/") != std::string::npos) {
      ++skipped;  // needs fetched data
      continue;
    }
    const Scene s = loadScene(entry.path());
    EXPECT_FALSE(s.objects.empty());
    for (const Object& o : s.objects) {
      ASSERT_GE(o.material, 0);
      ASSERT_LT(size_t(o.material), s.materials.size());
      if (o.kind == ObjectKind::Mesh) {
        ASSERT_GE(o.mesh, 0);
        ASSERT_LT(size_t(o.mesh), s.meshes.size());
      }
    }
    for (const Material& m : s.materials) {
      if (m.texture >= 0) {
        EXPECT_LT(size_t(m.texture), s.images.size());
      }
    }
    if (s.world.kind == WorldKind::Map) {
      EXPECT_LT(size_t(s.world.image), s.images.size());
    }
  }
  EXPECT_GE(count, 15u);
  if (skipped) BVHLAB_SKIP_OR_FAIL(skipped << " scene(s) need the dataset cache: run `bash datasets/fetch.sh`");
}

TEST(ShippedScenes, ReportSceneHasEveryIngredientOfTheReport) {
  if (!fs::exists(kSource / "datasets/cache/meshes/bunny00.off"))
    BVHLAB_SKIP_OR_FAIL("needs the dataset cache: run `bash datasets/fetch.sh`");
  const Scene s = loadScene(kSource / "datasets/scenes/report.toml");
  std::set<ObjectKind> kinds;
  for (const Object& o : s.objects) kinds.insert(o.kind);
  for (int k = 0; k < kObjectKindCount; ++k) EXPECT_TRUE(kinds.count(ObjectKind(k))) << objectKindName(ObjectKind(k));
  EXPECT_EQ(s.world.kind, WorldKind::Map);
  bool mirror = false, glass = false, logo = false;
  for (const Material& m : s.materials) {
    mirror |= m.reflectivity >= 0.5f;
    glass |= m.transparency >= 0.5f;
    logo |= m.texture >= 0 && s.images[size_t(m.texture)].name == "builtin:logo";
  }
  EXPECT_TRUE(mirror);
  EXPECT_TRUE(glass);
  EXPECT_TRUE(logo);
  EXPECT_NEAR(float(s.settings.width) / float(s.settings.height), 16.0f / 9.0f, 0.01f);
}

// ---- bad scenes ------------------------------------------------------------------------------------

// Each case is a scene text; the line holding "#!" is where the error must point, and `expect` must
// appear in the message.
struct BadScene {
  const char* label;
  std::string text;
  std::string expect;
};

TEST(SceneErrors, EveryProblemNamesFileLineAndKey) {
  TempDir tmp;
  writeFile(tmp / "tri.obj", kTriangleObj);
  writeFile(tmp / "broken.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
  writeFile(tmp / "notanimage.png", "garbage");
  const std::vector<BadScene> cases = {
      {"syntax", kCamera + "[render #!\n", "TOML syntax error"},
      {"unknown top-level key", "colour = 3 #!\n" + kCamera + kSphere, "unknown key 'colour' in the top level"},
      {"unknown camera key", "[camera]\neye = [0, 1, 5]\ntarget = [0, 0, 0]\nfocus = 2 #!\n" + kSphere,
       "unknown key 'focus' in [camera]"},
      {"unknown object key", kCamera + "[[object]]\nkind = \"sphere\"\nradius = 2 #!\n", "unknown key 'radius' in [[object]]"},
      {"unknown material key", kCamera + "[[material]]\nname = \"a\"\nroughness = 0.5 #!\n" + kSphere,
       "unknown key 'roughness' in [[material]]"},
      {"missing camera", "#! (a whole-file problem points at line 1)\n" + kSphere, "missing [camera]"},
      {"missing eye", "[camera] #!\ntarget = [0, 0, 0]\n" + kSphere, "missing required key 'eye'"},
      {"no objects", "#!\n" + kCamera, "no [[object]]"},
      {"eye wrong type", "[camera]\neye = \"up\" #!\ntarget = [0, 0, 0]\n" + kSphere, "camera.eye must be an array of 3 numbers"},
      {"eye wrong length", "[camera]\neye = [0, 1] #!\ntarget = [0, 0, 0]\n" + kSphere, "camera.eye must be an array of 3 numbers"},
      {"eye NaN", "[camera]\neye = [0, nan, 5] #!\ntarget = [0, 0, 0]\n" + kSphere, "camera.eye[1] is NaN or infinite"},
      {"fov inf", kCamera + "fov = inf #!\n" + kSphere, "camera.fov is NaN or infinite"},
      {"fov range", kCamera + "fov = 180 #!\n" + kSphere, "camera.fov must be (0, 180)"},
      {"eye == target", "[camera] #!\neye = [1, 1, 1]\ntarget = [1, 1, 1]\n" + kSphere, "eye and target coincide"},
      {"up parallel", "[camera] #!\neye = [0, 5, 0]\ntarget = [0, 0, 0]\n" + kSphere, "up is parallel"},
      {"width not int", kCamera + "[render]\nwidth = 640.5 #!\n" + kSphere, "render.width must be an integer"},
      {"height range", kCamera + "[render]\nheight = 0 #!\n" + kSphere, "render.height must be in [1, 16384]"},
      {"depth range", kCamera + "[render]\nmax_depth = 100 #!\n" + kSphere, "render.max_depth must be in [1, 32]"},
      {"exposure", kCamera + "[render]\nexposure = 0 #!\n" + kSphere, "render.exposure must be > 0"},
      {"tonemap", kCamera + "[render]\ntonemap = \"aces\" #!\n" + kSphere, "render.tonemap must be \"none\" or \"reinhard\""},
      {"world kind", kCamera + "[world]\nkind = \"hdri\" #!\n" + kSphere, "world.kind must be"},
      {"world foreign key", kCamera + "[world]\nkind = \"sky\"\nmap = \"x.exr\" #!\n" + kSphere,
       "key 'map' is only valid with kind = \"map\""},
      {"world map missing key", kCamera + "[world] #!\nkind = \"map\"\n" + kSphere, "needs map = "},
      {"world map missing file", kCamera + "[world]\nkind = \"map\"\nmap = \"nowhere.exr\" #!\n" + kSphere,
       "world map 'nowhere.exr' not found"},
      {"world map unreadable", kCamera + "[world]\nkind = \"map\"\nmap = \"notanimage.png\" #!\n" + kSphere,
       "notanimage.png"},
      {"unknown builtin", kCamera + "[world]\nkind = \"map\"\nmap = \"builtin:sunset\" #!\n" + kSphere,
       "unknown builtin image 'builtin:sunset'"},
      {"negative ambient", kCamera + "[world]\nambient = [0.1, -0.1, 0.1] #!\n" + kSphere, "world.ambient[1] must be >= 0"},
      {"light kind", kCamera + "[[light]]\nkind = \"spot\" #!\n" + kSphere, "kind must be \"point\" or \"directional\""},
      {"light needs position", kCamera + "[[light]] #!\nkind = \"point\"\n" + kSphere, "missing required key 'position'"},
      {"light zero direction", kCamera + "[[light]]\nkind = \"directional\"\ndirection = [0, 0, 0] #!\n" + kSphere,
       "direction must not be zero"},
      {"light foreign key", kCamera + "[[light]]\nkind = \"directional\"\ndirection = [0, -1, 0]\nposition = [0, 1, 0] #!\n" + kSphere,
       "key 'position' is only valid with kind = \"point\""},
      {"light intensity", kCamera + "[[light]]\nkind = \"point\"\nposition = [0, 1, 0]\nintensity = -1 #!\n" + kSphere,
       "intensity must be >= 0"},
      {"light as table", kCamera + "[light] #!\nkind = \"point\"\n" + kSphere, "'light' must be an array of tables"},
      {"material name missing", kCamera + "[[material]] #!\ncolor = [1, 0, 0]\n" + kSphere, "missing required key 'name'"},
      {"duplicate material", kCamera + "[[material]]\nname = \"a\"\n[[material]]\nname = \"a\" #!\n" + kSphere,
       "duplicate material name 'a'"},
      {"ior zero", kCamera + "[[material]]\nname = \"g\"\nior = 0 #!\n" + kSphere, "material 'g'.ior must be > 0"},
      {"ior negative", kCamera + "[[material]]\nname = \"g\"\nior = -1.5 #!\n" + kSphere, "ior must be > 0"},
      {"color above one", kCamera + "[[material]]\nname = \"g\"\ncolor = [1, 2, 0] #!\n" + kSphere, "color[1] must be [0, 1]"},
      {"refl + transp > 1", kCamera + "[[material]]\nname = \"g\"\nreflectivity = 0.6\ntransparency = 0.5 #!\n" + kSphere,
       "reflectivity + transparency must be <= 1"},
      {"shininess", kCamera + "[[material]]\nname = \"g\"\nshininess = 0 #!\n" + kSphere, "shininess must be (0, 10000]"},
      {"uv scale", kCamera + "[[material]]\nname = \"g\"\nuv_scale = [1, 0] #!\n" + kSphere, "uv_scale[1] must be > 0"},
      {"texture missing", kCamera + "[[material]]\nname = \"g\"\ntexture = \"logo.png\" #!\n" + kSphere,
       "texture 'logo.png' not found"},
      {"unknown material", kCamera + "[[material]]\nname = \"red\"\n[[object]]\nkind = \"sphere\"\nmaterial = \"blue\" #!\n",
       "unknown material 'blue' (known: red)"},
      {"object kind", kCamera + "[[object]]\nkind = \"teapot\" #!\n", "unknown kind \"teapot\""},
      {"object kind missing", kCamera + "[[object]] #!\nname = \"x\"\n", "missing required key 'kind'"},
      {"negative scale", kCamera + "[[object]]\nkind = \"box\"\nscale = [1, -1, 1] #!\n", "scale[1] must be > 0"},
      {"zero scale", kCamera + "[[object]]\nkind = \"box\"\nscale = 0 #!\n", "scale must be > 0"},
      {"translate NaN", kCamera + "[[object]]\nkind = \"box\"\ntranslate = [nan, 0, 0] #!\n", "translate[0] is NaN or infinite"},
      {"rotate type", kCamera + "[[object]]\nkind = \"box\"\nrotate = 45 #!\n", "rotate must be [x, y, z] degrees"},
      {"rotate axis zero", kCamera + "[[object]]\nkind = \"box\"\nrotate = { axis = [0, 0, 0], angle = 3 } #!\n",
       "rotate.axis must not be zero"},
      {"rotate unknown key", kCamera + "[[object]]\nkind = \"box\"\nrotate = { axis = [0, 1, 0], degrees = 3 } #!\n",
       "unknown key 'degrees'"},
      {"torus radius", kCamera + "[[object]]\nkind = \"torus\"\nminor_radius = -0.2 #!\n", "minor_radius must be > 0"},
      {"torus spindle", kCamera + "[[object]]\nkind = \"torus\"\nmajor_radius = 0.5\nminor_radius = 0.7 #!\n",
       "minor_radius must be <= major_radius"},
      {"foreign torus key", kCamera + "[[object]]\nkind = \"sphere\"\nmajor_radius = 2 #!\n",
       "key 'major_radius' is only valid with kind = \"torus\""},
      {"plane infinite type", kCamera + "[[object]]\nkind = \"plane\"\ninfinite = 1 #!\n", "infinite must be true or false"},
      {"mesh path missing", kCamera + "[[object]] #!\nkind = \"mesh\"\n", "missing required key 'mesh'"},
      {"mesh file missing", kCamera + "[[object]]\nkind = \"mesh\"\nmesh = \"bunny.obj\" #!\n", "mesh 'bunny.obj' not found"},
      {"mesh file broken", kCamera + "[[object]]\nkind = \"mesh\"\nmesh = \"broken.obj\" #!\n",
       "broken.obj:3: face: vertex index 3 out of range"},
      {"fit", kCamera + "[[object]]\nkind = \"mesh\"\nmesh = \"tri.obj\"\nfit = -1 #!\n", "fit must be > 0"},
      {"description type", "description = 3 #!\n" + kCamera + kSphere, "description must be a string"},
  };
  for (const BadScene& c : cases) {
    SCOPED_TRACE(c.label);
    const fs::path file = tmp / (std::string("case.toml"));
    writeFile(file, c.text);
    // The expected line: the one holding "#!".
    size_t line = 1;
    const size_t marker = c.text.find("#!");
    ASSERT_NE(marker, std::string::npos);
    for (size_t i = 0; i < marker; ++i) line += c.text[i] == '\n';
    const std::string msg = inputErrorOf([&] { loadScene(file); });
    EXPECT_EQ(msg.rfind(file.string() + ":" + std::to_string(line) + ": ", 0), 0u) << msg;
    EXPECT_NE(msg.find(c.expect), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

TEST(SceneErrors, MissingAndUnsupportedInputs) {
  TempDir tmp;
  EXPECT_NE(inputErrorOf([&] { loadScene(tmp / "none.toml"); }).find("none.toml: scene file not found"), std::string::npos);
  EXPECT_NE(inputErrorOf([&] { loadInput(tmp / "scene.json"); }).find("unsupported input '.json'"), std::string::npos);
  EXPECT_NE(inputErrorOf([&] { loadInput(tmp / "none.obj"); }).find("none.obj: mesh file not found"), std::string::npos);
}

// ---- semantics -------------------------------------------------------------------------------------

TEST(SceneSemantics, ValuesAndDefaultsArrive) {
  TempDir tmp;
  writeFile(tmp / "s.toml", kCamera +
                                "fov = 35\n[render]\nwidth = 320\nheight = 200\nmax_depth = 3\nexposure = 1.5\n"
                                "tonemap = \"reinhard\"\n[world]\nkind = \"color\"\ncolor = [0.1, 0.2, 0.3]\n"
                                "intensity = 2\n[[light]]\nkind = \"directional\"\ndirection = [0, -2, 0]\n"
                                "[[material]]\nname = \"glass\"\ntransparency = 0.9\nior = 1.33\nuv_scale = 4\n"
                                "[[object]]\nkind = \"torus\"\nmaterial = \"glass\"\nmajor_radius = 2\n"
                                "minor_radius = 0.5\n[[object]]\nkind = \"plane\"\ninfinite = true\n");
  const Scene s = loadScene(tmp / "s.toml");
  EXPECT_EQ(s.source, tmp / "s.toml");
  EXPECT_EQ(s.camera.fovDeg, 35.0f);
  EXPECT_EQ(s.settings.width, 320);
  EXPECT_EQ(s.settings.height, 200);
  EXPECT_EQ(s.settings.maxDepth, 3);
  EXPECT_EQ(s.settings.exposure, 1.5f);
  EXPECT_TRUE(s.settings.reinhard);
  EXPECT_EQ(s.world.kind, WorldKind::Color);
  EXPECT_EQ(s.world.color, glm::vec3(0.1f, 0.2f, 0.3f));
  EXPECT_EQ(s.world.intensity, 2.0f);
  ASSERT_EQ(s.lights.size(), 1u);
  EXPECT_EQ(s.lights[0].direction, glm::vec3(0, -1, 0));  // normalised
  ASSERT_EQ(s.objects.size(), 2u);
  EXPECT_EQ(s.objects[0].majorRadius, 2.0f);
  EXPECT_EQ(s.objects[0].minorRadius, 0.5f);
  EXPECT_EQ(s.materials[size_t(s.objects[0].material)].name, "glass");
  EXPECT_EQ(s.materials[size_t(s.objects[0].material)].uvScale, glm::vec2(4.0f));
  EXPECT_EQ(s.materials[size_t(s.objects[0].material)].ior, 1.33f);
  EXPECT_TRUE(s.objects[1].infinite);
  // No material given: the implicit default material with Material's defaults.
  const Material& d = s.materials[size_t(s.objects[1].material)];
  EXPECT_EQ(d.name, "default");
  EXPECT_EQ(d.color, Material{}.color);
}

TEST(SceneSemantics, TransformsComposeTranslateRotateScale) {
  // Scale 2, rotate 90 degrees about +Y (x -> -z), translate (0, 0, 5): (1,0,0) -> (2,0,0) -> (0,0,-2) -> (0,0,3).
  const glm::mat4 m = composeTransform(glm::vec3(0, 0, 5), glm::vec3(0, 90, 0), glm::vec3(2.0f));
  expectNear(apply(m, glm::vec3(1, 0, 0)), glm::vec3(0, 0, 3));
  // Euler order: X first, then Y, then Z (fixed axes). (0,1,0) -x90-> (0,0,1) -y90-> (1,0,0) -z90-> (0,1,0).
  const glm::mat4 e = composeTransform(glm::vec3(0.0f), glm::vec3(90, 90, 90), glm::vec3(1.0f));
  expectNear(apply(e, glm::vec3(0, 1, 0)), glm::vec3(0, 1, 0));
  expectNear(apply(e, glm::vec3(1, 0, 0)), glm::vec3(0, 0, -1));
  // Axis-angle agrees with the single-axis Euler form, and normalises its axis.
  const glm::mat4 a = composeTransform(glm::vec3(1, 2, 3), glm::vec3(0, 5, 0), 30.0f, glm::vec3(1, 2, 3));
  const glm::mat4 b = composeTransform(glm::vec3(1, 2, 3), glm::vec3(0, 30, 0), glm::vec3(1, 2, 3));
  for (int c = 0; c < 4; ++c) expectNear(glm::vec3(a[c]), glm::vec3(b[c]));

  TempDir tmp;
  writeFile(tmp / "t.toml", kCamera +
                                "[[object]]\nkind = \"box\"\ntranslate = [1, 2, 3]\nrotate = [0, 90, 0]\n"
                                "scale = [1, 2, 3]\n[[object]]\nkind = \"sphere\"\n"
                                "rotate = { axis = [0, 1, 0], angle = 30 }\nscale = 0.5\n");
  const Scene s = loadScene(tmp / "t.toml");
  const glm::mat4 want = composeTransform(glm::vec3(1, 2, 3), glm::vec3(0, 90, 0), glm::vec3(1, 2, 3));
  for (int c = 0; c < 4; ++c) expectNear(glm::vec3(s.objects[0].transform[c]), glm::vec3(want[c]));
  // The box corner (1,1,1): scale (1,2,3), y-rotation (x,z) -> (z,-x), then translate.
  expectNear(apply(s.objects[0].transform, glm::vec3(1, 1, 1)), glm::vec3(1 + 3, 2 + 2, 3 - 1));
  expectNear(apply(s.objects[1].transform, glm::vec3(0, 1, 0)), glm::vec3(0, 0.5f, 0));
}

TEST(SceneSemantics, MeshesAreBakedToWorldSpaceWithInverseTransposeNormals) {
  TempDir tmp;
  writeFile(tmp / "m/tri.obj", kTriangleObj);
  // Non-uniform scale and a rotation: normals must follow the inverse transpose, not the matrix.
  writeFile(tmp / "s.toml", kCamera +
                                "[[material]]\nname = \"red\"\ncolor = [1, 0, 0]\n"
                                "[[object]]\nkind = \"mesh\"\nmesh = \"m/tri.obj\"\nmaterial = \"red\"\n"
                                "translate = [0, 1, 0]\nrotate = [0, 0, 45]\nscale = [3, 1, 1]\n");
  const Scene s = loadScene(tmp / "s.toml");
  ASSERT_EQ(s.meshes.size(), 1u);
  ASSERT_EQ(s.objects.size(), 1u);
  const Mesh& m = s.meshes[0];
  EXPECT_EQ(s.objects[0].mesh, 0);
  EXPECT_EQ(m.material, s.objects[0].material);
  EXPECT_EQ(s.materials[size_t(m.material)].name, "red");
  const glm::mat4 M = composeTransform(glm::vec3(0, 1, 0), glm::vec3(0, 0, 45), glm::vec3(3, 1, 1));
  expectNear(m.positions[0], apply(M, glm::vec3(0, 0, 0)));
  expectNear(m.positions[1], apply(M, glm::vec3(1, 0, 0)));
  expectNear(m.positions[2], apply(M, glm::vec3(0, 1, 0)));
  // The normal stays perpendicular to the transformed triangle and unit length.
  const glm::vec3 e1 = m.positions[1] - m.positions[0], e2 = m.positions[2] - m.positions[0];
  for (const glm::vec3& n : m.normals) {
    EXPECT_NEAR(glm::length(n), 1.0f, 1e-6f);
    EXPECT_NEAR(glm::dot(n, e1), 0.0f, 1e-5f);
    EXPECT_NEAR(glm::dot(n, e2), 0.0f, 1e-5f);
    EXPECT_GT(glm::dot(n, glm::cross(e1, e2)), 0.0f);  // same side as the winding
  }
  // bakeMesh with a mirror keeps the winding consistent with the normals.
  const Mesh mirrored = bakeMesh(loadMesh(tmp / "m/tri.obj"), glm::scale(glm::mat4(1.0f), glm::vec3(-1, 1, 1)));
  const glm::vec3 f1 = mirrored.positions[mirrored.triangles[0].y] - mirrored.positions[mirrored.triangles[0].x];
  const glm::vec3 f2 = mirrored.positions[mirrored.triangles[0].z] - mirrored.positions[mirrored.triangles[0].x];
  EXPECT_GT(glm::dot(glm::cross(f1, f2), mirrored.normals[0]), 0.0f);
}

TEST(SceneSemantics, FitPlacesTheMeshBottomCentreAtTheTranslation) {
  TempDir tmp;
  saveMeshObj(tmp / "cube.obj", makeCube(1));  // [-1,1]^3: extent 2
  writeFile(tmp / "s.toml", kCamera + "[[object]]\nkind = \"mesh\"\nmesh = \"cube.obj\"\nfit = 0.5\ntranslate = [3, 0, 1]\n");
  const Scene s = loadScene(tmp / "s.toml");
  glm::vec3 lo(1e30f), hi(-1e30f);
  for (const glm::vec3& p : s.meshes[0].positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  expectNear(lo, glm::vec3(2.75f, 0.0f, 0.75f));
  expectNear(hi, glm::vec3(3.25f, 0.5f, 1.25f));
}

TEST(SceneSemantics, ImagesAndMeshesAreLoadedOnce) {
  TempDir tmp;
  writeFile(tmp / "tri.obj", kTriangleObj);
  writeFile(tmp / "sub/s.toml",
            kCamera +
                "[[material]]\nname = \"a\"\ntexture = \"builtin:logo\"\n"
                "[[material]]\nname = \"b\"\ntexture = \"builtin:logo\"\n"
                "[[material]]\nname = \"c\"\ntexture = \"builtin:checker\"\n"
                "[[material]]\nname = \"d\"\ntexture = \"../sub/../tex.png\"\n"  // the same file by another path
                "[[material]]\nname = \"e\"\ntexture = \"../tex.png\"\n"
                "[world]\nkind = \"map\"\nmap = \"builtin:checker\"\n"
                "[[object]]\nkind = \"mesh\"\nmesh = \"../tri.obj\"\n"
                "[[object]]\nkind = \"mesh\"\nmesh = \"../tri.obj\"\ntranslate = [2, 0, 0]\n");
  saveImageRgba8(tmp / "tex.png", 1, 1, {255, 255, 255, 255});
  const Scene s = loadScene(tmp / "sub/s.toml");
  EXPECT_EQ(s.images.size(), 3u);  // logo, checker, tex.png
  EXPECT_EQ(s.materials[0].texture, s.materials[1].texture);
  EXPECT_EQ(s.materials[3].texture, s.materials[4].texture);
  EXPECT_NE(s.materials[0].texture, s.materials[2].texture);
  EXPECT_EQ(s.world.image, s.materials[2].texture);
  ASSERT_EQ(s.meshes.size(), 2u);  // one per object (baked), from one load
  expectNear(s.meshes[1].positions[1] - s.meshes[0].positions[1], glm::vec3(2, 0, 0));
}

// ---- bare meshes -----------------------------------------------------------------------------------

TEST(MeshScenes, CameraFramesTheMeshAndTheGroundTouchesIt) {
  TempDir tmp;
  Mesh cube = makeCube(2);
  for (glm::vec3& p : cube.positions) p = p * glm::vec3(3.0f, 1.0f, 2.0f) + glm::vec3(10.0f, 5.0f, -4.0f);
  cube.normals.clear();
  saveMeshObj(tmp / "box.obj", cube);
  const Scene s = loadInput(tmp / "box.obj");
  EXPECT_EQ(s.source, tmp / "box.obj");
  EXPECT_EQ(s.triangleCount(), cube.triangles.size());
  ASSERT_FALSE(s.lights.empty());
  // Every bounding-box corner projects inside the view at the default 16:9 aspect.
  const Camera& c = s.camera;
  const glm::mat4 view = glm::lookAt(c.eye, c.target, c.up);
  const glm::mat4 proj = glm::perspective(glm::radians(c.fovDeg), float(s.settings.width) / s.settings.height, 0.01f, 1000.0f);
  for (int k = 0; k < 8; ++k) {
    const glm::vec3 corner(k & 1 ? 13.0f : 7.0f, k & 2 ? 6.0f : 4.0f, k & 4 ? -2.0f : -6.0f);
    const glm::vec4 clip = proj * view * glm::vec4(corner, 1.0f);
    ASSERT_GT(clip.w, 0.0f);
    EXPECT_LT(std::abs(clip.x / clip.w), 1.0f);
    EXPECT_LT(std::abs(clip.y / clip.w), 1.0f);
  }
  // Looking down at it from above, front-right (a 3/4 view).
  EXPECT_GT(c.eye.y, c.target.y);
  EXPECT_GT(c.eye.x, c.target.x);
  EXPECT_GT(c.eye.z, c.target.z);
  // The ground plane sits just under the lowest point and extends past the mesh.
  const Object* ground = nullptr;
  for (const Object& o : s.objects)
    if (o.kind == ObjectKind::Plane) ground = &o;
  ASSERT_NE(ground, nullptr);
  const glm::vec3 origin = apply(ground->transform, glm::vec3(0.0f)), edge = apply(ground->transform, glm::vec3(1, 0, 1));
  EXPECT_LT(origin.y, 4.0f);
  EXPECT_GT(origin.y, 4.0f - 0.01f);
  EXPECT_GT(edge.x - origin.x, 3.0f);
  // Without the ground plane only the mesh remains.
  const Scene bare = makeMeshScene(loadMesh(tmp / "box.obj"), MeshSceneOptions{false});
  EXPECT_EQ(bare.objects.size(), 1u);
  EXPECT_EQ(bare.objects[0].kind, ObjectKind::Mesh);
}

// ---- documentation ---------------------------------------------------------------------------------

TEST(SceneDocs, TheCompleteExampleLoads) {
  if (!fs::exists(kSource / "datasets/cache/meshes/bunny00.off"))
    BVHLAB_SKIP_OR_FAIL("needs the dataset cache: run `bash datasets/fetch.sh`");
  const std::string doc = readFile(kSource / "docs/scene-format.md");
  const size_t begin = doc.find("```toml\n");
  ASSERT_NE(begin, std::string::npos);
  const size_t end = doc.find("```", begin + 8);
  std::string example = doc.substr(begin + 8, end - begin - 8);
  // Its paths are written relative to datasets/scenes/.
  for (size_t at = example.find("../cache/"); at != std::string::npos; at = example.find("../cache/", at))
    example.replace(at, 9, (kSource / "datasets/cache").string() + "/");
  TempDir tmp;
  writeFile(tmp / "example.toml", example);
  const Scene s = loadScene(tmp / "example.toml");
  EXPECT_EQ(s.objects.size(), 4u);
  EXPECT_EQ(s.meshes.size(), 1u);
  EXPECT_EQ(s.world.kind, WorldKind::Map);
}

// A mesh file whose own coordinates are 1e7 from the origin, used by a scene near the origin
// (translate brings it back) and by a scene at its own place (the camera there, rebased to the eye).
// Either way the baked vertices keep double precision: within 1e-6 of the exact values, where a float
// reading of the file (spacing 1 at 1e7) is off by up to 0.5 and a float bake by as much.
TEST(SceneIo, FarMeshFilesAreBakedInDouble) {
  TempDir tmp;
  const glm::dvec3 far(1e7, 5e6, -1e7);
  const glm::dvec3 corners[3] = {{0.0, 0.0, 0.0}, {0.3, 0.0, 0.1}, {0.0, 0.7, 1.0 / 3.0}};
  std::string obj;
  char line[128];
  for (const glm::dvec3& c : corners) {
    std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", far.x + c.x, far.y + c.y, far.z + c.z);
    obj += line;
  }
  writeFile(tmp / "far.obj", obj + "f 1 2 3\n");
  // Near the origin: translate = -far.
  writeFile(tmp / "near.toml", "[camera]\neye = [0, 1, 5]\ntarget = [0, 0, 0]\n[[object]]\nkind = \"mesh\"\n"
                               "mesh = \"far.obj\"\ntranslate = [-10000000, -5000000, 10000000]\n");
  // At the mesh: the eye is far, the scene is rebased to it.
  writeFile(tmp / "there.toml", "[camera]\neye = [10000000, 5000001, -9999995]\ntarget = [10000000, 5000000, -10000000]\n"
                                "[[object]]\nkind = \"mesh\"\nmesh = \"far.obj\"\n");
  for (const char* name : {"near.toml", "there.toml"}) {
    SCOPED_TRACE(name);
    const Scene s = loadScene(tmp / name);
    ASSERT_EQ(s.meshes.size(), 1u);
    ASSERT_EQ(s.meshes[0].positions.size(), 3u);
    const glm::dvec3 base = std::string(name) == "near.toml" ? glm::dvec3(0.0) : far - s.origin;
    for (int k = 0; k < 3; ++k)
      EXPECT_LE(glm::length(glm::dvec3(s.meshes[0].positions[k]) - (base + corners[k])), 1e-6) << "corner " << k;
  }
  // A bare far mesh is rebased to its bounding box centre, so its float vertices are small and exact.
  const Scene bare = loadMeshScene(tmp / "far.obj");
  EXPECT_LE(glm::length(bare.origin - (far + glm::dvec3(0.15, 0.35, 1.0 / 6.0))), 1e-6);
  for (int k = 0; k < 3; ++k)
    EXPECT_LE(glm::length(glm::dvec3(bare.meshes[0].positions[k]) + bare.origin - (far + corners[k])), 1e-6);
}
