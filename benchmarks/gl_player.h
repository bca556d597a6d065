// Player: executes the calls of a GL trace (benchmarks/gl_trace.h) on the current OpenGL ES 3
// context for ecrf_gl_replay (gl_replay.cc), the recorded object ids mapped to GL names. WebGL's
// framebuffer null (the canvas) is an RGBA8 FBO of the canvas's size.
#ifndef ECRF_BENCHMARKS_GL_PLAYER_H_
#define ECRF_BENCHMARKS_GL_PLAYER_H_

#include <GLES3/gl3.h>

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "benchmarks/gl_trace.h"

namespace ecrf {
namespace gl_replay {

class Player {
 public:
  Player(uint32_t canvas_w, uint32_t canvas_h);

  // checks: glGetError after each call, compile / link / framebuffer status (untimed passes).
  bool Run(const Trace& t, size_t from, size_t to, bool checks, std::string* err);

  const std::vector<uint8_t>& pixels() const { return pixels_; }
  uint32_t pixels_w() const { return pixels_w_; }
  uint32_t pixels_h() const { return pixels_h_; }

 private:
  GLuint Name(uint32_t kind, uint32_t id) const { return id == 0 ? 0 : names_[kind][id]; }
  GLint Location(uint32_t prog, const std::string& name);
  bool Exec(const Call& c, bool checks, std::string* err);
  static std::string ShaderLog(GLuint obj, bool program);

  std::vector<std::vector<GLuint>> names_;
  std::map<std::pair<uint32_t, std::string>, GLint> locations_;
  std::vector<uint8_t> scratch_, pixels_;
  uint32_t pixels_w_ = 0, pixels_h_ = 0;
  GLuint canvas_rb_ = 0, canvas_fbo_ = 0;
};

}  // namespace gl_replay
}  // namespace ecrf

#endif  // ECRF_BENCHMARKS_GL_PLAYER_H_
