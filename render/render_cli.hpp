// The `render` command line (CLI11), in one place: `bvhlab render` parses the process's arguments
// with it and `bvhlab measure` parses each run of a group with it, so both accept exactly the same
// flags with the same checks.
#pragma once
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <glm/glm.hpp>

#include "render/render_command.hpp"

namespace bvhlab {

// Flags whose text is parsed after CLI11 is done (three numbers "x,y,z").
struct RenderCliText {
  std::string eye, target, up;
};

// A CLI11 check for an input path: a directory is refused with a message that says so (a missing
// file is left to the loader, whose message names the file and what it expected).
CLI::Validator notADirectory(const std::string& expected);

// The options that choose and walk the tree (builder and its knobs, layout, kernel, leaf size, storage),
// shared by `render` and `trace`.
// --update, --update-repeats, --clip-frames, --clip-step: an animated scene's clip, frame by frame.
void addClipOptions(CLI::App& app, RenderCommand& rc);
void addTreeOptions(CLI::App& app, RenderCommand& cmd);

// Adds every `render` option to `app`, writing into `cmd` and `text`.
void addRenderOptions(CLI::App& app, RenderCommand& cmd, RenderCliText& text);
// Parses --eye/--target/--up into `cmd`; throws std::invalid_argument naming the flag.
void applyRenderCliText(RenderCommand& cmd, const RenderCliText& text);

// "x,y,z" in double (a far scene's --eye keeps the precision the scene loader has); throws
// std::invalid_argument naming `flag` unless it is three finite numbers.
glm::dvec3 parseVec3(const std::string& text, const char* flag);

// Parses a `render` argument list (without the program name and the word "render", e.g.
// {"scene.toml", "--json", "--builder", "median"}). Throws std::invalid_argument with CLI11's
// message for anything `bvhlab render` would refuse.
RenderCommand parseRenderArgs(const std::vector<std::string>& args);

}  // namespace bvhlab
