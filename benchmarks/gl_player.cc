#include "benchmarks/gl_player.h"

#include <algorithm>
#include <cstring>

namespace ecrf {
namespace gl_replay {

// The trace checks (gl_trace.cc) spell out the GL enums they accept, to need no GL headers.
static_assert(gl_enum::kUnsignedByte == GL_UNSIGNED_BYTE && gl_enum::kFloat == GL_FLOAT &&
                  gl_enum::kRed == GL_RED && gl_enum::kRgba == GL_RGBA &&
                  gl_enum::kRedInteger == GL_RED_INTEGER &&
                  gl_enum::kRgbaInteger == GL_RGBA_INTEGER &&
                  gl_enum::kUnpackAlignment == GL_UNPACK_ALIGNMENT &&
                  gl_enum::kTexture2D == GL_TEXTURE_2D && gl_enum::kTexture3D == GL_TEXTURE_3D &&
                  gl_enum::kTexture2DArray == GL_TEXTURE_2D_ARRAY &&
                  gl_enum::kArrayBuffer == GL_ARRAY_BUFFER &&
                  gl_enum::kUniformBuffer == GL_UNIFORM_BUFFER &&
                  gl_enum::kFragmentShader == GL_FRAGMENT_SHADER &&
                  gl_enum::kVertexShader == GL_VERTEX_SHADER,
              "gl_trace.h's gl_enum differs from GLES3/gl3.h");

Player::Player(uint32_t canvas_w, uint32_t canvas_h) : names_(kNumKinds) {
  // The canvas's drawing buffer (framebuffer null in WebGL): an FBO of its size.
  glGenRenderbuffers(1, &canvas_rb_);
  glBindRenderbuffer(GL_RENDERBUFFER, canvas_rb_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, canvas_w, canvas_h);
  glGenFramebuffers(1, &canvas_fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, canvas_fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, canvas_rb_);
  glBindFramebuffer(GL_FRAMEBUFFER, canvas_fbo_);
}

bool Player::Run(const Trace& t, size_t from, size_t to, bool checks, std::string* err) {
  for (size_t i = from; i < to; ++i) {
    if (!Exec(t.calls[i], checks, err)) {
      *err =
          Fmt("%s: call %zu (%s): %s", t.path.c_str(), i, kOps[t.calls[i].op].name, err->c_str());
      return false;
    }
    if (checks) {
      GLenum e = glGetError();
      if (e != GL_NO_ERROR) {
        *err =
            Fmt("%s: call %zu (%s): GL error 0x%x", t.path.c_str(), i, kOps[t.calls[i].op].name, e);
        return false;
      }
    }
  }
  return true;
}

GLint Player::Location(uint32_t prog, const std::string& name) {
  auto key = std::make_pair(prog, name);
  auto it = locations_.find(key);
  if (it != locations_.end()) return it->second;
  GLint loc = glGetUniformLocation(Name(kProgram, prog), name.c_str());
  locations_[key] = loc;
  return loc;
}

bool Player::Exec(const Call& c, bool checks, std::string* err) {
  const uint32_t* u = c.u;
  switch (c.op) {
    case kEnd:
    case kMark:
      return true;
    case kCreate: {
      GLuint n = 0;
      switch (u[0]) {
        case kTexture:
          glGenTextures(1, &n);
          break;
        case kBuffer:
          glGenBuffers(1, &n);
          break;
        case kFramebuffer:
          glGenFramebuffers(1, &n);
          break;
        case kVertexArray:
          glGenVertexArrays(1, &n);
          break;
        case kProgram:
          n = glCreateProgram();
          break;
        case kShader:
          n = glCreateShader(u[2]);
          break;
        default:
          break;
      }
      if (n == 0) return Fail(err, Fmt("could not create a %s", kKindName[u[0]]));
      auto& v = names_[u[0]];
      if (v.size() <= u[1]) v.resize(u[1] + 1);
      v[u[1]] = n;
      if (u[0] == kProgram) {
        for (auto it = locations_.begin(); it != locations_.end();) {
          it = it->first.first == u[1] ? locations_.erase(it) : std::next(it);
        }
      }
      return true;
    }
    case kDelete: {
      GLuint n = Name(u[0], u[1]);
      switch (u[0]) {
        case kTexture:
          glDeleteTextures(1, &n);
          break;
        case kBuffer:
          glDeleteBuffers(1, &n);
          break;
        case kFramebuffer:
          glDeleteFramebuffers(1, &n);
          break;
        case kVertexArray:
          glDeleteVertexArrays(1, &n);
          break;
        case kProgram:
          glDeleteProgram(n);
          break;
        case kShader:
          glDeleteShader(n);
          break;
        default:
          break;
      }
      names_[u[0]][u[1]] = 0;
      return true;
    }
    case kShaderSource: {
      const GLchar* src = c.str.c_str();
      GLint len = static_cast<GLint>(c.str.size());
      glShaderSource(Name(kShader, u[0]), 1, &src, &len);
      return true;
    }
    case kCompileShader: {
      GLuint sh = Name(kShader, u[0]);
      glCompileShader(sh);
      if (!checks) return true;
      GLint ok = 0;
      glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
      if (!ok) return Fail(err, "shader compilation failed: " + ShaderLog(sh, false));
      return true;
    }
    case kAttachShader:
      glAttachShader(Name(kProgram, u[0]), Name(kShader, u[1]));
      return true;
    case kLinkProgram: {
      GLuint p = Name(kProgram, u[0]);
      glLinkProgram(p);
      if (!checks) return true;
      GLint ok = 0;
      glGetProgramiv(p, GL_LINK_STATUS, &ok);
      if (!ok) return Fail(err, "program link failed: " + ShaderLog(p, true));
      return true;
    }
    case kUseProgram:
      glUseProgram(Name(kProgram, u[0]));
      return true;
    case kUniformBlockBinding: {
      GLuint p = Name(kProgram, u[0]);
      GLuint idx = glGetUniformBlockIndex(p, c.str.c_str());
      if (idx != GL_INVALID_INDEX) glUniformBlockBinding(p, idx, u[1]);
      return true;
    }
    case kUniform: {
      GLint loc = Location(u[0], c.str);
      if (loc < 0) return true;  // inactive: WebGL's location is null, the call a no-op
      scratch_.assign(c.data, c.data + c.size);
      GLsizei n = static_cast<GLsizei>(u[3]);
      if (u[1] == 0) {
        const GLfloat* v = reinterpret_cast<const GLfloat*>(scratch_.data());
        switch (u[2]) {
          case 1:
            glUniform1fv(loc, n, v);
            break;
          case 2:
            glUniform2fv(loc, n, v);
            break;
          case 3:
            glUniform3fv(loc, n, v);
            break;
          default:
            glUniform4fv(loc, n, v);
            break;
        }
      } else {
        const GLint* v = reinterpret_cast<const GLint*>(scratch_.data());
        switch (u[2]) {
          case 1:
            glUniform1iv(loc, n, v);
            break;
          case 2:
            glUniform2iv(loc, n, v);
            break;
          case 3:
            glUniform3iv(loc, n, v);
            break;
          default:
            glUniform4iv(loc, n, v);
            break;
        }
      }
      return true;
    }
    case kActiveTexture:
      glActiveTexture(u[0]);
      return true;
    case kBindTexture:
      glBindTexture(u[0], Name(kTexture, u[1]));
      return true;
    case kTexParameteri:
      glTexParameteri(u[0], u[1], static_cast<GLint>(u[2]));
      return true;
    case kPixelStorei:
      glPixelStorei(u[0], static_cast<GLint>(u[1]));
      return true;
    case kTexImage: {
      const void* data = nullptr;
      if (c.has_data) {
        scratch_.assign(c.data, c.data + c.size);
        data = scratch_.data();
      }
      if (u[0] == GL_TEXTURE_2D) {
        glTexImage2D(u[0], u[1], u[2], u[3], u[4], u[6], u[7], u[8], data);
      } else {
        glTexImage3D(u[0], u[1], u[2], u[3], u[4], u[5], u[6], u[7], u[8], data);
      }
      return true;
    }
    case kTexStorage2D:
      glTexStorage2D(u[0], u[1], u[2], u[3], u[4]);
      return true;
    case kBindBuffer:
      glBindBuffer(u[0], Name(kBuffer, u[1]));
      return true;
    case kBufferData:
      scratch_.assign(c.data, c.data + c.size);
      glBufferData(u[0], static_cast<GLsizeiptr>(c.size), scratch_.data(), u[1]);
      return true;
    case kBindBufferBase:
      glBindBufferBase(u[0], u[1], Name(kBuffer, u[2]));
      return true;
    case kBindFramebuffer:
      glBindFramebuffer(u[0], u[1] == 0 ? canvas_fbo_ : Name(kFramebuffer, u[1]));
      return true;
    case kFramebufferTexture2D:
      glFramebufferTexture2D(u[0], u[1], u[2], Name(kTexture, u[3]), u[4]);
      return true;
    case kBindVertexArray:
      glBindVertexArray(Name(kVertexArray, u[0]));
      return true;
    case kViewport:
      glViewport(u[0], u[1], u[2], u[3]);
      return true;
    case kScissor:
      glScissor(u[0], u[1], u[2], u[3]);
      return true;
    case kEnable:
      glEnable(u[0]);
      return true;
    case kDisable:
      glDisable(u[0]);
      return true;
    case kDrawArrays:
      if (checks) {
        GLenum s = glCheckFramebufferStatus(GL_FRAMEBUFFER);
        if (s != GL_FRAMEBUFFER_COMPLETE) return Fail(err, Fmt("framebuffer incomplete (0x%x)", s));
      }
      glDrawArrays(u[0], u[1], u[2]);
      return true;
    case kReadPixels:
      pixels_.resize(size_t(u[2]) * u[3] * 4);
      glReadPixels(u[0], u[1], u[2], u[3], GL_RGBA, GL_UNSIGNED_BYTE, pixels_.data());
      pixels_w_ = u[2];
      pixels_h_ = u[3];
      return true;
    default:
      return Fail(err, "unknown op");
  }
}

std::string Player::ShaderLog(GLuint obj, bool program) {
  GLint n = 0;
  if (program)
    glGetProgramiv(obj, GL_INFO_LOG_LENGTH, &n);
  else
    glGetShaderiv(obj, GL_INFO_LOG_LENGTH, &n);
  std::string log(std::max(n, 1), '\0');
  GLsizei got = 0;
  if (program)
    glGetProgramInfoLog(obj, n, &got, &log[0]);
  else
    glGetShaderInfoLog(obj, n, &got, &log[0]);
  log.resize(std::max(got, 0));
  if (log.size() > 4000) log = log.substr(0, 4000) + "...";
  return log;
}

}  // namespace gl_replay
}  // namespace ecrf
