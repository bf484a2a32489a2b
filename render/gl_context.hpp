// Headless OpenGL 4.5 core contexts: OSMesa (default, Mesa llvmpipe) or EGL surfaceless / device
// (llvmpipe here, the NVIDIA driver on a GPU machine). Both load GL through glad.
#pragma once
#include <memory>
#include <string>

namespace bvhlab {

enum class Backend { OSMesa, EGL };
Backend parseBackend(const std::string& name);  // throws std::invalid_argument naming the valid ones
const char* backendName(Backend b);

// True for Mesa's CPU rasterisers (llvmpipe, softpipe, swrast): what EGL lands on without a GPU.
bool isSoftwareRenderer(const std::string& glRenderer);

class GlContext {
 public:
  virtual ~GlContext() = default;
  virtual Backend backend() const = 0;
  std::string renderer() const;  // GL_RENDERER
  std::string version() const;   // GL_VERSION
  bool software() const { return isSoftwareRenderer(renderer()); }
};

// Creates a context, makes it current and loads GL. Throws std::runtime_error with the reason.
// An EGL context that lands on a software renderer (no GPU, or no driver for it) prints a one-line
// note on stderr, once per process: numbers taken then are llvmpipe's, not a GPU's.
// Rendering goes to FBOs; the default framebuffer (if any) is never used.
std::unique_ptr<GlContext> createContext(Backend backend);

// Throws std::runtime_error naming `where` and the GL error if glGetError() reports one.
void checkGl(const char* where);

}  // namespace bvhlab
