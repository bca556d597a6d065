#include "trainer/data/image_io.h"

// jpeglib.h uses FILE and size_t without including their headers.
#include <cstddef>
#include <cstdio>

#include <jpeglib.h>
#include <png.h>

// jerror.h needs jpeglib.h first for the J_MESSAGE_CODE enum it fills.
#include <jerror.h>

#include <unistd.h>
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>

#include "trainer/data/exif_orientation.h"
#include "trainer/data/file_io.h"

namespace ecrf::trainer {
namespace {

// Keeps a corrupt header from asking for gigabytes before decoding fails.
constexpr uint64_t kMaxSamples = uint64_t{1} << 30;

[[noreturn]] void Fail(const std::string& path, const std::string& problem) {
  throw std::runtime_error(path + ": " + problem);
}

struct FileCloser {
  void operator()(FILE* f) const {
    if (f) std::fclose(f);
  }
};
using FilePtr = std::unique_ptr<FILE, FileCloser>;

FilePtr OpenForRead(const std::string& path) {
  CheckRegularFile(path);
  FilePtr file(std::fopen(path.c_str(), "rb"));
  if (!file) Fail(path, std::string("cannot open: ") + std::strerror(errno));
  return file;
}

// Reads at most `limit` bytes; whole-file reads keep the decoders free of I/O error handling.
std::vector<uint8_t> ReadBytes(const std::string& path, size_t limit = SIZE_MAX) {
  FilePtr file = OpenForRead(path);
  std::vector<uint8_t> bytes;
  uint8_t chunk[1 << 16];
  while (bytes.size() < limit) {
    size_t want = std::min(sizeof chunk, limit - bytes.size());
    size_t got = std::fread(chunk, 1, want, file.get());
    bytes.insert(bytes.end(), chunk, chunk + got);
    if (got < want) {
      if (std::ferror(file.get())) Fail(path, std::string("read error: ") + std::strerror(errno));
      break;
    }
  }
  return bytes;
}

enum class Format { kPng, kJpeg, kUnknown };

Format DetectFormat(const std::vector<uint8_t>& bytes) {
  static const uint8_t kPngMagic[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (bytes.size() >= 8 && std::memcmp(bytes.data(), kPngMagic, 8) == 0) return Format::kPng;
  if (bytes.size() >= 3 && bytes[0] == 0xff && bytes[1] == 0xd8 && bytes[2] == 0xff) {
    return Format::kJpeg;
  }
  return Format::kUnknown;
}

[[noreturn]] void FailUnknownFormat(const std::string& path, size_t size) {
  if (size == 0) Fail(path, "empty file, expected a PNG or JPEG image");
  Fail(path, "not a PNG or JPEG image (unrecognised header)");
}

// ---- PNG decoding. libpng reports errors by longjmp, so everything that owns memory lives
// outside the setjmp frame (in *out) and the frame itself holds only plain pointers.

struct PngSource {
  const uint8_t* data;
  size_t size;
  size_t pos;
  char error[256];
};

struct PngRaw {
  uint32_t width = 0, height = 0;
  int channels = 0, bit_depth = 0;
  size_t row_bytes = 0;
  std::vector<uint8_t> bytes;
  std::vector<png_bytep> rows;
};

void PngOnError(png_structp png, png_const_charp message) {
  auto* source = static_cast<PngSource*>(png_get_error_ptr(png));
  std::snprintf(source->error, sizeof source->error, "%s", message);
  png_longjmp(png, 1);
}

// Ancillary-chunk complaints (e.g. sRGB profiles) are harmless for training data.
void PngOnWarning(png_structp, png_const_charp) {}

void PngRead(png_structp png, png_bytep out, size_t count) {
  auto* source = static_cast<PngSource*>(png_get_io_ptr(png));
  if (source->size - source->pos < count) png_error(png, "unexpected end of file (truncated)");
  std::memcpy(out, source->data + source->pos, count);
  source->pos += count;
}

bool DecodePngRaw(PngSource* source, PngRaw* out) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, source, PngOnError, PngOnWarning);
  if (!png) {
    std::snprintf(source->error, sizeof source->error, "cannot create libpng reader");
    return false;
  }
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    std::snprintf(source->error, sizeof source->error, "cannot create libpng info");
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  png_set_read_fn(png, source, PngRead);
  png_read_info(png, info);
  // Palette -> RGB, gray below 8 bits -> 8 bits, tRNS -> alpha channel.
  png_set_expand(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  out->width = png_get_image_width(png, info);
  out->height = png_get_image_height(png, info);
  out->channels = png_get_channels(png, info);
  out->bit_depth = png_get_bit_depth(png, info);
  out->row_bytes = png_get_rowbytes(png, info);
  if (uint64_t{out->width} * out->height * out->channels > kMaxSamples) {
    png_error(png, "image too large");
  }
  out->bytes.resize(out->row_bytes * out->height);
  out->rows.resize(out->height);
  for (uint32_t y = 0; y < out->height; ++y) out->rows[y] = out->bytes.data() + y * out->row_bytes;
  png_read_image(png, out->rows.data());
  // Reading to IEND is what notices a file cut off after the last pixel row.
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

Image DecodePng(const std::string& path, const std::vector<uint8_t>& bytes) {
  PngSource source{bytes.data(), bytes.size(), 0, {0}};
  PngRaw raw;
  if (!DecodePngRaw(&source, &raw))
    Fail(path, std::string("corrupt or truncated PNG: ") + source.error);
  if (raw.bit_depth != 8 && raw.bit_depth != 16) {
    Fail(path, "unsupported PNG bit depth " + std::to_string(raw.bit_depth));
  }
  Image image = MakeImage(static_cast<int>(raw.width), static_cast<int>(raw.height), raw.channels);
  const size_t samples_per_row = size_t{raw.width} * raw.channels;
  for (uint32_t y = 0; y < raw.height; ++y) {
    const uint8_t* row = raw.rows[y];
    float* dst = image.pixels.data() + y * samples_per_row;
    if (raw.bit_depth == 8) {
      for (size_t i = 0; i < samples_per_row; ++i) dst[i] = row[i] / 255.0f;
    } else {
      // PNG stores 16-bit samples big-endian.
      for (size_t i = 0; i < samples_per_row; ++i)
        dst[i] = ((row[2 * i] << 8) | row[2 * i + 1]) / 65535.0f;
    }
  }
  return image;
}

// ---- JPEG decoding, same longjmp discipline as PNG.

struct JpegErrorManager {
  jpeg_error_mgr pub;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void JpegOnError(j_common_ptr cinfo) {
  auto* manager = reinterpret_cast<JpegErrorManager*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, manager->message);
  std::longjmp(manager->jump, 1);
}

// libjpeg only warns about corrupt or truncated data and pads the image with grey; for
// training data a silently damaged view is worse than an error. Stray bytes between markers
// are the one warning that real cameras trigger without damaging pixels.
void JpegOnMessage(j_common_ptr cinfo, int level) {
  if (level < 0 && cinfo->err->msg_code != JWRN_EXTRANEOUS_DATA) JpegOnError(cinfo);
}

struct JpegRaw {
  int width = 0, height = 0, channels = 0;  // upright: after the EXIF orientation
  int orientation = 1;                      // EXIF Orientation, 1 to 8 (1: as stored)
  bool unsupported = false;                 // a valid JPEG this loader does not read
  std::vector<uint8_t> bytes;
  char error[JMSG_LENGTH_MAX] = {0};
};

bool DecodeJpegRaw(const std::vector<uint8_t>& data, bool header_only, JpegRaw* out) {
  jpeg_decompress_struct cinfo;
  JpegErrorManager errors;
  cinfo.err = jpeg_std_error(&errors.pub);
  errors.pub.error_exit = JpegOnError;
  errors.pub.emit_message = JpegOnMessage;
  errors.message[0] = 0;
  if (setjmp(errors.jump)) {
    jpeg_destroy_decompress(&cinfo);
    std::snprintf(out->error, sizeof out->error, "%s", errors.message);
    return false;
  }
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, data.data(), static_cast<unsigned long>(data.size()));
  jpeg_save_markers(&cinfo, JPEG_APP0 + 1, 0xFFFF);  // EXIF lives in APP1
  jpeg_read_header(&cinfo, TRUE);
  for (jpeg_saved_marker_ptr m = cinfo.marker_list; m != nullptr; m = m->next) {
    if (m->marker != JPEG_APP0 + 1) continue;
    const int orientation = ExifOrientation(m->data, m->data_length);
    if (orientation != 1) {
      out->orientation = orientation;
      break;
    }
  }
  const bool swap = OrientationSwapsAxes(out->orientation);
  out->width = static_cast<int>(swap ? cinfo.image_height : cinfo.image_width);
  out->height = static_cast<int>(swap ? cinfo.image_width : cinfo.image_height);
  if (header_only) {
    jpeg_destroy_decompress(&cinfo);
    return true;
  }
  if (cinfo.num_components == 1) {
    cinfo.out_color_space = JCS_GRAYSCALE;
  } else if (cinfo.jpeg_color_space == JCS_YCbCr || cinfo.jpeg_color_space == JCS_RGB) {
    cinfo.out_color_space = JCS_RGB;
  } else {
    jpeg_destroy_decompress(&cinfo);
    std::snprintf(out->error, sizeof out->error,
                  "unsupported JPEG: CMYK or YCCK colour (print-ready files; save it as RGB)");
    out->unsupported = true;
    return false;
  }
  jpeg_start_decompress(&cinfo);
  out->channels = cinfo.output_components;
  const size_t row_bytes = size_t{cinfo.output_width} * cinfo.output_components;
  if (uint64_t{row_bytes} * cinfo.output_height > kMaxSamples) {
    jpeg_destroy_decompress(&cinfo);
    std::snprintf(out->error, sizeof out->error, "image too large");
    return false;
  }
  out->bytes.resize(row_bytes * cinfo.output_height);
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW row = out->bytes.data() + size_t{cinfo.output_scanline} * row_bytes;
    jpeg_read_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
  int width = static_cast<int>(cinfo.output_width), height = static_cast<int>(cinfo.output_height);
  ApplyOrientation(out->orientation, out->channels, &width, &height, &out->bytes);
  return true;
}

Image DecodeJpeg(const std::string& path, const std::vector<uint8_t>& bytes) {
  JpegRaw raw;
  if (!DecodeJpegRaw(bytes, /*header_only=*/false, &raw)) {
    Fail(path, raw.unsupported ? std::string(raw.error)
                               : std::string("corrupt or truncated JPEG: ") + raw.error);
  }
  Image image = MakeImage(raw.width, raw.height, raw.channels);
  for (size_t i = 0; i < raw.bytes.size(); ++i) image.pixels[i] = raw.bytes[i] / 255.0f;
  return image;
}

// ---- PNG encoding into memory; the file is written in one piece afterwards.

struct PngSink {
  std::vector<uint8_t> bytes;
  char error[256];
};

void PngWrite(png_structp png, png_bytep data, size_t count) {
  auto* sink = static_cast<PngSink*>(png_get_io_ptr(png));
  try {
    sink->bytes.insert(sink->bytes.end(), data, data + count);
  } catch (...) {
    // Exceptions must not unwind through libpng's C frames.
    png_error(png, "out of memory");
  }
}

void PngFlush(png_structp) {}

void PngOnWriteError(png_structp png, png_const_charp message) {
  auto* sink = static_cast<PngSink*>(png_get_error_ptr(png));
  std::snprintf(sink->error, sizeof sink->error, "%s", message);
  png_longjmp(png, 1);
}

bool EncodePngRaw(const Image& image, int bit_depth, const std::vector<png_bytep>& rows,
                  PngSink* sink) {
  png_structp png =
      png_create_write_struct(PNG_LIBPNG_VER_STRING, sink, PngOnWriteError, PngOnWarning);
  if (!png) {
    std::snprintf(sink->error, sizeof sink->error, "cannot create libpng writer");
    return false;
  }
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    std::snprintf(sink->error, sizeof sink->error, "cannot create libpng info");
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  static const int kColorTypes[5] = {0, PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA,
                                     PNG_COLOR_TYPE_RGB, PNG_COLOR_TYPE_RGB_ALPHA};
  png_set_write_fn(png, sink, PngWrite, PngFlush);
  png_set_IHDR(png, info, image.width, image.height, bit_depth, kColorTypes[image.channels],
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_write_image(png, const_cast<png_bytepp>(rows.data()));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

}  // namespace

Image MakeImage(int width, int height, int channels, float value) {
  Image image;
  image.width = width;
  image.height = height;
  image.channels = channels;
  image.pixels.assign(static_cast<size_t>(width) * height * channels, value);
  return image;
}

namespace {

// The size an image's header declares, from its first bytes (PNG: 24) or, for JPEG, the whole
// file (the SOF marker can sit after large EXIF blocks, so libjpeg finds it).
ImageSize SizeFromHeader(const std::string& path, const std::vector<uint8_t>& bytes) {
  switch (DetectFormat(bytes)) {
    case Format::kPng: {
      // Signature, IHDR length and tag, then width and height: 24 bytes.
      if (bytes.size() < 24 || std::memcmp(bytes.data() + 12, "IHDR", 4) != 0) {
        Fail(path, "corrupt or truncated PNG: missing IHDR header");
      }
      auto be32 = [&](size_t at) {
        return (uint32_t{bytes[at]} << 24) | (uint32_t{bytes[at + 1]} << 16) |
               (uint32_t{bytes[at + 2]} << 8) | bytes[at + 3];
      };
      uint32_t width = be32(16), height = be32(20);
      if (width == 0 || height == 0 || width > 0x7fffffff || height > 0x7fffffff) {
        Fail(path, "corrupt PNG: invalid image size in IHDR");
      }
      return {static_cast<int>(width), static_cast<int>(height)};
    }
    case Format::kJpeg: {
      JpegRaw raw;
      if (!DecodeJpegRaw(bytes, /*header_only=*/true, &raw)) {
        Fail(path, std::string("corrupt or truncated JPEG: ") + raw.error);
      }
      return {raw.width, raw.height, raw.orientation};
    }
    case Format::kUnknown:
      break;
  }
  FailUnknownFormat(path, bytes.size());
}

}  // namespace

Image LoadImage(const std::string& path, const ImageSize* expected) {
  const std::vector<uint8_t> bytes = ReadBytes(path);
  // The header alone, before decoding allocates anything.
  const ImageSize size = SizeFromHeader(path, bytes);
  if (expected && (size.width != expected->width || size.height != expected->height)) {
    Fail(path, "image is " + std::to_string(size.width) + "x" + std::to_string(size.height) +
                   " but its camera says " + std::to_string(expected->width) + "x" +
                   std::to_string(expected->height));
  }
  if (int64_t{size.width} * size.height > kMaxImagePixels) {
    Fail(path, "image is " + std::to_string(size.width) + "x" + std::to_string(size.height) +
                   " = " + std::to_string(int64_t{size.width} * size.height) +
                   " pixels; ecrf loads at most " + std::to_string(kMaxImagePixels) +
                   " pixels per image (shrink it first)");
  }
  if (DetectFormat(bytes) == Format::kPng) return DecodePng(path, bytes);
  return DecodeJpeg(path, bytes);  // SizeFromHeader refused every other format
}

ImageSize ReadImageSize(const std::string& path) {
  std::vector<uint8_t> bytes = ReadBytes(path, 24);
  if (DetectFormat(bytes) == Format::kJpeg) bytes = ReadBytes(path);
  return SizeFromHeader(path, bytes);
}

void SavePng(const std::string& path, const Image& image, int bit_depth) {
  if (image.channels < 1 || image.channels > 4) {
    Fail(path,
         "cannot save a PNG with " + std::to_string(image.channels) + " channels (need 1 to 4)");
  }
  if (image.width <= 0 || image.height <= 0) {
    Fail(path, "cannot save an empty image (" + std::to_string(image.width) + "x" +
                   std::to_string(image.height) + ")");
  }
  if (image.pixels.size() != static_cast<size_t>(image.width) * image.height * image.channels) {
    Fail(path, "image pixel buffer does not match its width x height x channels");
  }
  if (bit_depth != 8 && bit_depth != 16) {
    Fail(path, "PNG bit depth must be 8 or 16, got " + std::to_string(bit_depth));
  }
  const int bytes_per_sample = bit_depth / 8;
  const size_t row_bytes = static_cast<size_t>(image.width) * image.channels * bytes_per_sample;
  const float max_value = bit_depth == 8 ? 255.0f : 65535.0f;
  std::vector<uint8_t> samples(row_bytes * image.height);
  for (size_t i = 0; i < image.pixels.size(); ++i) {
    float v = image.pixels[i];
    v = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f;  // also maps NaN to 0
    auto q = static_cast<uint32_t>(v * max_value + 0.5f);
    if (bit_depth == 8) {
      samples[i] = static_cast<uint8_t>(q);
    } else {
      samples[2 * i] = static_cast<uint8_t>(q >> 8);
      samples[2 * i + 1] = static_cast<uint8_t>(q & 0xff);
    }
  }
  std::vector<png_bytep> rows(image.height);
  for (int y = 0; y < image.height; ++y) rows[y] = samples.data() + y * row_bytes;
  PngSink sink;
  sink.error[0] = 0;
  if (!EncodePngRaw(image, bit_depth, rows, &sink))
    Fail(path, std::string("PNG encoding failed: ") + sink.error);
  WriteFileAtomically(path, sink.bytes);
}

Image CompositeOnWhite(const Image& image) {
  if (image.channels < 1 || image.channels > 4) {
    throw std::runtime_error("CompositeOnWhite: unsupported channel count " +
                             std::to_string(image.channels));
  }
  Image out = MakeImage(image.width, image.height, 3);
  const bool has_alpha = image.channels == 2 || image.channels == 4;
  const int colour_channels = image.channels >= 3 ? 3 : 1;
  const size_t count = static_cast<size_t>(image.width) * image.height;
  for (size_t p = 0; p < count; ++p) {
    const float* src = image.pixels.data() + p * image.channels;
    const float alpha = has_alpha ? src[image.channels - 1] : 1.0f;
    for (int c = 0; c < 3; ++c) {
      const float colour = src[colour_channels == 3 ? c : 0];
      out.pixels[p * 3 + c] = colour * alpha + (1.0f - alpha);
    }
  }
  return out;
}

Image DownscaleArea(const Image& image, int factor) {
  if (factor < 1)
    throw std::runtime_error("DownscaleArea: factor must be >= 1, got " + std::to_string(factor));
  if (factor == 1) return image;
  Image out = MakeImage(image.width / factor, image.height / factor, image.channels);
  const float inv_area = 1.0f / static_cast<float>(factor * factor);
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      for (int c = 0; c < image.channels; ++c) {
        float sum = 0.0f;
        for (int dy = 0; dy < factor; ++dy) {
          for (int dx = 0; dx < factor; ++dx) sum += image.at(x * factor + dx, y * factor + dy, c);
        }
        out.at(x, y, c) = sum * inv_area;
      }
    }
  }
  return out;
}

}  // namespace ecrf::trainer
