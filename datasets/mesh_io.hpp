// Triangle meshes from files: OBJ, OFF (ASCII), PLY (ASCII and binary), STL (ASCII and binary).
//
// OpenMesh's readers do the parsing into a plain indexed triangle soup (no half-edge topology, so
// non-manifold scans lose nothing). OpenMesh accepts many broken files silently or loops on absurd
// counts, so every file first goes through a cheap structural pre-check of our own (header counts
// against file size, line shapes, index ranges, NaN/Inf), and the result is validated again after.
// Every problem is one InputError line: "PATH[:LINE]: message".
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "datasets/scene.hpp"

namespace bvhlab {

// Loads a mesh in its own (object) space. Polygons are fan-triangulated (exact for convex faces).
// Normals and UVs are kept when the file gives one for every vertex (OBJ: one per position, last
// wins), otherwise left empty. Mesh::name is the path; Mesh::material is 0.
Mesh loadMesh(const std::filesystem::path& path);

// Lower-case extensions (with the dot) that loadMesh reads: .obj .off .ply .stl
const std::vector<std::string>& meshExtensions();
bool isMeshFile(const std::filesystem::path& path);  // by extension only

// Writes a mesh as a Wavefront OBJ (positions, normals/UVs when present); atomic like the image
// writers. For tests, debugging and exporting procedural meshes.
void saveMeshObj(const std::filesystem::path& path, const Mesh& mesh);

}  // namespace bvhlab
