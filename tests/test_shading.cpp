// Shading checked against closed-form optics, not against the C++ mirror: every expected value below
// is computed in this file, in double precision, from the textbook formula (Lambert + Blinn-Phong +
// ambient, Schlick's Fresnel term, Snell's law, similar triangles for hard shadows), and compared with
// what the real GLSL path renders (GpuRenderer on llvmpipe). Scenes are TOML text loaded by the real
// scene loader.
//
// The only things taken from the renderer are its documented conventions, not its code:
//  - camera (main.glsl cameraRay): the ray through pixel (i, j), rows bottom-up, goes through
//    ndc = 2 (i + 0.5, j + 0.5) / (W, H) - 1 on an image plane at distance 1 whose half height is
//    tan(fov / 2) (vertical fov) and half width tan(fov / 2) * W / H;
//  - output: linear radiance * exposure, clamped to [0, 1], sRGB-encoded (IEC 61966-2-1), stored in
//    8 bits; no tone map unless the scene asks for one;
//  - shading model (docs/scene-format.md, shade.glsl's header): emission + albedo * ambient weight *
//    world ambient + sum over visible lights of radiance * (albedo * diffuse * cos + specular *
//    max(n.h, 0)^shininess), h the Blinn half vector; lights have no falloff; a transparent surface
//    splits into reflection R and refraction 1 - R with Schlick's R computed with the cosine on the
//    optically thinner side.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>

#include <glm/glm.hpp>

#include "render_fixture.hpp"

namespace bvhlab::test {
namespace {

using glm::dvec3;

// ---- independent camera, sRGB and image access ---------------------------------------------------

struct PinholeCamera {
  dvec3 eye, forward, right, up;  // right/up span the image plane at distance 1 (half extents)
  int width, height;

  PinholeCamera(const Camera& c, int w, int h) : width(w), height(h) {
    eye = dvec3(c.eye);
    forward = glm::normalize(dvec3(c.target) - eye);
    const dvec3 r = glm::normalize(glm::cross(forward, dvec3(c.up)));
    const double tanHalf = std::tan(glm::radians(double(c.fovDeg)) * 0.5);
    right = r * tanHalf * (double(w) / double(h));
    up = glm::cross(r, forward) * tanHalf;
  }
  // Unit direction through image position (px, py) in pixels, (0, 0) the bottom-left corner.
  dvec3 dir(double px, double py) const {
    const double nx = 2.0 * px / width - 1.0, ny = 2.0 * py / height - 1.0;
    return glm::normalize(forward + nx * right + ny * up);
  }
  dvec3 pixelDir(int i, int j) const { return dir(i + 0.5, j + 0.5); }
};

double srgbEncode(double c) {
  c = std::clamp(c, 0.0, 1.0);
  return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
}
double srgbDecode(double e) { return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4); }
// Expected 8-bit value (real-valued, before the driver's rounding) of a linear radiance.
double expected8(double linear) { return 255.0 * srgbEncode(linear); }
// Linear radiance an 8-bit value stands for.
double linearOf(uint8_t v) { return srgbDecode(v / 255.0); }

struct Image {
  std::vector<uint8_t> rgba;
  int width, height;
  uint8_t at(int i, int j, int c) const { return rgba[4 * (size_t(j) * width + i) + c]; }
};

Image render(const PreparedScene& p, int w, int h, std::optional<Camera> camera = std::nullopt) {
  FrameOptions f = smallFrame(p.scene, w, h);
  if (camera) f.camera = *camera;
  return Image{renderGpu(p, tracerOptions(p), f).rgba, w, h};
}

// Tolerance for a per-pixel comparison with a value computed in double: the driver rounds to the
// nearest of 256 levels (0.5 step) and the GPU computes the ray, the intersection and pow() in float
// (relative error ~1e-6, far below a step); 1 step leaves room for both, nothing more.
constexpr double kStepTolerance = 1.0;

// ---- Lambert + Blinn-Phong + ambient --------------------------------------------------------------

// A Lambertian (then Blinn-Phong) infinite plane y = 0 seen from straight above, lit by a point light
// and a directional light, with world ambient and a black background: every pixel against
//   L = albedo * ka * A + sum_l C_l * (albedo * kd * max(cos_l, 0) + ks * max(n.h_l, 0)^s)
TEST(Shading, DiffusePlaneIsAmbientPlusLambertPlusBlinnPhong) {
  const dvec3 albedo(0.6, 0.5, 0.3), ambient(0.2, 0.3, 0.4);
  const double kd = 0.8, ka = 0.5, shininess = 20.0;
  const dvec3 pointPos(1.5, 2.0, -0.5), pointColor = 0.7 * dvec3(1.0, 0.9, 0.8);
  const dvec3 dirTravel = glm::normalize(dvec3(-0.3, -1.0, 0.2)), dirColor = 0.3 * dvec3(0.5, 0.7, 1.0);
  for (double ks : {0.0, 0.4}) {
    SCOPED_TRACE("specular " + std::to_string(ks));
    std::ostringstream toml;
    toml << R"(
[camera]
eye = [0, 4, 0]
target = [0, 0, 0]
up = [0, 0, -1]
fov = 60
[world]
kind = "color"
color = [0, 0, 0]
ambient = [0.2, 0.3, 0.4]
[[light]]
kind = "point"
position = [1.5, 2, -0.5]
color = [1, 0.9, 0.8]
intensity = 0.7
[[light]]
kind = "directional"
direction = [-0.3, -1, 0.2]
color = [0.5, 0.7, 1]
intensity = 0.3
[[material]]
name = "m"
color = [0.6, 0.5, 0.3]
diffuse = 0.8
ambient = 0.5
shininess = 20
specular = )" << ks << R"(
[[object]]
kind = "plane"
infinite = true
material = "m"
)";
    auto p = prepareToml(toml.str());
    constexpr int W = 96, H = 72;
    const Image img = render(*p, W, H);
    const PinholeCamera cam(p->scene.camera, W, H);
    const dvec3 n(0, 1, 0);
    double worst = 0.0, minCos = 1.0, maxCos = 0.0;
    int failures = 0;
    for (int j = 0; j < H; ++j)
      for (int i = 0; i < W; ++i) {
        const dvec3 v = cam.pixelDir(i, j);
        const dvec3 hit = cam.eye + (-cam.eye.y / v.y) * v;
        dvec3 L = albedo * ka * ambient;
        auto addLight = [&](dvec3 toLight, dvec3 color) {
          const double c = glm::dot(n, toLight);
          if (c <= 0.0) return;
          const dvec3 h = glm::normalize(toLight - v);
          L += color * (albedo * kd * c + dvec3(ks * std::pow(std::max(glm::dot(n, h), 0.0), shininess)));
        };
        const dvec3 toPoint = glm::normalize(pointPos - hit);
        minCos = std::min(minCos, toPoint.y), maxCos = std::max(maxCos, toPoint.y);
        addLight(toPoint, pointColor);
        addLight(-dirTravel, dirColor);
        for (int c = 0; c < 3; ++c) {
          const double err = std::abs(img.at(i, j, c) - expected8(L[c]));
          worst = std::max(worst, err);
          if (err > kStepTolerance && ++failures <= 3)
            ADD_FAILURE() << "pixel (" << i << "," << j << ") channel " << c << ": rendered " << int(img.at(i, j, c))
                          << ", formula " << expected8(L[c]);
        }
      }
    EXPECT_EQ(failures, 0);
    // The point light's cosine must really vary over the image, or the test proves little.
    EXPECT_LT(minCos, 0.6);
    EXPECT_GT(maxCos, 0.99);
    std::printf("[ measured ] Lambert/Blinn-Phong ks=%.1f: max |rendered - formula| = %.2f 8-bit steps over %d pixels"
                " (point-light cos %.2f..%.2f)\n", ks, worst, W * H, minCos, maxCos);
  }
}

// ---- Schlick's Fresnel term -----------------------------------------------------------------------

double schlick(double cosTheta, double n1, double n2) {
  const double r0 = ((n1 - n2) / (n1 + n2)) * ((n1 - n2) / (n1 + n2));
  return r0 + (1.0 - r0) * std::pow(1.0 - cosTheta, 5.0);
}

// An infinitely thin glass plane y = 0 between two emissive planes: red emission 1 above (y = 2), green
// emission 1 below (y = -1), black world, no lights. A camera ray that meets the glass at angle theta
// splits into a reflected ray, which can only see the red plane, and a refracted one, which can only
// see the green plane, so the pixel is exactly (R(theta), 1 - R(theta), 0). Seen from straight above
// (normal incidence, R ~ R0) and towards the horizon (grazing, R up to ~0.95), for glass and water.
TEST(Shading, FresnelReflectanceFollowsSchlickFromNormalToGrazingIncidence) {
  for (double ior : {1.5, 1.33}) {
    std::ostringstream toml;
    toml << R"(
[camera]
eye = [0, 1, 0]
target = [0, 0, 0]
up = [0, 0, -1]
fov = 40
[render]
max_depth = 3
[world]
kind = "color"
color = [0, 0, 0]
ambient = [0, 0, 0]
[[material]]
name = "glass"
color = [1, 1, 1]
transparency = 1.0
ior = )" << ior << R"(
[[material]]
name = "above"
color = [0, 0, 0]
diffuse = 0
ambient = 0
emission = [1, 0, 0]
[[material]]
name = "below"
color = [0, 0, 0]
diffuse = 0
ambient = 0
emission = [0, 1, 0]
[[object]]
kind = "plane"
infinite = true
material = "glass"
[[object]]
kind = "plane"
infinite = true
material = "above"
translate = [0, 2, 0]
[[object]]
kind = "plane"
infinite = true
material = "below"
translate = [0, -1, 0]
)";
    auto p = prepareToml(toml.str());
    const double r0 = ((1.0 - ior) / (1.0 + ior)) * ((1.0 - ior) / (1.0 + ior));

    Camera grazing = p->scene.camera;
    grazing.target = glm::vec3(0.0f, 1.0f - 0.125f, -1.0f);  // 7.1 degrees below the horizon
    grazing.up = glm::vec3(0.0f, 1.0f, 0.0f);
    grazing.fovDeg = 30.0f;
    struct View {
      const char* name;
      Camera camera;
    };
    for (const View& view : {View{"normal", p->scene.camera}, View{"grazing", grazing}}) {
      SCOPED_TRACE(std::string(view.name) + " incidence, ior " + std::to_string(ior));
      constexpr int W = 64, H = 64;
      const Image img = render(*p, W, H, view.camera);
      const PinholeCamera cam(view.camera, W, H);
      double worst = 0.0, minCos = 1.0, maxCos = 0.0;
      int checked = 0, failures = 0;
      for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
          const dvec3 v = cam.pixelDir(i, j);
          // Above the horizon the red plane is seen directly; within 0.01 of the horizon the reflected
          // ray runs ~100 units to the emitter (float precision, not optics): not checked.
          if (v.y > -0.01) continue;
          const double cosTheta = -v.y;
          minCos = std::min(minCos, cosTheta), maxCos = std::max(maxCos, cosTheta);
          const double R = schlick(cosTheta, 1.0, ior);
          const double expect[3] = {expected8(R), expected8(1.0 - R), 0.0};
          for (int c = 0; c < 3; ++c) {
            const double err = std::abs(img.at(i, j, c) - expect[c]);
            worst = std::max(worst, err);
            if (err > kStepTolerance && ++failures <= 3)
              ADD_FAILURE() << "pixel (" << i << "," << j << ") cos " << cosTheta << " channel " << c
                            << ": rendered " << int(img.at(i, j, c)) << ", Schlick " << expect[c];
          }
          ++checked;
        }
      EXPECT_EQ(failures, 0);
      EXPECT_GT(checked, W * H / 3);
      if (std::string(view.name) == "normal") {
        EXPECT_GT(minCos, 0.88);  // every pixel near normal incidence: R within 2e-5 of R0
        const double measured = linearOf(img.at(W / 2, H / 2, 0));
        std::printf("[ measured ] ior %.2f normal incidence: R = %.4f (centre pixel, decoded), formula R0 = %.4f;"
                    " max |rendered - formula| %.2f steps over %d pixels\n", ior, measured, r0, worst, checked);
      } else {
        EXPECT_LT(minCos, 0.02);  // reaches grazing incidence (R > 0.9)
        EXPECT_GT(schlick(minCos, 1.0, ior), 0.9);
        std::printf("[ measured ] ior %.2f grazing: cos %.3f..%.3f;", ior, minCos, maxCos);
        for (int j : {2, 10, 20, 30}) {  // a few rows, centre column: measured R vs formula
          const double c = -cam.pixelDir(W / 2, j).y;
          if (c < 0.01) continue;
          std::printf(" cos %.3f: R %.4f vs %.4f;", c, linearOf(img.at(W / 2, j, 0)), schlick(c, 1.0, ior));
        }
        std::printf(" max |rendered - formula| %.2f steps over %d pixels\n", worst, checked);
      }
    }
  }
}

// ---- Snell's law through a parallel glass slab -----------------------------------------------------

// A horizontal glass slab (ior 1.5, thickness T = 0.8, y in [0.2, 1]) over a black floor with an
// emissive rectangle x in [0, 6], z in [-6, 6]; black world, no lights; camera 2.5 above, looking
// down at ~45 degrees. Every pixel's path is computed here from Snell's law (sin t = sin i / n): the
// ray bends towards the normal inside the slab (horizontal run T tan(theta_t) instead of T tan(theta))
// and leaves parallel to itself, so the floor point it sees is displaced back towards the camera by
// T (tan theta - tan theta_t) horizontally, a lateral shift of T sin(theta - theta_t) / cos(theta_t).
// Rendered bright/dark must match the prediction at every pixel not within 0.01 units (~1/5 pixel) of
// the rectangle's edge, and the bright pixels must carry the Fresnel transmission (1 - R)^2.
TEST(Shading, RefractionThroughAGlassSlabShiftsTheFloorBySnellsLaw) {
  constexpr double kIor = 1.5, kTop = 1.0, kBottom = 0.2, kT = kTop - kBottom, kEmission = 0.8;
  auto p = prepareToml(R"(
[camera]
eye = [-2.5, 2.5, 0]
target = [0.5, 0, 0]
fov = 40
[render]
max_depth = 6
[world]
kind = "color"
color = [0, 0, 0]
ambient = [0, 0, 0]
[[material]]
name = "glass"
color = [1, 1, 1]
transparency = 1.0
ior = 1.5
[[material]]
name = "lamp"
color = [0, 0, 0]
diffuse = 0
ambient = 0
emission = [0.8, 0.8, 0.8]
[[object]]
kind = "box"
material = "glass"
translate = [0, 0.6, 0]
scale = [20, 0.4, 20]
[[object]]
kind = "plane"
material = "lamp"
translate = [3, 0, 0]
scale = [3, 1, 6]
)");
  constexpr int W = 96, H = 96;
  const Image img = render(*p, W, H);
  const PinholeCamera cam(p->scene.camera, W, H);

  // Floor point seen along v: straight (no refraction) or through the slab by Snell's law.
  auto floorStraight = [&](dvec3 v) { return cam.eye + (-cam.eye.y / v.y) * v; };
  // Floor points seen through the slab, by Snell's law.
  struct SnellPath {
    dvec3 floor;   // where the ray that crosses the slab once reaches the floor
    dvec3 second;  // where the ray reflected once off the bottom and once off the top reaches it
  };
  auto floorSnell = [&](dvec3 v) {
    const dvec3 top = cam.eye + ((kTop - cam.eye.y) / v.y) * v;
    const double cosI = -v.y, sinI = std::sqrt(1.0 - cosI * cosI);
    const double sinT = sinI / kIor, tanT = sinT / std::sqrt(1.0 - sinT * sinT), tanI = sinI / cosI;
    const dvec3 u = glm::normalize(dvec3(v.x, 0.0, v.z));  // horizontal direction of travel
    const dvec3 floor = dvec3(top.x, 0.0, top.z) + u * (kT * tanT + kBottom * tanI);
    return SnellPath{floor, floor + u * (2.0 * kT * tanT)};
  };
  auto onLamp = [](dvec3 q) { return q.x >= 0.0 && q.x <= 6.0 && std::abs(q.z) <= 6.0; };
  auto nearEdge = [](dvec3 q, double eps) {
    const bool inZ = std::abs(q.z) <= 6.0 + eps, inX = q.x >= -eps && q.x <= 6.0 + eps;
    return (inZ && (std::abs(q.x) < eps || std::abs(q.x - 6.0) < eps)) || (inX && std::abs(std::abs(q.z) - 6.0) < eps);
  };

  int checked = 0, mismatches = 0, refractionMatters = 0, brightChecked = 0;
  double worstBright = 0.0;
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i) {
      const dvec3 v = cam.pixelDir(i, j);
      ASSERT_LT(v.y, -0.1) << "every pixel looks down through the slab top";
      const SnellPath path = floorSnell(v);
      const dvec3 q = path.floor;
      if (nearEdge(q, 0.01)) continue;
      ++checked;
      const bool predicted = onLamp(q);
      refractionMatters += predicted != onLamp(floorStraight(v));
      const double g = linearOf(img.at(i, j, 1));
      const bool bright = g > 0.5 * kEmission * 0.75;  // halfway between black and (1-R)^2 E >= 0.75 E
      if (bright != predicted && ++mismatches <= 3)
        ADD_FAILURE() << "pixel (" << i << "," << j << "): rendered " << (bright ? "lamp" : "black") << " (green "
                      << int(img.at(i, j, 1)) << "), Snell predicts floor point (" << q.x << ", " << q.z << ")";
      if (predicted && !nearEdge(path.second, 0.01)) {
        // Enter and leave: Schlick's R at the outside angle both times (the cosine on the thinner side),
        // (1 - R)^2 E; plus the path reflected inside once off the bottom and once off the top,
        // (1 - R)^2 R^2 E where it lands on the lamp (up to 1.3% of E at these angles). Longer paths
        // exceed max_depth = 6.
        const double R = schlick(-v.y, 1.0, kIor);
        const double L = kEmission * (1.0 - R) * (1.0 - R) * (1.0 + (onLamp(path.second) ? R * R : 0.0));
        const double err = std::abs(img.at(i, j, 1) - expected8(L));
        worstBright = std::max(worstBright, err);
        if (err > kStepTolerance && ++mismatches <= 3)
          ADD_FAILURE() << "pixel (" << i << "," << j << "): green " << int(img.at(i, j, 1)) << ", Fresnel gives "
                        << expected8(L);
        ++brightChecked;
      }
    }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(checked, W * H * 9 / 10);
  EXPECT_GT(brightChecked, W * H / 4);
  // The test has power: without refraction many more pixels would see the lamp (or not).
  EXPECT_GT(refractionMatters, 3 * W) << "the slab must displace the edge by several pixels";

  // The centre column crosses the lamp's near edge x = 0: where the rendered image turns bright,
  // the straight ray would land at x = the horizontal shift. Measured (bracketed by two pixel
  // centres) against T (tan i - tan t), and as a lateral shift against T sin(i - t) / cos t.
  const int col = W / 2;
  int edge = -1;
  for (int j = 0; j + 1 < H && edge < 0; ++j)
    if (linearOf(img.at(col, j, 1)) < 0.2 && linearOf(img.at(col, j + 1, 1)) > 0.4) edge = j;
  ASSERT_GE(edge, 0) << "no dark-to-bright edge in the centre column";
  const double lo = floorStraight(cam.pixelDir(col, edge)).x, hi = floorStraight(cam.pixelDir(col, edge + 1)).x;
  const dvec3 vEdge = cam.dir(col + 0.5, edge + 1.0);
  const double cosI = -vEdge.y, thetaI = std::acos(cosI), thetaT = std::asin(std::sin(thetaI) / kIor);
  const double horizontal = kT * (std::tan(thetaI) - std::tan(thetaT));
  const double lateral = kT * std::sin(thetaI - thetaT) / std::cos(thetaT);
  EXPECT_LE(lo, horizontal);
  EXPECT_GE(hi, horizontal);
  std::printf("[ measured ] slab T=%.1f ior %.1f, incidence %.1f deg: edge seen at straight-ray x in [%.4f, %.4f],"
              " formula T(tan i - tan t) = %.4f; lateral shift measured %.4f +- %.4f, T sin(i-t)/cos t = %.4f;"
              " %d of %d pixels checked, %d decided by refraction; bright max err %.2f steps\n",
              kT, kIor, glm::degrees(thetaI), lo, hi, horizontal, 0.5 * (lo + hi) * cosI, 0.5 * (hi - lo) * cosI,
              lateral, checked, W * H, refractionMatters, worstBright);
}

// ---- hard shadows from a point light ---------------------------------------------------------------

struct Sphere {
  dvec3 c;
  double r;
};
struct Box {
  dvec3 lo, hi;
};

// Nearest t > 0 of the ray o + t v on a sphere / box, or +inf.
double raySphere(dvec3 o, dvec3 v, const Sphere& s) {
  const dvec3 oc = o - s.c;
  const double b = glm::dot(oc, v), c = glm::dot(oc, oc) - s.r * s.r, disc = b * b - c;
  if (disc < 0.0) return INFINITY;
  const double t = -b - std::sqrt(disc);
  return t > 0.0 ? t : INFINITY;
}
double rayBox(dvec3 o, dvec3 v, const Box& b) {
  double t0 = 0.0, t1 = INFINITY;
  for (int a = 0; a < 3; ++a) {
    if (v[a] == 0.0) {
      if (o[a] < b.lo[a] || o[a] > b.hi[a]) return INFINITY;
      continue;
    }
    double n = (b.lo[a] - o[a]) / v[a], f = (b.hi[a] - o[a]) / v[a];
    if (n > f) std::swap(n, f);
    t0 = std::max(t0, n), t1 = std::min(t1, f);
  }
  return t0 <= t1 ? t0 : INFINITY;
}

// A grey infinite floor lit by one point light (and world ambient), with a sphere and an axis-aligned
// box between them, seen from straight above. A floor point is in shadow exactly when the segment from
// it to the light meets an occluder (the shadow's outline is the occluders' outline projected from the
// light through similar triangles). Expected colour: ambient, plus Lambert where the light is seen.
// Pixels within 0.01 units (~1/6 pixel) of a shadow or silhouette boundary are not judged (the
// shader's shadow ray starts 1e-4 of the hit's magnitude off the floor; float rounding): both other
// classes are, at 1 step.
TEST(Shading, PointLightShadowsFallWhereSimilarTrianglesPutThem) {
  const dvec3 light(-0.5, 3.0, 0.2);
  const double intensity = 0.8, albedo = 0.7, ka = 0.5, ambient = 0.3;
  const Sphere sphere{{-1.2, 1.0, -0.6}, 0.5};
  const Box box{{0.6, 0.4, -0.1}, {1.4, 1.2, 0.7}};
  // Beyond the light (and outside the camera's view): on the line from the light back to the floor
  // around (3.25, 0, 0.2), so it would shadow that floor if shadow rays did not stop at the light.
  const Sphere beyond{{-3.0, 5.0, 0.2}, 0.5};
  auto p = prepareToml(R"(
[camera]
eye = [0, 8, 0]
target = [0, 0, 0]
up = [0, 0, -1]
fov = 40
[world]
kind = "color"
color = [0, 0, 0]
ambient = [0.3, 0.3, 0.3]
[[light]]
kind = "point"
position = [-0.5, 3, 0.2]
intensity = 0.8
[[material]]
name = "floor"
color = [0.7, 0.7, 0.7]
ambient = 0.5
[[material]]
name = "block"
color = [0.9, 0.2, 0.2]
[[object]]
kind = "plane"
infinite = true
material = "floor"
[[object]]
kind = "sphere"
material = "block"
translate = [-1.2, 1, -0.6]
scale = 0.5
[[object]]
kind = "box"
material = "block"
translate = [1, 0.8, 0.3]
scale = 0.4
[[object]]
kind = "sphere"
material = "block"
translate = [-3, 5, 0.2]
scale = 0.5
)");
  constexpr int W = 128, H = 96;
  const Image img = render(*p, W, H);
  const PinholeCamera cam(p->scene.camera, W, H);

  auto inShadow = [&](dvec3 q) {
    const dvec3 d = light - q;
    const double len = glm::length(d);
    const dvec3 v = d / len;
    return raySphere(q, v, sphere) < len || rayBox(q, v, box) < len || raySphere(q, v, beyond) < len;
  };
  auto seesFloor = [&](dvec3 v) {
    return std::min({raySphere(cam.eye, v, sphere), rayBox(cam.eye, v, box), raySphere(cam.eye, v, beyond)}) == INFINITY;
  };
  // The sphere beyond the light is not in view (the floor it would wrongly shadow is: wouldBeShadowed).
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i) ASSERT_EQ(raySphere(cam.eye, cam.pixelDir(i, j), beyond), INFINITY);
  int wouldBeShadowed = 0;  // floor pixels in view that the sphere beyond the light lines up with

  int lit = 0, shadowed = 0, failures = 0;
  double worst = 0.0;
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i) {
      // Silhouettes of the occluders themselves: judged only where the whole +-0.2 pixel neighbourhood agrees.
      const dvec3 v = cam.pixelDir(i, j);
      bool floor = seesFloor(v), ambiguous = false;
      for (double dx : {-0.2, 0.2})
        for (double dy : {-0.2, 0.2}) ambiguous |= seesFloor(cam.dir(i + 0.5 + dx, j + 0.5 + dy)) != floor;
      if (!floor || ambiguous) continue;
      const dvec3 q = cam.eye + (-cam.eye.y / v.y) * v;
      const bool shadow = inShadow(q);
      {
        const dvec3 toLight = glm::normalize(light - q);
        wouldBeShadowed += !shadow && raySphere(q, toLight, beyond) < INFINITY;
      }
      for (double dx : {-0.01, 0.01})
        for (double dz : {-0.01, 0.01}) ambiguous |= inShadow(q + dvec3(dx, 0.0, dz)) != shadow;
      if (ambiguous) continue;
      const double cosTheta = glm::normalize(light - q).y;
      const double L = albedo * ka * ambient + (shadow ? 0.0 : intensity * albedo * cosTheta);
      const double err = std::abs(img.at(i, j, 0) - expected8(L));
      worst = std::max(worst, err);
      if (err > kStepTolerance && ++failures <= 3)
        ADD_FAILURE() << "floor pixel (" << i << "," << j << ") at (" << q.x << ", " << q.z << "): rendered "
                      << int(img.at(i, j, 0)) << ", expected " << expected8(L) << (shadow ? " (in shadow)" : " (lit)");
      (shadow ? shadowed : lit)++;
    }
  EXPECT_EQ(failures, 0);
  EXPECT_GT(shadowed, 200) << "both shadows must be in view";
  EXPECT_GT(lit, W * H / 2);
  EXPECT_GT(wouldBeShadowed, 50) << "shadow rays that overshoot the light would darken these";

  // Similar triangles, measured: along the image row through the box's centre z, the box's shadow ends
  // where the ray from the light over the box's top far edge (x = 1.4, y = 1.2) reaches the floor:
  // x = Lx + (1.4 - Lx) Ly / (Ly - 1.2).
  const double predicted = light.x + (box.hi.x - light.x) * light.y / (light.y - box.hi.y);
  // Image columns run along +x here (right = forward x up = +x), rows along -z: take the row whose
  // centre-column floor point is nearest z = 0.3 (the box's centre).
  auto floorAt = [&](int i, int j) { return cam.eye + (-cam.eye.y / cam.pixelDir(i, j).y) * cam.pixelDir(i, j); };
  int row = 0;
  for (int j = 1; j < H; ++j)
    if (std::abs(floorAt(W / 2, j).z - 0.3) < std::abs(floorAt(W / 2, row).z - 0.3)) row = j;
  double lastShadowX = NAN, firstLitX = NAN;
  const double litLevel = expected8(albedo * ka * ambient) + 10.0;
  for (int i = 0; i < W; ++i) {
    const dvec3 v = cam.pixelDir(i, row);
    if (!seesFloor(v)) continue;
    const dvec3 q = cam.eye + (-cam.eye.y / v.y) * v;
    if (q.x < box.hi.x) continue;  // beyond the box, towards +x
    if (img.at(i, row, 0) < litLevel) lastShadowX = std::isnan(lastShadowX) ? q.x : std::max(lastShadowX, q.x);
    else if (std::isnan(firstLitX) || q.x < firstLitX) firstLitX = q.x;
  }
  ASSERT_FALSE(std::isnan(lastShadowX)) << "the box's shadow is not visible beyond the box";
  ASSERT_FALSE(std::isnan(firstLitX));
  EXPECT_LE(lastShadowX, predicted);
  EXPECT_GE(firstLitX, predicted);
  std::printf("[ measured ] shadows: %d lit (%d of them lined up with the sphere beyond the light) + %d shadowed"
              " floor pixels within %.2f steps; box shadow edge between x = %.4f and %.4f (pixel centres),"
              " similar triangles %.4f\n", lit, wouldBeShadowed, shadowed, worst, lastShadowX, firstLitX, predicted);
}

}  // namespace
}  // namespace bvhlab::test
