// Skips that CI turns into failures. A test that cannot run here (no fetched data, no GL context, a
// tool setup.sh installs is missing) skips with its reason on a developer's machine; with the
// environment variable BVHLAB_REQUIRE_ALL=1 (set by .ci/run, where setup.sh has installed every
// package and fetched the data) the same reason is a failure, so a skip can never pass for a check.
// Skips whose reason can hold on a CI machine too (a sanitizer build's own allocator) stay GTEST_SKIP.
#pragma once
#include <cstdlib>
#include <cstring>

#include <gtest/gtest.h>

namespace bvhlab::test {

inline bool requireAll() {
  const char* v = std::getenv("BVHLAB_REQUIRE_ALL");
  return v != nullptr && std::strcmp(v, "1") == 0;
}

}  // namespace bvhlab::test

// BVHLAB_SKIP_OR_FAIL(reason): `reason` is a stream chain (`path << " is missing"`). Returns from the
// test body (or the void helper it is used in) like GTEST_SKIP / FAIL.
#define BVHLAB_SKIP_OR_FAIL(reason)                                                              \
  do {                                                                                           \
    if (::bvhlab::test::requireAll())                                                            \
      GTEST_FAIL() << "BVHLAB_REQUIRE_ALL=1, so this is a failure, not a skip: " << reason;      \
    else                                                                                         \
      GTEST_SKIP() << reason;                                                                    \
  } while (0)
