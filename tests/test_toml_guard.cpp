// datasets/toml_guard.hpp: the code points that toml++ 3.3.0 cannot test for whitespace without
// undefined behaviour, and the pre-check that refuses them before the scene and config readers parse.
#include <cstdint>
#include <string>

#include <gtest/gtest.h>
#include <toml++/toml.h>

#include "datasets/toml_guard.hpp"

namespace {

using bvhlab::findTomlTextHazard;
using bvhlab::tomlppWhitespaceHazard;

// The edges of the three hazardous ranges, computed outside this code from the library's function
// (chunks of 0x3FA from U+00A0, mask 0x7FFFFFFFFFFFF75E, cases 5 and 7): U+00A1-U+0499,
// U+2C5E-U+3057 but U+3000, U+FB26-U+FEFE.
TEST(TomlGuard, HazardousCodePointsAreTheLibrarysUnreachableOnes) {
  for (uint32_t c : {0xA1u, 0xE9u, 0x499u, 0x2C5Eu, 0x2C67u, 0x2D6Eu, 0x3001u, 0x3057u, 0xFB26u, 0xFEFEu})
    EXPECT_TRUE(tomlppWhitespaceHazard(c)) << std::hex << c;
  // Whitespace the library answers for (U+00A0, U+1680, U+2000, U+3000, U+FEFF), its switched chunks
  // (5: U+1482-U+187B, 7: U+1C76-U+206F), the chunks its mask answers false for, and the edges.
  for (uint32_t c : {0x20u, 0x7Fu, 0xA0u, 0x49Au, 0x1680u, 0x1500u, 0x2000u, 0x2060u, 0x2C5Du, 0x3000u, 0x3058u,
                     0x3167u, 0xFB06u, 0xFB25u, 0xFEFFu, 0x1F600u})
    EXPECT_FALSE(tomlppWhitespaceHazard(c)) << std::hex << c;
}

// Every code point the guard lets through, asked of the library itself: under `bash setup.sh sanitize`
// (UBSan) one that reaches the library's unreachable point fails this test; in any build the library
// must find exactly its 20 non-ASCII horizontal whitespace code points among them.
TEST(TomlGuard, TheLibraryAnswersEveryCodePointTheGuardLetsThrough) {
  uint32_t asked = 0, whitespace = 0;
  for (char32_t c = 0; c < 0x110000; ++c) {
    if (tomlppWhitespaceHazard(uint32_t(c))) continue;
    ++asked;
    whitespace += toml::impl::is_non_ascii_horizontal_whitespace(c) ? 1 : 0;
  }
  EXPECT_EQ(asked, 0x110000u - (0x499u - 0xA1u + 1) - (0x3057u - 0x2C5Eu) - (0xFEFEu - 0xFB26u + 1));
  EXPECT_EQ(whitespace, 20u);
}

TEST(TomlGuard, RefusesAHazardOutsideCommentsAndNamesWhere) {
  // U+2C67 after a bare key: the input fuzz_config found (tests/fuzz/regressions/config/).
  const auto h = findTomlTextHazard("a = 1\ns\xE2\xB1\xA7 = 2\n");
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->line, 2);
  EXPECT_EQ(h->column, 2);
  EXPECT_NE(h->message.find("U+2C67"), std::string::npos);
  EXPECT_NE(h->message.find("\\u2C67"), std::string::npos);
  // In a comment it is left alone; so is a code point outside the ranges anywhere.
  EXPECT_FALSE(findTomlTextHazard("a = 1 # s\xE2\xB1\xA7\n").has_value());
  EXPECT_FALSE(findTomlTextHazard("name = \"\xE3\x81\x98\"\n").has_value());  // U+3058
}

}  // namespace
