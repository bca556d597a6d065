// Headless EGL display and context creation (gl_replay_context.h).
#include "benchmarks/gl_replay_context.h"

#include <EGL/eglext.h>

#include <cstring>

#include "benchmarks/gl_trace.h"  // Fmt, Fail

namespace ecrf {
namespace gl_replay {
namespace {

// Whether the space-separated extension list has `name` (a whole word, not a prefix).
bool HasExt(const char* list, const char* name) {
  if (!list) return false;
  size_t n = strlen(name);
  for (const char* p = list; (p = strstr(p, name)) != nullptr; p += n) {
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == 0)) return true;
  }
  return false;
}

bool InitDisplay(HeadlessDisplay* egl, EGLDisplay dpy, const char* platform) {
  if (dpy == EGL_NO_DISPLAY) {
    egl->log += Fmt("%s: no display (0x%x); ", platform, eglGetError());
    return false;
  }
  EGLint major = 0, minor = 0;
  if (!eglInitialize(dpy, &major, &minor)) {
    egl->log += Fmt("%s: eglInitialize failed (0x%x); ", platform, eglGetError());
    return false;
  }
  if (!eglBindAPI(EGL_OPENGL_ES_API)) {
    egl->log += Fmt("%s: eglBindAPI(GLES) failed (0x%x); ", platform, eglGetError());
    eglTerminate(dpy);
    return false;
  }
  const char* exts = eglQueryString(dpy, EGL_EXTENSIONS);
  bool surfaceless = HasExt(exts, "EGL_KHR_surfaceless_context");
  // Surface type 0: any config (EGL's default would ask for window surfaces).
  EGLint attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_ES3_BIT, EGL_SURFACE_TYPE,
                      surfaceless ? 0 : EGL_PBUFFER_BIT, EGL_NONE};
  EGLint n = 0;
  if (!eglChooseConfig(dpy, attribs, &egl->config, 1, &n) || n < 1) {
    egl->log += Fmt("%s: no OpenGL ES 3 config (0x%x); ", platform, eglGetError());
    eglTerminate(dpy);
    return false;
  }
  egl->dpy = dpy;
  egl->surfaceless = surfaceless;
  egl->platform = platform;
  return true;
}

}  // namespace

bool OpenDisplay(HeadlessDisplay* egl, const std::string& want, int device) {
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if ((want == "auto" || want == "device") && HasExt(client, "EGL_EXT_platform_device") &&
      get_platform_display) {
    auto query_devices =
        reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    EGLDeviceEXT devices[16];
    EGLint n = 0;
    if (query_devices && query_devices(16, devices, &n) && n > 0) {
      if (device >= n) {
        egl->log += Fmt("device: only %d devices; ", n);
      } else if (InitDisplay(
                     egl, get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[device], nullptr),
                     "device")) {
        egl->platform = Fmt("device %d of %d", device, n);
        return true;
      }
    } else {
      egl->log += Fmt("device: eglQueryDevicesEXT found none (0x%x); ", eglGetError());
    }
  } else if (want == "device") {
    egl->log += "device: EGL_EXT_platform_device missing; ";
  }
  if ((want == "auto" || want == "surfaceless") &&
      HasExt(client, "EGL_MESA_platform_surfaceless") && get_platform_display) {
    if (InitDisplay(
            egl, get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr),
            "surfaceless")) {
      return true;
    }
  } else if (want == "surfaceless") {
    egl->log += "surfaceless: EGL_MESA_platform_surfaceless missing; ";
  }
  if (want == "auto" || want == "default") {
    if (InitDisplay(egl, eglGetDisplay(EGL_DEFAULT_DISPLAY), "default")) return true;
  }
  return false;
}

void CloseDisplay(HeadlessDisplay* egl) {
  if (egl->dpy != EGL_NO_DISPLAY) eglTerminate(egl->dpy);
  egl->dpy = EGL_NO_DISPLAY;
}

bool CreateContext(const HeadlessDisplay& egl, bool robust, HeadlessContext* c, std::string* err) {
  if (robust &&
      HasExt(eglQueryString(egl.dpy, EGL_EXTENSIONS), "EGL_EXT_create_context_robustness")) {
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                              3,
                              EGL_CONTEXT_MINOR_VERSION,
                              0,
                              EGL_CONTEXT_OPENGL_ROBUST_ACCESS_EXT,
                              EGL_TRUE,
                              EGL_NONE};
    c->ctx = eglCreateContext(egl.dpy, egl.config, EGL_NO_CONTEXT, attribs);
    c->robust = c->ctx != EGL_NO_CONTEXT;
  }
  if (c->ctx == EGL_NO_CONTEXT) {
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 0, EGL_NONE};
    c->ctx = eglCreateContext(egl.dpy, egl.config, EGL_NO_CONTEXT, attribs);
  }
  if (c->ctx == EGL_NO_CONTEXT)
    return Fail(err, Fmt("eglCreateContext(ES 3.0) failed (0x%x)", eglGetError()));
  if (!egl.surfaceless) {
    const EGLint pb[] = {EGL_WIDTH, 16, EGL_HEIGHT, 16, EGL_NONE};
    c->surface = eglCreatePbufferSurface(egl.dpy, egl.config, pb);
    if (c->surface == EGL_NO_SURFACE)
      return Fail(err, Fmt("eglCreatePbufferSurface failed (0x%x)", eglGetError()));
  }
  if (!eglMakeCurrent(egl.dpy, c->surface, c->surface, c->ctx)) {
    return Fail(err, Fmt("eglMakeCurrent failed (0x%x)", eglGetError()));
  }
  return true;
}

void DestroyContext(const HeadlessDisplay& egl, HeadlessContext* c) {
  eglMakeCurrent(egl.dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  if (c->surface != EGL_NO_SURFACE) eglDestroySurface(egl.dpy, c->surface);
  if (c->ctx != EGL_NO_CONTEXT) eglDestroyContext(egl.dpy, c->ctx);
  *c = HeadlessContext();
}

}  // namespace gl_replay
}  // namespace ecrf
