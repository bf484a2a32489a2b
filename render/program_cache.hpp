// Compiled tracer programs shared by their assembled source within one GL context.
//
// Why (measured, experiments/README.md "One program per shader source"): on llvmpipe each compiled
// copy of a program gets its own JIT code placement, and a copy's speed is fixed for its life: in
// one process, eight copies of the same three bunny renders (one source per builder) had copies
// 5-10% slower than their twins, about one copy in six, while copies that shared one program but
// uploaded their own buffers agreed within 0.8%. Two runs whose shaders are the same text therefore
// draw with one program, so a comparison between them (builders, leaf sizes) sees their data and
// nothing of where the JIT put their code.
#pragma once
#include <cstddef>
#include <map>
#include <string>

#include "shaders/assemble.hpp"

namespace bvhlab {

class ProgramCache {
 public:
  ProgramCache() = default;
  ProgramCache(const ProgramCache&) = delete;
  ProgramCache& operator=(const ProgramCache&) = delete;
  ~ProgramCache();  // deletes the programs: the context they were made in must be current

  struct Program {
    unsigned id = 0;     // the GL program
    int index = -1;      // which distinct source it is, in order of first use (0, 1, ...)
  };
  // The program for this source, compiled (compileFullscreenProgram) on first use. Throws ShaderError.
  Program get(const AssembledShader& shader);
  size_t size() const { return programs_.size(); }

 private:
  std::map<std::string, Program> programs_;
};

}  // namespace bvhlab
