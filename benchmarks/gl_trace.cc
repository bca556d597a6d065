// Reading and checking GL traces (gl_trace.h); no GL calls.
#include "benchmarks/gl_trace.h"

#include <algorithm>
#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstring>

#ifdef ECRF_GL_REPLAY_ZSTD
#include <zstd.h>
#endif

namespace ecrf {
namespace gl_replay {

std::string Fmt(const char* fmt, ...) {
  char buf[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  return buf;
}

// Sets *err and returns false: `return Fail(err, "...")`.
bool Fail(std::string* err, std::string message) {
  *err = std::move(message);
  return false;
}

namespace {

bool ReadFile(const std::string& path, std::vector<uint8_t>* out, std::string* err) {
  FILE* f = fopen(path.c_str(), "rb");
  if (!f) {
    *err = Fmt("cannot open %s: %s", path.c_str(), strerror(errno));
    return false;
  }
  out->clear();
  uint8_t buf[1 << 16];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, f)) > 0) {
    if (out->size() + n > kMaxFileBytes) {
      fclose(f);
      *err = Fmt("%s: larger than 4 GiB", path.c_str());
      return false;
    }
    out->insert(out->end(), buf, buf + n);
  }
  bool bad = ferror(f) != 0;
  fclose(f);
  if (bad) *err = Fmt("error reading %s", path.c_str());
  return !bad;
}

// A whole-file zstd frame (zstd -q FILE) is decompressed in memory.
bool MaybeDecompress(const std::string& path, std::vector<uint8_t>* bytes, std::string* err) {
  static const uint8_t kZstdMagic[4] = {0x28, 0xb5, 0x2f, 0xfd};
  if (bytes->size() < 4 || memcmp(bytes->data(), kZstdMagic, 4) != 0) return true;
#ifdef ECRF_GL_REPLAY_ZSTD
  unsigned long long n = ZSTD_getFrameContentSize(bytes->data(), bytes->size());
  if (n == ZSTD_CONTENTSIZE_ERROR || n == ZSTD_CONTENTSIZE_UNKNOWN || n > kMaxFileBytes) {
    *err = Fmt("%s: corrupt zstd frame header (or no content size)", path.c_str());
    return false;
  }
  std::vector<uint8_t> out(static_cast<size_t>(n));
  size_t got = ZSTD_decompress(out.data(), out.size(), bytes->data(), bytes->size());
  if (ZSTD_isError(got) || got != n) {
    *err = Fmt("%s: zstd decompression failed: %s", path.c_str(),
               ZSTD_isError(got) ? ZSTD_getErrorName(got) : "size mismatch");
    return false;
  }
  bytes->swap(out);
  return true;
#else
  *err = Fmt("%s is zstd-compressed, but this build has no zstd (unzstd it first)", path.c_str());
  return false;
#endif
}

class Reader {
 public:
  Reader(const uint8_t* p, uint64_t n, std::string what) : p_(p), n_(n), what_(std::move(what)) {}
  bool U32(uint32_t* v) {
    if (n_ - pos_ < 4) return Fail("truncated");
    memcpy(v, p_ + pos_, 4);  // little-endian hosts only (x86-64, arm64)
    pos_ += 4;
    return true;
  }
  bool Bytes(const uint8_t** data, uint64_t* size, uint64_t max) {
    uint32_t n;
    if (!U32(&n)) return false;
    if (n > max)
      return Fail(Fmt("a length of %u is over the limit of %llu", n, (unsigned long long)max));
    if (n_ - pos_ < n) return Fail("truncated");
    *data = p_ + pos_;
    *size = n;
    pos_ += n;
    return true;
  }
  bool Str(std::string* s, uint64_t max) {
    const uint8_t* d;
    uint64_t n;
    if (!Bytes(&d, &n, max)) return false;
    if (memchr(d, 0, n)) return Fail("a string with a NUL byte");
    s->assign(reinterpret_cast<const char*>(d), n);
    return true;
  }
  void Skip(uint64_t n) { pos_ += std::min(n, n_ - pos_); }
  uint64_t pos() const { return pos_; }
  uint64_t left() const { return n_ - pos_; }
  const std::string& error() const { return error_; }
  bool Fail(const std::string& e) {
    if (error_.empty())
      error_ = Fmt("%s at byte %llu: %s", what_.c_str(), (unsigned long long)pos_, e.c_str());
    return false;
  }

 private:
  const uint8_t* p_;
  uint64_t n_, pos_ = 0;
  std::string what_;
  std::string error_;
};

}  // namespace

bool ParseTrace(const std::string& path, Trace* t, std::string* err) {
  t->path = path;
  if (!ReadFile(path, &t->bytes, err) || !MaybeDecompress(path, &t->bytes, err)) return false;
  Reader r(t->bytes.data(), t->bytes.size(), path);
  if (t->bytes.size() < 8 || memcmp(t->bytes.data(), kMagic, 8) != 0) {
    *err = Fmt("%s: not an ecrf GL trace (magic ECRFGLT1 missing)", path.c_str());
    return false;
  }
  r.Skip(8);
  if (!r.U32(&t->kind) || !r.Str(&t->meta, 1 << 24)) {
    *err = r.error();
    return false;
  }
  if (t->kind == kKindSetup) {
    uint32_t n;
    if (!r.Str(&t->setup_id, 256) || !r.U32(&n)) return Fail(err, r.error());
    if (n > 64) return Fail(err, Fmt("%s: %u limits", path.c_str(), n));
    for (uint32_t i = 0; i < n; ++i) {
      uint32_t e, v;
      if (!r.U32(&e) || !r.U32(&v)) return Fail(err, r.error());
      t->limits.emplace_back(e, static_cast<int32_t>(v));
    }
  } else if (t->kind == kKindFrame) {
    if (!r.Str(&t->setup_file, 4096) || !r.Str(&t->setup_id, 256) || !r.U32(&t->width) ||
        !r.U32(&t->height) || !r.U32(&t->canvas_w) || !r.U32(&t->canvas_h)) {
      return Fail(err, r.error());
    }
    auto ok = [](uint32_t v) { return v >= 1 && v <= 16384; };
    if (!ok(t->width) || !ok(t->height) || !ok(t->canvas_w) || !ok(t->canvas_h)) {
      return Fail(err, Fmt("%s: image size %ux%u / canvas %ux%u not in [1, 16384]", path.c_str(),
                           t->width, t->height, t->canvas_w, t->canvas_h));
    }
    if (t->setup_file.empty() || t->setup_file.find('/') != std::string::npos ||
        t->setup_file.find("..") != std::string::npos) {
      return Fail(err, Fmt("%s: bad setup file name '%s'", path.c_str(), t->setup_file.c_str()));
    }
  } else {
    return Fail(err, Fmt("%s: unknown trace kind %u", path.c_str(), t->kind));
  }
  uint32_t ncalls;
  if (!r.U32(&ncalls)) return Fail(err, r.error());
  if (ncalls == 0 || ncalls > (1u << 24))
    return Fail(err, Fmt("%s: %u calls", path.c_str(), ncalls));
  t->calls.reserve(std::min<uint32_t>(ncalls, 1u << 16));
  for (uint32_t i = 0; i < ncalls; ++i) {
    Call c;
    uint32_t len;
    if (!r.U32(&c.op) || !r.U32(&len)) return Fail(err, r.error());
    if (c.op >= kNumOps)
      return Fail(err, Fmt("%s: call %u has unknown op %u", path.c_str(), i, c.op));
    if (len > r.left())
      return Fail(err, Fmt("%s: call %u (%s) is truncated", path.c_str(), i, kOps[c.op].name));
    uint64_t start = r.pos();
    Reader p(t->bytes.data() + start, len,
             Fmt("%s call %u (%s)", path.c_str(), i, kOps[c.op].name));
    int nu = 0;
    bool ok = true;
    for (const char* l = kOps[c.op].layout; *l && ok; ++l) {
      if (*l == 'u') {
        ok = p.U32(&c.u[nu++]);
      } else if (*l == 's') {
        ok = p.Str(&c.str, c.op == kShaderSource ? (16u << 20) : 256u);
      } else if (*l == 'b') {
        ok = p.Bytes(&c.data, &c.size, 1ull << 31);
        c.has_data = ok;
      } else {  // 'o'
        uint32_t flag;
        ok = p.U32(&flag);
        if (ok && flag > 1) ok = p.Fail("bad data flag");
        if (ok && flag) ok = c.has_data = p.Bytes(&c.data, &c.size, 1ull << 31);
      }
    }
    if (!ok) return Fail(err, p.error());
    if (p.left() != 0) {
      return Fail(err, Fmt("%s: call %u (%s) has %llu bytes too many", path.c_str(), i,
                           kOps[c.op].name, (unsigned long long)p.left()));
    }
    r.Skip(len);
    t->calls.push_back(std::move(c));
    if (t->calls.back().op == kEnd && i + 1 != ncalls) {
      return Fail(err, Fmt("%s: end marker at call %u of %u", path.c_str(), i, ncalls));
    }
  }
  if (t->calls.back().op != kEnd) return Fail(err, Fmt("%s: no end marker", path.c_str()));
  if (r.left() != 0) {
    return Fail(err, Fmt("%s: %llu bytes after the end marker", path.c_str(),
                         (unsigned long long)r.left()));
  }
  return true;
}

namespace {

// Bytes per texel of the texture formats the viewer uploads (0: not supported).
uint32_t BytesPerTexel(uint32_t format, uint32_t type) {
  if (format == gl_enum::kRgba && type == gl_enum::kFloat) return 16;
  if (format == gl_enum::kRgba && type == gl_enum::kUnsignedByte) return 4;
  if (format == gl_enum::kRedInteger && type == gl_enum::kUnsignedByte) return 1;
  if (format == gl_enum::kRed && type == gl_enum::kFloat) return 4;
  if (format == gl_enum::kRed && type == gl_enum::kUnsignedByte) return 1;
  if (format == gl_enum::kRgbaInteger && type == gl_enum::kUnsignedByte) return 4;
  return 0;
}

struct Validator {
  std::vector<std::vector<uint8_t>> live = std::vector<std::vector<uint8_t>>(kNumKinds);
  uint32_t unpack_alignment = 4;

  bool Id(uint32_t kind, uint32_t id, bool null_ok, std::string* e) {
    if (id == 0) {
      if (!null_ok) *e = Fmt("null %s", kKindName[kind]);
      return null_ok;
    }
    if (id >= kMaxId || id >= live[kind].size() || !live[kind][id]) {
      *e = Fmt("%s %u was never created (or was deleted)", kKindName[kind], id);
      return false;
    }
    return true;
  }

  bool Check(const Call& c, std::string* e) {
    const uint32_t* u = c.u;
    switch (c.op) {
      case kCreate:
        if (u[0] == 0 || u[0] >= kNumKinds) return Fail(e, Fmt("object kind %u", u[0]));
        if (u[1] == 0 || u[1] >= kMaxId) return Fail(e, Fmt("object id %u", u[1]));
        if (u[1] < live[u[0]].size() && live[u[0]][u[1]])
          return Fail(e, Fmt("%s %u created twice", kKindName[u[0]], u[1]));
        if (u[0] == kShader && u[2] != gl_enum::kVertexShader && u[2] != gl_enum::kFragmentShader)
          return Fail(e, Fmt("shader type 0x%x", u[2]));
        if (live[u[0]].size() <= u[1]) live[u[0]].resize(u[1] + 1);
        live[u[0]][u[1]] = 1;
        return true;
      case kDelete:
        if (u[0] == 0 || u[0] >= kNumKinds) return Fail(e, Fmt("object kind %u", u[0]));
        if (!Id(u[0], u[1], false, e)) return false;
        live[u[0]][u[1]] = 0;
        return true;
      case kShaderSource:
      case kCompileShader:
        return Id(kShader, u[0], false, e);
      case kAttachShader:
        return Id(kProgram, u[0], false, e) && Id(kShader, u[1], false, e);
      case kLinkProgram:
        return Id(kProgram, u[0], false, e);
      case kUseProgram:
        return Id(kProgram, u[0], true, e);
      case kUniformBlockBinding:
        return Id(kProgram, u[0], false, e);
      case kUniform:
        if (!Id(kProgram, u[0], false, e)) return false;
        if (u[1] > 1 || u[2] < 1 || u[2] > 4 || u[3] < 1 || u[3] > (1u << 20))
          return Fail(e, "bad uniform shape");
        if (c.size != uint64_t(u[2]) * u[3] * 4)
          return Fail(e, Fmt("uniform %s: %llu bytes for %u x %u values", c.str.c_str(),
                             (unsigned long long)c.size, u[3], u[2]));
        return true;
      case kBindTexture:
        return Id(kTexture, u[1], true, e);
      case kPixelStorei:
        if (u[0] != gl_enum::kUnpackAlignment || (u[1] != 1 && u[1] != 2 && u[1] != 4 && u[1] != 8))
          return Fail(e, Fmt("pixelStorei(0x%x, %d) is not supported", u[0], (int)u[1]));
        unpack_alignment = u[1];
        return true;
      case kTexImage: {
        // target level internal w h d border format type
        if (u[0] != gl_enum::kTexture2D && u[0] != gl_enum::kTexture2DArray &&
            u[0] != gl_enum::kTexture3D)
          return Fail(e, Fmt("texture target 0x%x", u[0]));
        uint32_t w = u[3], h = u[4], d = u[5];
        if (w < 1 || h < 1 || d < 1 || w > 65536 || h > 65536 || d > 65536 ||
            (u[0] == gl_enum::kTexture2D && d != 1) || u[1] > 16)
          return Fail(e, Fmt("texture size %ux%ux%u", w, h, d));
        uint32_t bpp = BytesPerTexel(u[7], u[8]);
        if (!bpp)
          return Fail(e, Fmt("texture format 0x%x / type 0x%x is not supported", u[7], u[8]));
        if (!c.has_data) return true;
        uint64_t row = uint64_t(w) * bpp,
                 stride = (row + unpack_alignment - 1) / unpack_alignment * unpack_alignment;
        uint64_t need = (uint64_t(h) * d - 1) * stride + row;
        if (c.size < need)
          return Fail(e, Fmt("texture %ux%ux%u needs %llu bytes, has %llu", w, h, d,
                             (unsigned long long)need, (unsigned long long)c.size));
        return true;
      }
      case kTexStorage2D:
        if (u[0] != gl_enum::kTexture2D || u[1] < 1 || u[1] > 16 || u[3] < 1 || u[4] < 1 ||
            u[3] > 65536 || u[4] > 65536)
          return Fail(e, "bad texStorage2D");
        return true;
      case kBindBuffer:
        return Id(kBuffer, u[1], true, e);
      case kBufferData:
        if (u[0] != gl_enum::kUniformBuffer && u[0] != gl_enum::kArrayBuffer)
          return Fail(e, Fmt("buffer target 0x%x", u[0]));
        return true;
      case kBindBufferBase:
        if (u[1] > 1024) return Fail(e, Fmt("binding %u", u[1]));
        return Id(kBuffer, u[2], true, e);
      case kBindFramebuffer:
        return Id(kFramebuffer, u[1], true, e);
      case kFramebufferTexture2D:
        return Id(kTexture, u[3], true, e);
      case kBindVertexArray:
        return Id(kVertexArray, u[0], true, e);
      case kViewport:
      case kScissor:
        if (int32_t(u[2]) < 0 || int32_t(u[3]) < 0 || u[2] > 65536 || u[3] > 65536)
          return Fail(e, "negative or huge viewport/scissor");
        return true;
      case kDrawArrays:
        if (int32_t(u[1]) < 0 || int32_t(u[2]) < 0 || u[2] > (1u << 24))
          return Fail(e, "bad draw range");
        return true;
      case kReadPixels:
        if (u[4] != gl_enum::kRgba || u[5] != gl_enum::kUnsignedByte)
          return Fail(e, "readPixels other than RGBA / UNSIGNED_BYTE");
        if (int32_t(u[0]) < 0 || int32_t(u[1]) < 0 || u[2] < 1 || u[3] < 1 || u[2] > 16384 ||
            u[3] > 16384)
          return Fail(e, "bad readPixels rectangle");
        return true;
      case kMark:
        if (u[0] != kMarkFrameBegin && u[0] != kMarkFrameEnd) return Fail(e, Fmt("mark %u", u[0]));
        return true;
      default:
        return true;
    }
  }
};

}  // namespace

bool Validate(const Trace& setup, const Trace& frame, size_t* begin, size_t* end,
              std::string* err) {
  Validator v;
  for (const Trace* t : {&setup, &frame}) {
    for (size_t i = 0; i < t->calls.size(); ++i) {
      std::string e;
      if (!v.Check(t->calls[i], &e)) {
        *err =
            Fmt("%s: call %zu (%s): %s", t->path.c_str(), i, kOps[t->calls[i].op].name, e.c_str());
        return false;
      }
      if (t == &setup && t->calls[i].op == kMark)
        return Fail(err, Fmt("%s: a frame mark in a setup trace", t->path.c_str()));
    }
  }
  *begin = *end = 0;
  for (size_t i = 0; i < frame.calls.size(); ++i) {
    if (frame.calls[i].op != kMark) continue;
    if (frame.calls[i].u[0] == kMarkFrameBegin && *begin == 0 && *end == 0)
      *begin = i + 1;
    else if (frame.calls[i].u[0] == kMarkFrameEnd && *begin != 0 && *end == 0)
      *end = i;
    else
      return Fail(err, Fmt("%s: frame marks out of order", frame.path.c_str()));
  }
  if (*begin == 0 || *end == 0)
    return Fail(err, Fmt("%s: no frame marks (not a frame trace?)", frame.path.c_str()));
  return true;
}

}  // namespace gl_replay
}  // namespace ecrf
