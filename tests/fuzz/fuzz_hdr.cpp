// libFuzzer target for hdr images (loadImage, OpenImageIO; tests/fuzz/parsers.hpp); run by `bash setup.sh fuzz`.
#include "fuzz_common.hpp"

BVHLAB_FUZZ_TARGET("hdr")
