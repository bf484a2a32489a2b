// libFuzzer target for the group file `bvhlab measure` reads (readGroupSpec; tests/fuzz/parsers.hpp); run by `bash setup.sh fuzz`.
#include "fuzz_common.hpp"

BVHLAB_FUZZ_TARGET("group")
