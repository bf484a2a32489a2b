// storage.hpp — C++ mirror of storage_tbo.glsl, storage_tex2d.glsl and storage_ssbo.glsl. Every GLSL storage kind
// return texel i of a stream; the mirror reads the PackedBvh's streams directly. A texel out of
// range throws std::out_of_range here (a kernel bug), where GLSL would read an undefined texel.
#pragma once
#include <array>
#include <bit>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "layout/layout.hpp"
#include "layout/triangle_formats.hpp"
#include "shaders/common.hpp"

namespace bvhlab {
int stackSizeFor(uint32_t treeDepth);  // traversal/kernels.hpp
int stackSizeFor(const PackedBvh& packed);
}

namespace bvhlab::glsl {

// What the GLSL reads from its uniforms and #defines, passed explicitly: the streams and
// BVH_STACK_SIZE.
struct Storage {
  const PackedBvh* bvh;
  int stackSize;  // BVH_STACK_SIZE
  // The triangle format's accessor module the shader assembler would pick (packed.triangleFormat):
  // the mirrors' triangle accessors switch on it (traversal/triangles_format.hpp).
  TriangleFormat triangles;

  // Implicit on purpose: a PackedBvh passes for a Storage, with the stack size the shader
  // assembler defines for it.
  Storage(const PackedBvh& packed) : Storage(packed, stackSizeFor(packed)) {}
  Storage(const PackedBvh& packed, int stackSize_)
      : bvh(&packed), stackSize(stackSize_), triangles(findTriangleFormat(packed.triangleFormat).format) {
    // GLSL refuses an array of size 0; the stack kernels push the root unconditionally.
    if (stackSize < 1) throw std::invalid_argument("BVH_STACK_SIZE must be >= 1, got " + std::to_string(stackSize));
  }
};

// GLSL's uintBitsToFloat / floatBitsToUint. GLM's vector versions reinterpret_cast between vector
// types, which breaks strict aliasing: GCC -O2 miscompiled them (tests/test_layout.cpp). These
// component-wise std::bit_cast overloads are found first in this namespace and win overload
// resolution against GLM's templates.
inline float uintBitsToFloat(uint v) { return std::bit_cast<float>(v); }
inline vec2 uintBitsToFloat(uvec2 v) { return vec2(uintBitsToFloat(v.x), uintBitsToFloat(v.y)); }
inline vec3 uintBitsToFloat(uvec3 v) { return vec3(uintBitsToFloat(v.x), uintBitsToFloat(v.y), uintBitsToFloat(v.z)); }
inline uint floatBitsToUint(float v) { return std::bit_cast<uint>(v); }
inline uvec3 floatBitsToUint(vec3 v) { return uvec3(floatBitsToUint(v.x), floatBitsToUint(v.y), floatBitsToUint(v.z)); }

// Bytes one fetch of any stream reads: every stream is RGBA32UI texels (layout/layout.hpp), whatever
// the storage kind (texture buffer, 2D texture, storage buffer). The mirrors' byte counters
// (Counters::nodeBytes, ...) are texels fetched times this.
constexpr uint kTexelBytes = uint(sizeof(uvec4));
static_assert(kTexelBytes == 16, "RGBA32UI texels");

inline uvec4 fetchNode(const Storage& s, int texel) { return s.bvh->nodes.at(size_t(texel)); }
inline uvec4 fetchTriangle(const Storage& s, int texel) { return s.bvh->triangles.at(size_t(texel)); }
inline uvec4 fetchAttribute(const Storage& s, int texel) { return s.bvh->attributes.at(size_t(texel)); }
inline uvec4 fetchVertex(const Storage& s, int texel) { return s.bvh->vertices.at(size_t(texel)); }

// GLSL `T stack[BVH_STACK_SIZE];`: a fixed-size local array, its size known only at run time
// here. Up to kInline entries live on the C++ stack (no allocation per ray); more go to the heap.
template <class T>
class StackArray {
 public:
  explicit StackArray(int size) : size_(size) {
    if (size > kInline) heap_.resize(size_t(size));
  }
  StackArray(const StackArray&) = delete;
  StackArray& operator=(const StackArray&) = delete;
  T& operator[](int i) { return size_ > kInline ? heap_[size_t(i)] : inline_[size_t(i)]; }

 private:
  static constexpr int kInline = 64;
  int size_;
  std::array<T, kInline> inline_;
  std::vector<T> heap_;
};

}  // namespace bvhlab::glsl
