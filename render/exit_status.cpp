#include "render/exit_status.hpp"

#include <cstdio>
#include <stdexcept>

#include "datasets/scene.hpp"  // InputError, FileError

namespace bvhlab {

const char* const kExitStatusHelp =
    "Errors go to stderr as \"bvhlab: error: ...\". Exit status: 0 done; 2 usage error: an unknown command or\n"
    "flag, a bad or missing value, a scene/mesh/config file whose content is refused (a path in it that names\n"
    "no file too); 1 runtime failure: a file given on the command line that cannot be found, read or written,\n"
    "a GL or shader failure, a failed run.";

int exitStatusFor(const std::exception& e) {
  if (dynamic_cast<const FileError*>(&e)) return kExitFailure;
  if (dynamic_cast<const InputError*>(&e) || dynamic_cast<const std::invalid_argument*>(&e)) return kExitUsage;
  return kExitFailure;
}

int reportError(const std::exception& e) {
  std::fprintf(stderr, "bvhlab: error: %s\n", e.what());
  return exitStatusFor(e);
}

}  // namespace bvhlab
