// ASCII OFF: our structural pass (mesh_io_detail.hpp) — header, counts against the file size, every
// vertex line finite (positions kept in double), every face line's indices in range.
#include "datasets/mesh_io_detail.hpp"

namespace bvhlab::meshio {

// "[ST][C][N]OFF" line, "nV nF nE" line, nV vertex lines, nF face lines "k i0 .. ik-1".
Scanned scanOff(std::string_view text) {
  LineScanner sc{text};
  std::string_view line;
  sc.next(line);
  auto head = tokens(line);
  const std::string_view magic = head.empty() ? std::string_view() : head[0];
  const size_t off = magic.rfind("OFF");
  if (off == std::string_view::npos || off + 3 != magic.size()) failAt(1, "not an OFF file (no 'OFF' header)");
  const std::string_view prefix = magic.substr(0, off);
  if (prefix.find_first_of("4n") != std::string_view::npos) failAt(1, "OFF with 4D or n-D vertices is not supported");
  if (prefix.find_first_not_of("STCN") != std::string_view::npos) failAt(1, "unknown OFF header " + quoted(magic));
  const bool hasNormals = prefix.find('N') != std::string_view::npos;
  if (head.size() > 1 && head[1] == "BINARY") failAt(1, "binary OFF is not supported");
  if (head.size() > 1) failAt(1, "the vertex/face counts must be on the line after " + quoted(magic));

  if (!sc.next(line)) fail("truncated: no vertex/face count line");
  auto counts = tokens(line);
  if (counts.size() < 2) failAt(sc.lineNo, "expected 'vertices faces edges' counts");
  auto nV = parseInt(counts[0]), nF = parseInt(counts[1]);
  if (!nV || !nF || *nV < 0 || *nF < 0) failAt(sc.lineNo, "bad vertex/face counts");
  // Resource limit before anything is allocated: each vertex line needs >= 6 bytes ("0 0 0\n"), each
  // face line >= 8 ("3 0 1 2\n"), so counts the file cannot hold are refused here, whatever they claim.
  if (uint64_t(*nV) * 6 + uint64_t(*nF) * 8 > text.size())
    failAt(sc.lineNo, "truncated: header declares " + std::to_string(*nV) + " vertices and " + std::to_string(*nF) +
                          " faces but the file has only " + std::to_string(text.size()) + " bytes");

  auto nextContentLine = [&](const char* what, long long i, long long n) {
    do {
      if (!sc.next(line))
        fail("truncated: file ends after " + std::to_string(i) + " of " + std::to_string(n) + " " + what);
    } while (tokens(line).empty());
  };
  Scanned out{size_t(*nV), size_t(*nF), {}};
  out.positions.reserve(size_t(*nV));  // bounded by the file size above
  std::vector<double> xyz;
  for (long long i = 0; i < *nV; ++i) {
    nextContentLine("vertices", i, *nV);
    auto t = tokens(line);
    xyz.clear();
    expectReals(t, 0, 3, sc.lineNo, "vertex", &xyz);
    if (hasNormals) expectReals(t, 3, 3, sc.lineNo, "vertex");
    out.positions.emplace_back(xyz[0], xyz[1], xyz[2]);
  }
  for (long long i = 0; i < *nF; ++i) {
    nextContentLine("faces", i, *nF);
    auto t = tokens(line);
    auto k = parseInt(t[0]);
    if (!k) failAt(sc.lineNo, "face: " + quoted(t[0]) + " is not a vertex count");
    if (*k < 3) failAt(sc.lineNo, "face with " + std::to_string(*k) + " vertices (need at least 3)");
    if (size_t(*k) + 1 > t.size())
      failAt(sc.lineNo, "face: declares " + std::to_string(*k) + " vertices but lists " + std::to_string(t.size() - 1));
    for (long long j = 1; j <= *k; ++j) {
      auto idx = parseInt(t[j]);
      if (!idx) failAt(sc.lineNo, "face: " + quoted(t[j]) + " is not a vertex index");
      if (*idx < 0 || *idx >= *nV)
        failAt(sc.lineNo, "face: vertex index " + std::to_string(*idx) + " out of range [0, " + std::to_string(*nV) + ")");
    }
  }
  return out;
}

}  // namespace bvhlab::meshio
