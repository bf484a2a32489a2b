// The group file `bvhlab measure GROUP.json` reads (format in render/measure_command.hpp), checked
// and read into settings and runs before anything is loaded, built or drawn: a pure function of the
// JSON, shared by rendered and traced groups and fuzzed on its own (tests/fuzz/fuzz_group.cpp).
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace bvhlab {

// The group file's settings common to rendered and traced groups.
struct GroupSettings {
  int minFrames = 10, maxFrames = 10;
  double targetPct = 2.0, maxSeconds = 0.0;
  bool wantControl = true;  // aa_control, and enough rounds for its interval
  bool clipControl = true;  // aa_control: a group of clips steps its first clip twice (its interval is over frames)
  int programCopies = 1;
  std::string session = "unnamed";
};

// One run of the group: its key and `bvhlab render` (or `trace`) arguments. A run whose "args" is not
// a list of strings keeps its key and gets `error` (the group goes on; that run reports the error).
struct GroupRunSpec {
  std::string key;
  std::vector<std::string> args;
  std::string error;
};

struct GroupSpec {
  GroupSettings settings;
  std::string command = "render";  // "render" | "trace"
  bool sharePrograms = true;
  std::vector<GroupRunSpec> runs;  // at least one; keys non-empty and distinct
};

// Checks every key measure reads (type and range) and reads them. Throws InputError naming `source`
// and the key ("GROUP.json: runs[2].key: ...") for a group file that is not an object, has no runs,
// or holds a value of the wrong type or out of range. Unknown keys are ignored.
GroupSpec parseGroupSpec(const nlohmann::json& spec, const std::string& source);

// Reads FILE as JSON and parses it: FileError naming the file when it cannot be opened (a runtime
// failure, render/exit_status.hpp), InputError when it is not JSON.
GroupSpec readGroupSpec(const std::string& file);

}  // namespace bvhlab
