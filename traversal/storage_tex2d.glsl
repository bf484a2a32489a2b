// storage_tex2d.glsl — the texel streams of layout/layout.hpp (VERTEX: layout/triangle_formats.hpp) as 2D integer textures of width
// kTex2DWidth, texel i at (i % W, i / W); the last row is padded. C++ mirror: storage.hpp.
const int kTex2DWidth = 4096;  // = bvhlab::kTex2DWidth

uniform usampler2D u_nodes;
uniform usampler2D u_triangles;
uniform usampler2D u_attributes;
uniform usampler2D u_vertices;

ivec2 tex2DCoord(int texel) { return ivec2(texel % kTex2DWidth, texel / kTex2DWidth); }

uvec4 fetchNode(int texel) { return texelFetch(u_nodes, tex2DCoord(texel), 0); }
uvec4 fetchTriangle(int texel) { return texelFetch(u_triangles, tex2DCoord(texel), 0); }
uvec4 fetchAttribute(int texel) { return texelFetch(u_attributes, tex2DCoord(texel), 0); }
uvec4 fetchVertex(int texel) { return texelFetch(u_vertices, tex2DCoord(texel), 0); }
