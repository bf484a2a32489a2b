// libFuzzer target for the viewer_script parser (tests/fuzz/parsers.hpp); run by `bash setup.sh fuzz`.
#include "fuzz_common.hpp"

BVHLAB_FUZZ_TARGET("viewer_script")
