// storage_tbo.glsl — the texel streams of layout/layout.hpp (VERTEX: layout/triangle_formats.hpp) as texture buffers (the default
// storage kind). Texel i of a stream is texelFetch(stream, i). C++ mirror: storage.hpp.
uniform usamplerBuffer u_nodes;
uniform usamplerBuffer u_triangles;
uniform usamplerBuffer u_attributes;
uniform usamplerBuffer u_vertices;

uvec4 fetchNode(int texel) { return texelFetch(u_nodes, texel); }
uvec4 fetchTriangle(int texel) { return texelFetch(u_triangles, texel); }
uvec4 fetchAttribute(int texel) { return texelFetch(u_attributes, texel); }
uvec4 fetchVertex(int texel) { return texelFetch(u_vertices, texel); }
