// Checks of the JSON files a sweep directory holds (experiments/sweep_dir.hpp), made where they are
// read and before anything reads them by type: `bvhlab merge` and `bvhlab report` read directories
// that users copy, edit and hand in, so a wrong type or a missing key must be a clear error naming the
// file and key, never an exception from deep inside the JSON library or a crash. The fuzz target
// fuzz_merge (tests/fuzz) drives both through mergeSweeps.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

namespace bvhlab {

// Sweep files nest a few levels (a record: params.axes[i].value.file is 5). nlohmann::json parses
// without recursion but copies and prints recursively, one stack frame per level: a record of 200,000
// nested arrays (400 KB) crashed `merge` with a stack overflow. 64 levels leave ample room for what
// a renderer reports and stay far below the stack.
constexpr int kMaxJsonDepth = 64;

// Throws InputError "SOURCE: JSON nested deeper than 64 levels" (checked without recursion).
void checkNesting(const nlohmann::json& value, const std::string& source, int maxDepth = kMaxJsonDepth);

// plan.json: format 1; "experiment" an object whose "axes" (if any) map axis names to lists;
// "config" an object with a string "hash"; "runs" a list of run specs (RunSpec::fromJson reads each)
// with distinct keys. Throws InputError "SOURCE: KEY: what".
void checkPlan(const nlohmann::json& plan, const std::string& source);

// runs/KEY.json: an object with a non-empty string "key" and a string "status"; "result" and
// "machine", when present, objects; "image" and "visits_image" strings or null; "replicate" (in the
// record or its result) an integer. Throws InputError "SOURCE: KEY: what".
void checkRecord(const nlohmann::json& record, const std::string& source);

}  // namespace bvhlab
