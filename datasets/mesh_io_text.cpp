// The line/token scanner and number parsing shared by the mesh readers (mesh_io_detail.hpp).
#include <charconv>
#include <cmath>

#include "datasets/mesh_io_detail.hpp"

namespace bvhlab::meshio {

void failAt(size_t line, std::string message) { throw MeshFileError{line, std::move(message)}; }
void fail(std::string message) { throw MeshFileError{0, std::move(message)}; }

bool LineScanner::next(std::string_view& line) {
  if (pos >= text.size()) return false;
  size_t end = text.find('\n', pos);
  if (end == std::string_view::npos) end = text.size();
  line = text.substr(pos, end - pos);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  pos = end + 1;
  ++lineNo;
  return true;
}

namespace {
bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }
}  // namespace

std::vector<std::string_view> tokens(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && isBlank(line[i])) ++i;
    size_t j = i;
    while (j < line.size() && !isBlank(line[j])) ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

std::string printable(std::string_view token) {
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (size_t i = 0; i < token.size() && i < 32; ++i) {
    const unsigned char c = token[i];
    if (c >= 0x20 && c < 0x7f) {
      out += char(c);
    } else {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  if (token.size() > 32) out += "...";
  return out;
}

std::string quoted(std::string_view token) {
  std::string out(1, '\'');  // built with += : GCC 12 warns falsely (-Wrestrict) on "'" + s + "'"
  out += printable(token);
  out += '\'';
  return out;
}

std::optional<double> parseReal(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);  // from_chars rejects a leading '+'
  double v = 0.0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

std::optional<long long> parseInt(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  long long v = 0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

void expectReals(const std::vector<std::string_view>& toks, size_t first, size_t count, size_t line, const char* what,
                 std::vector<double>* out) {
  if (toks.size() < first + count)
    failAt(line, std::string(what) + ": expected " + std::to_string(count) + " numbers, found " +
                     std::to_string(toks.size() > first ? toks.size() - first : 0));
  for (size_t i = first; i < first + count; ++i) {
    auto v = parseReal(toks[i]);
    if (!v) failAt(line, std::string(what) + ": " + quoted(toks[i]) + " is not a number");
    if (!std::isfinite(*v)) failAt(line, std::string(what) + ": value " + quoted(toks[i]) + " is NaN or infinite");
    if (out) out->push_back(*v);
  }
}

}  // namespace bvhlab::meshio
