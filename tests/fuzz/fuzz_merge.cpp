// libFuzzer target for the sweep directory `bvhlab merge` reads (plan.json, runs/*.json: mergeSweeps;
// tests/fuzz/parsers.hpp); run by `bash setup.sh fuzz`.
#include "fuzz_common.hpp"

BVHLAB_FUZZ_TARGET("merge")
