// libFuzzer target for the fbx importer (assimp behind loadMesh; tests/fuzz/parsers.hpp); run by `bash setup.sh fuzz`.
#include "fuzz_common.hpp"

BVHLAB_FUZZ_TARGET("fbx")
