// ecrf_gl_replay: replays GL traces of the web viewer's WebGL2 renderer (recorded by
// web/test/gl_record.mjs from web/gpu_renderer.js + web/gpu_shaders.js, unchanged) on a headless
// EGL + OpenGL ES 3 context, times the frame and writes the image: the viewer's frame times on a
// GPU without a browser. Links only libEGL and libGLESv2 (and libzstd statically where found, for
// zstd-compressed traces).
//
//   ecrf_gl_replay [--frames N] [--max-seconds S] [--out-dir DIR] [--device I] [--no-robust]
//                  [--egl auto|device|surfaceless|default] FRAME.glt...
//   ecrf_gl_replay --check FILE.glt...     parse and validate only (no GL)
//
// A frame trace NAME_WxH.frame.glt names its setup trace (NAME.setup.glt, same folder). Each
// frame trace is replayed on a fresh context: the setup (renderer + setScene: textures, UBOs,
// shader compile), the warm-up render (creates the render target), the frame between the two
// marks once more untimed, then N times with glFinish before and after each (the viewer renders
// with finish: a 1-pixel readPixels ends the frame), then the final readPixels, written as
// DIR/NAME_WxH.ppm (RGB, top row first). One JSON line per trace on stdout. A trace is parsed and
// checked completely (sizes, ids, enums that size data) before any GL call: a truncated or corrupt
// file fails with a message, exit status 1.
//
// The trace format and its checks: gl_trace.h; the calls' execution: gl_player.h; the EGL display
// and context (--egl, --device, --no-robust): gl_replay_context.h. WebGL's framebuffer null (the
// canvas) is an RGBA8 FBO of the canvas's size.
#include "benchmarks/gl_replay_context.h"  // first: its EGL_NO_X11 must precede every EGL header

#include <GLES3/gl3.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "benchmarks/gl_player.h"
#include "benchmarks/gl_trace.h"

namespace ecrf {
namespace gl_replay {
namespace {

std::string JsonStr(const std::string& s) {
  std::string o = "\"";
  for (unsigned char ch : s) {
    if (ch == '"' || ch == '\\')
      o += '\\', o += static_cast<char>(ch);
    else if (ch < 0x20 || ch >= 0x7f)
      o += Fmt("\\u%04x", ch);
    else
      o += static_cast<char>(ch);
  }
  return o + "\"";
}

const char* GlStr(GLenum e) {
  const GLubyte* s = glGetString(e);
  return s ? reinterpret_cast<const char*>(s) : "";
}

std::string Dirname(const std::string& p) {
  size_t k = p.rfind('/');
  return k == std::string::npos ? "." : p.substr(0, k);
}

std::string Stem(const std::string& p) {
  size_t k = p.rfind('/');
  std::string b = k == std::string::npos ? p : p.substr(k + 1);
  for (const char* ext : {".frame.glt", ".glt"}) {
    size_t n = strlen(ext);
    if (b.size() > n && b.compare(b.size() - n, n, ext) == 0) return b.substr(0, b.size() - n);
  }
  return b;
}

bool WritePpm(const std::string& path, const std::vector<uint8_t>& rgba, uint32_t w, uint32_t h,
              std::string* err) {
  FILE* f = fopen(path.c_str(), "wb");
  if (!f) return Fail(err, Fmt("cannot write %s: %s", path.c_str(), strerror(errno)));
  fprintf(f, "P6\n%u %u\n255\n", w, h);
  std::vector<uint8_t> row(size_t(w) * 3);
  for (uint32_t y = 0; y < h; ++y) {
    for (uint32_t x = 0; x < w; ++x) memcpy(&row[3 * x], &rgba[(size_t(y) * w + x) * 4], 3);
    fwrite(row.data(), 1, row.size(), f);
  }
  bool ok = fclose(f) == 0;
  if (!ok) *err = Fmt("error writing %s", path.c_str());
  return ok;
}

struct Options {
  int frames = 10;
  double max_seconds = 20;
  std::string out_dir;
  std::string egl = "auto";
  int device = 0;
  bool check_only = false;
  bool robust = true;
};

double Ms(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// Parses the frame trace at path and the setup trace it names, and checks them together: the
// frame's timed calls are [*begin, *end).
bool ParseFrameAndSetup(const std::string& path, Trace* frame, Trace* setup,
                        std::string* setup_path, size_t* begin, size_t* end, std::string* err) {
  if (!ParseTrace(path, frame, err)) return false;
  if (frame->kind != kKindFrame)
    return Fail(err,
                path + ": not a frame trace (a setup trace is replayed through its frame traces)");
  *setup_path = Dirname(path) + "/" + frame->setup_file;
  if (!ParseTrace(*setup_path, setup, err)) return false;
  if (setup->kind != kKindSetup || setup->setup_id != frame->setup_id) {
    return Fail(err, Fmt("%s is not the setup %s was recorded with (id %s, expected %s)",
                         setup_path->c_str(), path.c_str(), setup->setup_id.c_str(),
                         frame->setup_id.c_str()));
  }
  return Validate(*setup, *frame, begin, end, err);
}

// The limits the mock told the renderer it has that this GPU falls short of ("" when none): the
// GPU must allow what the trace assumes.
std::string ShortLimits(const Trace& setup) {
  std::string short_limits;
  for (const auto& l : setup.limits) {
    GLint v[2] = {0, 0};
    glGetIntegerv(l.first, v);
    if (glGetError() != GL_NO_ERROR) continue;
    GLint have = l.first == GL_MAX_VIEWPORT_DIMS ? std::min(v[0], v[1]) : v[0];
    if (have < l.second)
      short_limits += Fmt("%s0x%x: GPU %d < trace %d", short_limits.empty() ? "" : ", ", l.first,
                          have, l.second);
  }
  return short_limits;
}

struct FrameTimes {
  double setup_ms = 0, first_frame_ms = 0;
  std::vector<double> ms;  // the timed frames
};

// Plays the setup, the warm-up render (creates the render target, first draw: lazy compiles), the
// frame once more untimed, then the timed frames (at least 3 unless --frames says fewer, at most
// --max-seconds), and the trace's rest (its final readPixels).
bool PlayAndTime(const Options& o, Player& player, const Trace& setup, const Trace& frame,
                 size_t begin, size_t end, FrameTimes* times, std::string* err) {
  glFinish();
  auto t0 = std::chrono::steady_clock::now();
  if (!player.Run(setup, 0, setup.calls.size(), true, err)) return false;
  glFinish();
  auto t1 = std::chrono::steady_clock::now();
  if (!player.Run(frame, 0, begin, true, err)) return false;
  glFinish();
  auto t2 = std::chrono::steady_clock::now();
  if (!player.Run(frame, begin, end, true, err)) return false;
  glFinish();
  times->setup_ms = Ms(t0, t1);
  times->first_frame_ms = Ms(t1, t2);
  auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < o.frames; ++k) {
    glFinish();
    auto a = std::chrono::steady_clock::now();
    player.Run(frame, begin, end, false, err);
    glFinish();
    auto b = std::chrono::steady_clock::now();
    times->ms.push_back(Ms(a, b));
    if (Ms(start, b) > 1000 * o.max_seconds && k >= 2) break;
  }
  GLenum e = glGetError();
  if (e != GL_NO_ERROR) return Fail(err, Fmt("GL error 0x%x during the timed frames", e));
  return player.Run(frame, end, frame.calls.size(), true, err);
}

// Writes the frame's final readPixels as OUT_DIR/NAME_WxH.ppm when --out-dir asks for it; *image
// is its JSON path, or null.
bool WriteImage(const Options& o, const std::string& path, const Trace& frame, const Player& player,
                std::string* image, std::string* err) {
  *image = "null";
  if (o.out_dir.empty()) return true;
  if (player.pixels_w() != frame.width || player.pixels_h() != frame.height) {
    return Fail(err, Fmt("the trace's last readPixels is %ux%u, not the image's %ux%u",
                         player.pixels_w(), player.pixels_h(), frame.width, frame.height));
  }
  std::string out = o.out_dir + "/" + Stem(path) + ".ppm";
  if (!WritePpm(out, player.pixels(), frame.width, frame.height, err)) return false;
  *image = JsonStr(out);
  return true;
}

// The JSON line of a replayed trace: the context, the times and the image.
std::string ResultLine(const std::string& path, const Trace& frame, const HeadlessDisplay& egl,
                       const HeadlessContext& ctx, const std::string& version,
                       const FrameTimes& times, const std::string& image,
                       const std::string& short_limits) {
  const std::vector<double>& ms = times.ms;
  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  double median =
      sorted.empty()
          ? 0
          : (sorted.size() % 2 ? sorted[sorted.size() / 2]
                               : 0.5 * (sorted[sorted.size() / 2 - 1] + sorted[sorted.size() / 2]));
  double mean = 0;
  for (double v : ms) mean += v / ms.size();
  std::string line;
  auto add = [&line](const char* key, const std::string& value) {
    line += (line.empty() ? "{" : ", ") + JsonStr(key) + ": " + value;
  };
  auto num = [](double v) { return Fmt("%.4f", v); };
  add("trace", JsonStr(path));
  add("width", Fmt("%u", frame.width));
  add("height", Fmt("%u", frame.height));
  add("egl", JsonStr(egl.platform));
  add("robust", ctx.robust ? "true" : "false");
  add("gl_vendor", JsonStr(GlStr(GL_VENDOR)));
  add("gl_renderer", JsonStr(GlStr(GL_RENDERER)));
  add("gl_version", JsonStr(version));
  add("setup_ms", num(times.setup_ms));
  add("first_frame_ms", num(times.first_frame_ms));
  add("ms_min", num(sorted.empty() ? 0 : sorted.front()));
  add("ms_median", num(median));
  add("ms_mean", num(mean));
  add("ms_max", num(sorted.empty() ? 0 : sorted.back()));
  add("frames", Fmt("%zu", ms.size()));
  add("image", image);
  add("limits_short", short_limits.empty() ? "null" : JsonStr(short_limits));
  add("ok", "true");
  return line + "}";
}

// Replays a checked frame trace and its setup on the current context ctx and prints its JSON line.
bool ReplayOnContext(const Options& o, const HeadlessDisplay& egl, const HeadlessContext& ctx,
                     const std::string& path, const Trace& setup, const Trace& frame, size_t begin,
                     size_t end, std::string* err) {
  std::string version = GlStr(GL_VERSION);
  if (version.compare(0, 12, "OpenGL ES 3.") != 0)
    return Fail(err, "the context is not OpenGL ES 3.x: " + version);
  const std::string short_limits = ShortLimits(setup);
  Player player(frame.canvas_w, frame.canvas_h);
  FrameTimes times;
  if (!PlayAndTime(o, player, setup, frame, begin, end, &times, err)) return false;
  std::string image;
  if (!WriteImage(o, path, frame, player, &image, err)) return false;
  printf("%s\n", ResultLine(path, frame, egl, ctx, version, times, image, short_limits).c_str());
  fflush(stdout);
  return true;
}

// One frame trace: a JSON line on stdout. Returns false after printing the error.
bool ReplayOne(const Options& o, HeadlessDisplay* egl, const std::string& path) {
  std::string err;
  auto fail = [&](const std::string& e) {
    fprintf(stderr, "ecrf_gl_replay: %s\n", e.c_str());
    printf("{\"trace\": %s, \"ok\": false, \"error\": %s}\n", JsonStr(path).c_str(),
           JsonStr(e).c_str());
    fflush(stdout);
    return false;
  };
  Trace frame, setup;
  std::string setup_path;
  size_t begin = 0, end = 0;
  if (!ParseFrameAndSetup(path, &frame, &setup, &setup_path, &begin, &end, &err)) return fail(err);
  if (o.check_only) {
    printf(
        "{\"trace\": %s, \"setup\": %s, \"width\": %u, \"height\": %u, \"calls\": %zu, "
        "\"setup_calls\": %zu, \"ok\": true}\n",
        JsonStr(path).c_str(), JsonStr(setup_path).c_str(), frame.width, frame.height,
        frame.calls.size(), setup.calls.size());
    return true;
  }
  HeadlessContext ctx;
  if (!CreateContext(*egl, o.robust, &ctx, &err)) {
    DestroyContext(*egl, &ctx);
    return fail(err);
  }
  const bool ok = ReplayOnContext(o, *egl, ctx, path, setup, frame, begin, end, &err);
  DestroyContext(*egl, &ctx);
  return ok || fail(err);
}

int Usage() {
  fprintf(
      stderr,
      "usage: ecrf_gl_replay [--frames N (10)] [--max-seconds S (20)] [--out-dir DIR]\n"
      "                      [--egl auto|device|surfaceless|default] [--device I] [--no-robust]\n"
      "                      FRAME.glt...\n"
      "       ecrf_gl_replay --check FRAME.glt...   (parse and validate only, no GL)\n");
  return 2;
}

int Main(int argc, char** argv) {
  Options o;
  std::vector<std::string> traces;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto value = [&](const char* name) -> const char* {
      if (i + 1 >= argc) {
        fprintf(stderr, "ecrf_gl_replay: %s needs a value\n", name);
        exit(2);
      }
      return argv[++i];
    };
    if (a == "--frames") {
      o.frames = atoi(value("--frames"));
      if (o.frames < 0 || o.frames > 100000) return Usage();
    } else if (a == "--max-seconds") {
      o.max_seconds = atof(value("--max-seconds"));
    } else if (a == "--out-dir") {
      o.out_dir = value("--out-dir");
    } else if (a == "--egl") {
      o.egl = value("--egl");
      if (o.egl != "auto" && o.egl != "device" && o.egl != "surfaceless" && o.egl != "default")
        return Usage();
    } else if (a == "--device") {
      o.device = atoi(value("--device"));
      if (o.device < 0 || o.device > 15) return Usage();
    } else if (a == "--no-robust") {
      o.robust = false;
    } else if (a == "--check") {
      o.check_only = true;
    } else if (a == "-h" || a == "--help") {
      Usage();
      return 0;
    } else if (!a.empty() && a[0] == '-') {
      fprintf(stderr, "ecrf_gl_replay: unknown flag %s\n", a.c_str());
      return Usage();
    } else {
      traces.push_back(a);
    }
  }
  if (traces.empty()) return Usage();
  HeadlessDisplay egl;
  if (!o.check_only && !OpenDisplay(&egl, o.egl, o.device)) {
    fprintf(stderr, "ecrf_gl_replay: no EGL display with OpenGL ES 3 (--egl %s): %s\n",
            o.egl.c_str(), egl.log.c_str());
    printf("{\"ok\": false, \"error\": %s}\n", JsonStr("no EGL display: " + egl.log).c_str());
    return 1;
  }
  if (!egl.log.empty()) fprintf(stderr, "ecrf_gl_replay: EGL: %s\n", egl.log.c_str());
  int failed = 0;
  for (const auto& t : traces) failed += ReplayOne(o, &egl, t) ? 0 : 1;
  CloseDisplay(&egl);
  return failed ? 1 : 0;
}

}  // namespace
}  // namespace gl_replay
}  // namespace ecrf

int main(int argc, char** argv) { return ecrf::gl_replay::Main(argc, argv); }