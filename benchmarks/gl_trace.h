// The GL trace format of ecrf_gl_replay: the web viewer's WebGL2 calls as recorded by
// web/test/gl_record.mjs (keep the two in sync), read into memory and checked before any GL call.
// No GL or EGL headers here: the few GL enum values the checks need are spelled out in gl_enum
// (gl_replay.cc asserts they match GLES3/gl3.h), so the format can be read where no GL exists.
#ifndef ECRF_BENCHMARKS_GL_TRACE_H_
#define ECRF_BENCHMARKS_GL_TRACE_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace ecrf {
namespace gl_replay {

inline constexpr char kMagic[8] = {'E', 'C', 'R', 'F', 'G', 'L', 'T', '1'};
constexpr uint32_t kKindSetup = 1, kKindFrame = 2;
enum Op : uint32_t {
  kEnd = 0,
  kCreate,
  kDelete,
  kShaderSource,
  kCompileShader,
  kAttachShader,
  kLinkProgram,
  kUseProgram,
  kUniformBlockBinding,
  kUniform,
  kActiveTexture,
  kBindTexture,
  kTexParameteri,
  kPixelStorei,
  kTexImage,
  kTexStorage2D,
  kBindBuffer,
  kBufferData,
  kBindBufferBase,
  kBindFramebuffer,
  kFramebufferTexture2D,
  kBindVertexArray,
  kViewport,
  kScissor,
  kEnable,
  kDisable,
  kDrawArrays,
  kReadPixels,
  kMark,
  kNumOps
};
// Name and payload layout of each op: u = u32 (or i32), s = string, b = blob, o = u32 flag then
// a blob if the flag is set.
struct OpInfo {
  const char* name;
  const char* layout;
};
inline constexpr OpInfo kOps[kNumOps] = {
    {"end", ""},
    {"create", "uuu"},
    {"delete", "uu"},
    {"shaderSource", "us"},
    {"compileShader", "u"},
    {"attachShader", "uu"},
    {"linkProgram", "u"},
    {"useProgram", "u"},
    {"uniformBlockBinding", "usu"},
    {"uniform", "usuuub"},
    {"activeTexture", "u"},
    {"bindTexture", "uu"},
    {"texParameteri", "uuu"},
    {"pixelStorei", "uu"},
    {"texImage", "uuuuuuuuuo"},
    {"texStorage2D", "uuuuu"},
    {"bindBuffer", "uu"},
    {"bufferData", "uub"},
    {"bindBufferBase", "uuu"},
    {"bindFramebuffer", "uu"},
    {"framebufferTexture2D", "uuuuu"},
    {"bindVertexArray", "u"},
    {"viewport", "uuuu"},
    {"scissor", "uuuu"},
    {"enable", "u"},
    {"disable", "u"},
    {"drawArrays", "uuu"},
    {"readPixels", "uuuuuu"},
    {"mark", "u"},
};
enum ObjKind : uint32_t {
  kTexture = 1,
  kBuffer,
  kFramebuffer,
  kVertexArray,
  kProgram,
  kShader,
  kNumKinds
};
inline constexpr const char* kKindName[kNumKinds] = {
    "", "texture", "buffer", "framebuffer", "vertex array", "program", "shader"};
constexpr uint32_t kMarkFrameBegin = 2, kMarkFrameEnd = 3;
constexpr uint32_t kMaxId = 1u << 20;
constexpr uint64_t kMaxFileBytes = 4ull << 30;

// One recorded call: the u32 arguments, string and blob of its kOps layout, in that order.
struct Call {
  uint32_t op = 0;
  uint32_t u[10] = {};
  std::string str;
  const uint8_t* data = nullptr;  // blob, inside Trace::bytes
  uint64_t size = 0;
  bool has_data = false;
};

// A parsed trace file; its calls point into `bytes`, so a Trace is not copied.
struct Trace {
  std::string path;
  std::vector<uint8_t> bytes;
  uint32_t kind = 0;
  std::string meta;
  std::string setup_id;
  std::vector<std::pair<uint32_t, int32_t>> limits;  // setup: the limits the mock reported
  std::string setup_file;                            // frame: its setup trace
  uint32_t width = 0, height = 0, canvas_w = 0, canvas_h = 0;
  std::vector<Call> calls;
};

// The GL enum values the trace checks accept (Khronos-assigned, never change).
namespace gl_enum {
constexpr uint32_t kUnsignedByte = 0x1401, kFloat = 0x1406;
constexpr uint32_t kRed = 0x1903, kRgba = 0x1908, kRedInteger = 0x8D94, kRgbaInteger = 0x8D99;
constexpr uint32_t kUnpackAlignment = 0x0CF5;
constexpr uint32_t kTexture2D = 0x0DE1, kTexture3D = 0x806F, kTexture2DArray = 0x8C1A;
constexpr uint32_t kArrayBuffer = 0x8892, kUniformBuffer = 0x8A11;
constexpr uint32_t kFragmentShader = 0x8B30, kVertexShader = 0x8B31;
}  // namespace gl_enum

// printf into a std::string (messages up to 1 KiB).
std::string Fmt(const char* fmt, ...) __attribute__((format(printf, 1, 2)));

// Sets *err and returns false: `return Fail(err, "...")`.
bool Fail(std::string* err, std::string message);

// Reads a trace file (a whole-file zstd frame is decompressed when built with
// ECRF_GL_REPLAY_ZSTD) and parses every call's payload against its layout in kOps. False with a
// message in *err on any truncation, bad length or unknown op.
bool ParseTrace(const std::string& path, Trace* t, std::string* err);

// Checks a setup trace and one of its frame traces, in replay order, for everything that sizes
// memory GL reads or writes (texture and uniform data, readPixels) and for object ids that were
// never created, so that a corrupt trace fails with a message instead of crashing the driver.
// [*begin, *end) are the frame trace's calls between its two frame marks (the timed frame).
bool Validate(const Trace& setup, const Trace& frame, size_t* begin, size_t* end, std::string* err);

}  // namespace gl_replay
}  // namespace ecrf

#endif  // ECRF_BENCHMARKS_GL_TRACE_H_
