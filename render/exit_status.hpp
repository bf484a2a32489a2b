// The command line's exit statuses and its one error style, shared by every `bvhlab` command:
// "bvhlab: error: MESSAGE" on stderr, then
//   2  a usage error: what the user typed or wrote is refused (unknown command, unknown flag, bad or
//      missing option value, missing argument, or a scene / mesh / config / group file whose content
//      is wrong, including a path in it that names no file; the message names the flag, or the file
//      and its line or key);
//   1  a runtime failure: a file given on the command line that cannot be found, opened, read or
//      written (FileError), a GL or shader failure, a run that failed, a traversal stack that
//      overflowed.
// A `bvhlab run` stopped by a signal exits 128 + the signal's number, as a shell reports it.
// `bvhlab --help` states the rule (kExitStatusHelp).
#pragma once
#include <exception>
#include <string>

namespace bvhlab {

constexpr int kExitFailure = 1;
constexpr int kExitUsage = 2;

// The footer of `bvhlab --help`.
extern const char* const kExitStatusHelp;

// kExitUsage for an InputError that is not a FileError (bad content) and for std::invalid_argument (a
// value refused after CLI11 parsed it, e.g. --layout nope or --leaf-size 0); kExitFailure for the rest.
int exitStatusFor(const std::exception& e);

// Prints "bvhlab: error: " + e.what() as one line on stderr and returns exitStatusFor(e).
int reportError(const std::exception& e);

}  // namespace bvhlab
