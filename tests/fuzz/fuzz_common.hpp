// One libFuzzer entry point per parser: fuzz_NAME.cpp is BVHLAB_FUZZ_TARGET("NAME").
//
// A parser that returns a well-formed result or throws bvhlab::InputError is correct. Another
// std::runtime_error is accepted too (a clean, reported error; set BVHLAB_FUZZ_STRICT=1 to have those
// abort, to find messages that are not one "FILE:LINE: ..." InputError line). Anything else is a
// finding: a crash, an ASan or UBSan report, a hang (-timeout), running out of memory (-rss_limit_mb),
// a broken invariant (parsers.hpp), or an exception of another kind (std::logic_error from a stoi or an
// .at(), std::bad_alloc), which std::terminate turns into an abort.
#pragma once
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <typeinfo>

#include "parsers.hpp"

namespace bvhlab::fuzz {

// A private, empty directory for the input file(s) of this process, removed at exit.
inline const std::filesystem::path& scratchDir() {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path d =
        std::filesystem::temp_directory_path() / ("bvhlab-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(scratchDir(), ec);
    });
    return d;
  }();
  return dir;
}

inline int runOne(const char* parser, const uint8_t* data, size_t size) {
  static const bool strict = [] {
    const char* s = std::getenv("BVHLAB_FUZZ_STRICT");
    return s && *s && std::string(s) != "0";
  }();
  try {
    parseAs(parser, std::string_view(reinterpret_cast<const char*>(data), size), scratchDir());
  } catch (const InputError&) {
    // rejected with a message: correct
  } catch (const std::runtime_error& e) {
    if (strict) {
      std::fprintf(stderr, "fuzz_%s: %s instead of InputError: %s\n", parser, typeid(e).name(), e.what());
      std::abort();
    }
  }
  return 0;
}

}  // namespace bvhlab::fuzz

#define BVHLAB_FUZZ_TARGET(NAME)                                                        \
  extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {             \
    return bvhlab::fuzz::runOne(NAME, data, size);                                      \
  }
