#include "render/gl_context.hpp"

#include <cstdio>
#include <stdexcept>
#include <vector>

#include <glad/gl.h>
#include <GL/osmesa.h>
#include <EGL/egl.h>
#include <EGL/eglext.h>

namespace bvhlab {

Backend parseBackend(const std::string& name) {
  if (name == "osmesa") return Backend::OSMesa;
  if (name == "egl") return Backend::EGL;
  throw std::invalid_argument("unknown backend '" + name + "' (valid: osmesa, egl)");
}

const char* backendName(Backend b) { return b == Backend::OSMesa ? "osmesa" : "egl"; }

bool isSoftwareRenderer(const std::string& r) {
  for (const char* name : {"llvmpipe", "softpipe", "swrast", "Software Rasterizer"})
    if (r.find(name) != std::string::npos) return true;
  return false;
}

std::string GlContext::renderer() const {
  const GLubyte* s = glGetString(GL_RENDERER);
  return s ? reinterpret_cast<const char*>(s) : "unknown";
}
std::string GlContext::version() const {
  const GLubyte* s = glGetString(GL_VERSION);
  return s ? reinterpret_cast<const char*>(s) : "unknown";
}

void checkGl(const char* where) {
  GLenum err = glGetError();
  if (err == GL_NO_ERROR) return;
  const char* name = "unknown";
  switch (err) {
    case GL_INVALID_ENUM: name = "GL_INVALID_ENUM"; break;
    case GL_INVALID_VALUE: name = "GL_INVALID_VALUE"; break;
    case GL_INVALID_OPERATION: name = "GL_INVALID_OPERATION"; break;
    case GL_OUT_OF_MEMORY: name = "GL_OUT_OF_MEMORY"; break;
    case GL_INVALID_FRAMEBUFFER_OPERATION: name = "GL_INVALID_FRAMEBUFFER_OPERATION"; break;
  }
  throw std::runtime_error(std::string("GL error ") + name + " in " + where);
}

namespace {

void loadGl(GLADloadfunc loader, const char* backend) {
  int version = gladLoadGL(loader);
  if (version == 0 || GLAD_VERSION_MAJOR(version) * 10 + GLAD_VERSION_MINOR(version) < 45)
    throw std::runtime_error(std::string(backend) + ": could not load OpenGL 4.5 core entry points");
}

class OSMesaContextImpl : public GlContext {
 public:
  OSMesaContextImpl() {
    const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 0, OSMESA_PROFILE,
                           OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, 4,
                           OSMESA_CONTEXT_MINOR_VERSION, 5, 0};
    ctx_ = OSMesaCreateContextAttribs(attribs, nullptr);
    if (!ctx_) throw std::runtime_error("osmesa: OSMesaCreateContextAttribs(4.5 core) failed");
    // OSMesa needs a bound colour buffer to make the context current; we render to FBOs.
    buffer_.resize(4);
    if (!OSMesaMakeCurrent(ctx_, buffer_.data(), GL_UNSIGNED_BYTE, 1, 1)) {
      OSMesaDestroyContext(ctx_);
      throw std::runtime_error("osmesa: OSMesaMakeCurrent failed");
    }
    loadGl(reinterpret_cast<GLADloadfunc>(OSMesaGetProcAddress), "osmesa");
  }
  ~OSMesaContextImpl() override { OSMesaDestroyContext(ctx_); }
  Backend backend() const override { return Backend::OSMesa; }

 private:
  OSMesaContext ctx_ = nullptr;
  std::vector<unsigned char> buffer_;
};

class EglContextImpl : public GlContext {
 public:
  EglContextImpl() {
    // Prefer an EGL device (a real GPU), fall back to Mesa's surfaceless platform (llvmpipe).
    display_ = openDisplay();
    EGLint major = 0, minor = 0;
    if (display_ == EGL_NO_DISPLAY || !eglInitialize(display_, &major, &minor))
      throw std::runtime_error("egl: no usable display (eglInitialize failed)");
    if (!eglBindAPI(EGL_OPENGL_API)) throw std::runtime_error("egl: eglBindAPI(OpenGL) failed");
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                              EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                              EGL_NONE};
    // EGL_KHR_no_config_context + EGL_KHR_surfaceless_context: no config, no surface, render to FBOs.
    context_ = eglCreateContext(display_, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attribs);
    if (context_ == EGL_NO_CONTEXT) throw std::runtime_error("egl: eglCreateContext(4.5 core) failed");
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
      throw std::runtime_error("egl: eglMakeCurrent (surfaceless) failed");
    loadGl(reinterpret_cast<GLADloadfunc>(eglGetProcAddress), "egl");
  }
  ~EglContextImpl() override {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    eglTerminate(display_);
  }
  Backend backend() const override { return Backend::EGL; }

 private:
  static EGLDisplay openDisplay() {
    auto getPlatformDisplay =
        reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    auto queryDevices =
        reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    if (!getPlatformDisplay) return eglGetDisplay(EGL_DEFAULT_DISPLAY);
    if (queryDevices) {
      EGLDeviceEXT devices[8];
      EGLint n = 0;
      if (queryDevices(8, devices, &n)) {
        auto queryDeviceString = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
            eglGetProcAddress("eglQueryDeviceStringEXT"));
        for (EGLint i = 0; i < n; ++i) {
          // Mesa's software device reports EGL_MESA_device_software; skip it in favour of hardware.
          const char* ext = queryDeviceString ? queryDeviceString(devices[i], EGL_EXTENSIONS) : nullptr;
          if (ext && std::string(ext).find("EGL_MESA_device_software") != std::string::npos) continue;
          EGLDisplay d = getPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
          EGLint maj, min;
          if (d != EGL_NO_DISPLAY && eglInitialize(d, &maj, &min)) return d;
        }
      }
    }
    return getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  }
  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
};

}  // namespace

std::unique_ptr<GlContext> createContext(Backend backend) {
  if (backend == Backend::OSMesa) return std::make_unique<OSMesaContextImpl>();
  auto ctx = std::make_unique<EglContextImpl>();
  static bool noted = false;
  if (!noted && ctx->software()) {
    noted = true;
    std::fprintf(stderr, "bvhlab: note: --backend egl found no GPU and runs on Mesa's software renderer (%s)\n",
                 ctx->renderer().c_str());
  }
  return ctx;
}

}  // namespace bvhlab
