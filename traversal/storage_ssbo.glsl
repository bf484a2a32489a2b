// storage_ssbo.glsl — the texel streams of layout/layout.hpp (VERTEX: layout/triangle_formats.hpp) as shader
// storage buffers (std430 uvec4 arrays, bindings 4..7: the ray tracer's own buffers take 0..2). Texel i of a
// stream is element i. The same buffer objects the texture buffers wrap, read without the sampler path.
// C++ mirror: storage.hpp.
layout(std430, binding = 4) readonly restrict buffer NodeStream { uvec4 s_nodes[]; };
layout(std430, binding = 5) readonly restrict buffer TriangleStream { uvec4 s_triangles[]; };
layout(std430, binding = 6) readonly restrict buffer AttributeStream { uvec4 s_attributes[]; };
layout(std430, binding = 7) readonly restrict buffer VertexStream { uvec4 s_vertices[]; };

uvec4 fetchNode(int texel) { return s_nodes[texel]; }
uvec4 fetchTriangle(int texel) { return s_triangles[texel]; }
uvec4 fetchAttribute(int texel) { return s_attributes[texel]; }
uvec4 fetchVertex(int texel) { return s_vertices[texel]; }
