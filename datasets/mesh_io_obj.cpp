// Wavefront OBJ: our structural pass (mesh_io_detail.hpp) — v / vt / vn lines hold finite numbers
// (positions kept in double), f lines have >= 3 corners whose indices resolve.
#include "datasets/mesh_io_detail.hpp"

namespace bvhlab::meshio {

Scanned scanObj(std::string_view text) {
  LineScanner sc{text};
  std::string_view line;
  Scanned out;
  long long nV = 0, nT = 0, nN = 0;
  size_t nF = 0;
  // Positive indices may point forward, so they are checked once all counts are known: keep, per
  // element kind, the largest index seen and the line that holds it.
  struct MaxRef { long long index = 0; size_t line = 0; };
  MaxRef maxRef[3];
  std::vector<double> xyz;
  while (sc.next(line)) {
    auto t = tokens(line);
    if (t.empty() || t[0].front() == '#') continue;
    if (t[0] == "v") {
      xyz.clear();
      expectReals(t, 1, 3, sc.lineNo, "vertex", &xyz);
      out.positions.emplace_back(xyz[0], xyz[1], xyz[2]);
      ++nV;
    } else if (t[0] == "vt") { expectReals(t, 1, 2, sc.lineNo, "texture coordinate"); ++nT; }
    else if (t[0] == "vn") { expectReals(t, 1, 3, sc.lineNo, "normal"); ++nN; }
    else if (t[0] == "f") {
      if (t.size() < 4) failAt(sc.lineNo, "face with " + std::to_string(t.size() - 1) + " corners (need at least 3)");
      for (size_t c = 1; c < t.size(); ++c) {
        // corner = v | v/vt | v//vn | v/vt/vn
        std::string_view corner = t[c];
        const long long counts[3] = {nV, nT, nN};
        for (int part = 0; part < 3 && !corner.empty(); ++part) {
          const size_t slash = corner.find('/');
          std::string_view field = corner.substr(0, slash);
          corner = slash == std::string_view::npos ? std::string_view() : corner.substr(slash + 1);
          if (field.empty()) {
            if (part == 0) failAt(sc.lineNo, "face corner " + quoted(t[c]) + " has no vertex index");
            continue;
          }
          auto idx = parseInt(field);
          if (!idx) failAt(sc.lineNo, "face: " + quoted(t[c]) + " is not a valid corner");
          if (*idx == 0) failAt(sc.lineNo, "face: index 0 in " + quoted(t[c]) + " (OBJ indices start at 1)");
          if (*idx < 0 && -*idx > counts[part])
            failAt(sc.lineNo, "face: relative index " + std::to_string(*idx) + " in " + quoted(t[c]) +
                                  " points before the first element");
          if (*idx > maxRef[part].index) maxRef[part] = {*idx, sc.lineNo};
        }
      }
      ++nF;
    }
  }
  const long long counts[3] = {nV, nT, nN};
  const char* what[3] = {"vertex", "texture coordinate", "normal"};
  for (int part = 0; part < 3; ++part)
    if (maxRef[part].index > counts[part])
      failAt(maxRef[part].line, std::string("face: ") + what[part] + " index " + std::to_string(maxRef[part].index) +
                                    " out of range (file has " + std::to_string(counts[part]) + ")");
  out.vertices = size_t(nV);
  out.faces = nF;
  return out;
}

}  // namespace bvhlab::meshio
