// A pre-check for TOML text before it reaches toml++ 3.3.0 (Debian 12's libtomlplusplus-dev).
//
// toml++ 3.3.0's is_non_ascii_horizontal_whitespace() reaches __builtin_unreachable() (undefined
// behaviour) for the code points U+00A1-U+0499, U+2D6E-U+3167 (but U+3000) and U+FB06-U+FEFE whenever the
// parser asks whether one of them is whitespace: after a value or a key, in a quoted key, after a
// backslash in a multi-line basic string (marzer/tomlplusplus#190, fixed upstream after 3.3.0). Found
// by tests/fuzz/fuzz_config (bash setup.sh fuzz). Until the distribution's toml++ is fixed, such a
// code point is refused everywhere but in a comment, with a message that says how to write it instead
// (a \uXXXX escape in a basic string). Every other byte is left for toml++ to judge.
#pragma once
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <string_view>

namespace bvhlab {

struct TomlTextHazard {
  int line = 1, column = 1;  // 1-based; the column counts bytes
  std::string message;
};

// True for the code points toml++ 3.3.0 cannot test for whitespace without undefined behaviour.
inline bool tomlppWhitespaceHazard(uint32_t c) {
  return (c >= 0xA1 && c <= 0x499) || (c >= 0x2D6E && c <= 0x3167 && c != 0x3000) || (c >= 0xFB06 && c <= 0xFEFE);
}

// The first hazardous code point outside a comment, if any. Strings and comments are tracked as TOML
// 1.0 delimits them, so a '#' inside a string is not a comment.
inline std::optional<TomlTextHazard> findTomlTextHazard(std::string_view text) {
  enum class State { Normal, Comment, Basic, Literal, MultiBasic, MultiLiteral } state = State::Normal;
  int line = 1;
  size_t lineStart = 0;
  bool escape = false;  // the previous character was an unescaped backslash (basic strings)
  const auto startsWith = [&](size_t i, std::string_view s) { return text.substr(i, s.size()) == s; };
  for (size_t i = 0; i < text.size();) {
    const unsigned char b = static_cast<unsigned char>(text[i]);
    if (b >= 0x80) {
      // Decode one UTF-8 sequence; invalid UTF-8 is toml++'s to reject, byte by byte here.
      uint32_t c = 0;
      size_t n = 0;
      if (b >= 0xC2 && b <= 0xDF) c = b & 0x1F, n = 2;
      else if (b >= 0xE0 && b <= 0xEF) c = b & 0x0F, n = 3;
      else if (b >= 0xF0 && b <= 0xF4) c = b & 0x07, n = 4;
      bool valid = n > 0 && i + n <= text.size();
      for (size_t k = 1; valid && k < n; ++k) {
        const unsigned char cb = static_cast<unsigned char>(text[i + k]);
        valid = (cb & 0xC0) == 0x80;
        c = (c << 6) | (cb & 0x3F);
      }
      if (!valid) n = 1;
      if (valid && state != State::Comment && tomlppWhitespaceHazard(c)) {
        char hex[16];
        std::snprintf(hex, sizeof hex, "U+%04X", unsigned(c));
        char esc[16];
        std::snprintf(esc, sizeof esc, "\\u%04X", unsigned(c));
        return TomlTextHazard{line, int(i - lineStart) + 1,
                              std::string("character ") + hex +
                                  " is not accepted outside comments: the TOML library (toml++ 3.3.0) cannot read it safely; "
                                  "inside a \"double-quoted\" string write it as " + esc};
      }
      escape = false;
      i += n;
      continue;
    }
    const char ch = static_cast<char>(b);
    if (ch == '\n') {
      ++line;
      lineStart = i + 1;
      if (state == State::Comment || state == State::Basic || state == State::Literal) state = State::Normal;
      escape = false;
      ++i;
      continue;
    }
    switch (state) {
      case State::Normal:
        if (ch == '#') state = State::Comment;
        else if (startsWith(i, "\"\"\"")) state = State::MultiBasic, i += 2;
        else if (startsWith(i, "'''")) state = State::MultiLiteral, i += 2;
        else if (ch == '"') state = State::Basic;
        else if (ch == '\'') state = State::Literal;
        break;
      case State::Comment: break;
      case State::Literal:
        if (ch == '\'') state = State::Normal;
        break;
      case State::MultiLiteral:
        if (startsWith(i, "'''")) {
          i += 2;
          while (i + 1 < text.size() && text[i + 1] == '\'') ++i;  // ''''' : up to two quotes of content
          state = State::Normal;
        }
        break;
      case State::Basic:
      case State::MultiBasic:
        if (escape) {
          escape = false;
        } else if (ch == '\\') {
          escape = true;
        } else if (state == State::Basic && ch == '"') {
          state = State::Normal;
        } else if (state == State::MultiBasic && startsWith(i, "\"\"\"")) {
          i += 2;
          while (i + 1 < text.size() && text[i + 1] == '"') ++i;
          state = State::Normal;
        }
        break;
    }
    ++i;
  }
  return std::nullopt;
}

}  // namespace bvhlab
