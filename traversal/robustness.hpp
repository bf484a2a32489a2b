// Robustness variants: three independent knobs, each chosen at shader-assembly time
// (shaders/assemble.cpp picks the GLSL module) and mirrored in C++ (traversal/intersectors.hpp for the
// two intersection tests, shaders/tracer.cpp for the origin offset).
//
//   knob            cheap                                  robust                                    name part
//   triangle test   Moller-Trumbore (ray_triangle.glsl)    watertight, Woop et al. 2013              "tri"
//                                                          (ray_triangle_watertight.glsl)
//   box test        slab test (ray_box.glsl)               Ize 2013 conservative slabs               "box"
//                                                          (ray_box_robust.glsl)
//   origin offset   fixed relative epsilon (shade.glsl)    Waechter & Binder ULP offset              "ulp"
//                                                          (offset_ulp.glsl)
//
// A variant's name lists its robust knobs in that order joined by '+': "fast" has none, "watertight"
// all three, and in between "tri", "box", "ulp", "tri+box", "tri+ulp", "box+ulp".
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace bvhlab {

enum class TriangleTest : uint8_t { MollerTrumbore, Watertight };
enum class BoxTest : uint8_t { Slab, Robust };
enum class OriginOffset : uint8_t { Epsilon, Ulp };

struct Robustness {
  TriangleTest triangle = TriangleTest::MollerTrumbore;
  BoxTest box = BoxTest::Slab;
  OriginOffset offset = OriginOffset::Epsilon;

  static const Robustness Fast;        // every knob cheap (the seed's; `--robust fast`)
  static const Robustness Watertight;  // every knob robust (the renderer's default: shaders/assemble.hpp)

  friend constexpr bool operator==(const Robustness&, const Robustness&) = default;
  // Which of the four (triangle test, box test) instantiations of a kernel mirror this variant runs:
  // 2 * triangle + box (the origin offset is the tracer's business, not the kernel's).
  constexpr int testsIndex() const { return 2 * int(triangle) + int(box); }
};
inline constexpr Robustness Robustness::Fast{};
inline constexpr Robustness Robustness::Watertight{TriangleTest::Watertight, BoxTest::Robust, OriginOffset::Ulp};

// Throws std::invalid_argument naming every valid name when `name` is not one of robustnessNames().
Robustness parseRobustness(const std::string& name);
const char* robustnessName(Robustness r);
// Every name parseRobustness accepts, one per variant: "fast", the single knobs, the pairs, "watertight".
const std::vector<std::string>& robustnessNames();
// The variants in robustnessNames() order.
const std::vector<Robustness>& robustnessVariants();

// The knobs' own names, for tables and JSON.
const char* triangleTestName(TriangleTest t);  // "moller-trumbore" | "watertight"
const char* boxTestName(BoxTest b);            // "slab" | "ize"
const char* originOffsetName(OriginOffset o);  // "epsilon" | "ulp"

}  // namespace bvhlab
