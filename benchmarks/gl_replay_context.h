// The headless EGL + OpenGL ES 3 context ecrf_gl_replay renders on: no window, no X11 or Wayland.
// Displays are tried in the order that finds a GPU first on a server: EGL_EXT_platform_device (a
// GPU without a display server), EGL_MESA_platform_surfaceless (Mesa), EGL_DEFAULT_DISPLAY.
#ifndef ECRF_BENCHMARKS_GL_REPLAY_CONTEXT_H_
#define ECRF_BENCHMARKS_GL_REPLAY_CONTEXT_H_

// No X11 types in the EGL headers (nothing here uses them; the GPU machine may lack X11 headers).
#define EGL_NO_X11
#define MESA_EGL_NO_X11_HEADERS
#include <EGL/egl.h>

#include <string>

namespace ecrf {
namespace gl_replay {

// An initialized EGL display with an OpenGL ES 3 config.
struct HeadlessDisplay {
  EGLDisplay dpy = EGL_NO_DISPLAY;
  EGLConfig config = nullptr;
  bool surfaceless = false;  // EGL_KHR_surfaceless_context: no pbuffer needed
  std::string platform;      // which display was opened, for the JSON line
  std::string log;           // why the displays tried before it (or all) failed
};

// want: "auto" (the first that works, in the order above), "device", "surfaceless" or
// "default"; device: the index among EGL's devices. False with the reasons in display->log.
bool OpenDisplay(HeadlessDisplay* display, const std::string& want, int device);

void CloseDisplay(HeadlessDisplay* display);

struct HeadlessContext {
  EGLContext ctx = EGL_NO_CONTEXT;
  EGLSurface surface = EGL_NO_SURFACE;  // a 16x16 pbuffer without surfaceless contexts
  bool robust = false;                  // robust buffer access was granted
};

// An ES 3.0 context, made current. robust: ask for robust buffer access
// (EGL_EXT_create_context_robustness), as browsers do for WebGL; without the extension, or when
// the driver refuses, an ordinary context (context->robust false).
bool CreateContext(const HeadlessDisplay& display, bool robust, HeadlessContext* context,
                   std::string* err);

// Also after a failed CreateContext: releases whatever it made.
void DestroyContext(const HeadlessDisplay& display, HeadlessContext* context);

}  // namespace gl_replay
}  // namespace ecrf

#endif  // ECRF_BENCHMARKS_GL_REPLAY_CONTEXT_H_
