#include "traversal/robustness.hpp"

#include <stdexcept>

namespace bvhlab {

namespace {

std::string nameOf(Robustness r) {
  if (r == Robustness::Fast) return "fast";
  if (r == Robustness::Watertight) return "watertight";
  std::string name;
  auto add = [&](bool on, const char* part) {
    if (on) name += (name.empty() ? "" : "+") + std::string(part);
  };
  add(r.triangle == TriangleTest::Watertight, "tri");
  add(r.box == BoxTest::Robust, "box");
  add(r.offset == OriginOffset::Ulp, "ulp");
  return name;
}

// Listed by the number of robust knobs, then in the order tri, box, ulp: a table reads from the
// cheapest variant to the most robust one.
std::vector<Robustness> makeVariants() {
  std::vector<Robustness> out;
  for (int bits : {0, 1, 2, 4, 3, 5, 6, 7})  // tri = 1, box = 2, ulp = 4
    out.push_back(Robustness{bits & 1 ? TriangleTest::Watertight : TriangleTest::MollerTrumbore,
                             bits & 2 ? BoxTest::Robust : BoxTest::Slab,
                             bits & 4 ? OriginOffset::Ulp : OriginOffset::Epsilon});
  return out;
}

struct Table {
  std::vector<Robustness> variants = makeVariants();
  std::vector<std::string> names;
  Table() {
    for (Robustness r : variants) names.push_back(nameOf(r));
  }
};

const Table& table() {
  static const Table t;
  return t;
}

}  // namespace

Robustness parseRobustness(const std::string& name) {
  const Table& t = table();
  for (size_t i = 0; i < t.names.size(); ++i)
    if (t.names[i] == name) return t.variants[i];
  std::string valid;
  for (const std::string& n : t.names) valid += (valid.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown robustness variant '" + name + "' (valid: " + valid + ")");
}

const char* robustnessName(Robustness r) {
  const Table& t = table();
  for (size_t i = 0; i < t.variants.size(); ++i)
    if (t.variants[i] == r) return t.names[i].c_str();
  throw std::logic_error("robustnessName: a variant outside the table");  // every knob combination is listed
}

const std::vector<std::string>& robustnessNames() { return table().names; }
const std::vector<Robustness>& robustnessVariants() { return table().variants; }

const char* triangleTestName(TriangleTest t) { return t == TriangleTest::Watertight ? "watertight" : "moller-trumbore"; }
const char* boxTestName(BoxTest b) { return b == BoxTest::Robust ? "ize" : "slab"; }
const char* originOffsetName(OriginOffset o) { return o == OriginOffset::Ulp ? "ulp" : "epsilon"; }

}  // namespace bvhlab
