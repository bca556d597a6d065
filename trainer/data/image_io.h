// Decoding and encoding of the images that datasets ship (PNG, JPEG) into float pixels.
#ifndef ECRF_TRAINER_DATA_IMAGE_IO_H_
#define ECRF_TRAINER_DATA_IMAGE_IO_H_

#include <cstdint>
#include <string>
#include <vector>

namespace ecrf::trainer {

// Interleaved pixels, row-major from the top-left, values in [0, 1]. channels is 1 (gray),
// 2 (gray+alpha), 3 (RGB) or 4 (RGBA); alpha is straight (not premultiplied), as PNG stores it.
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<float> pixels;

  float& at(int x, int y, int c) {
    return pixels[(static_cast<size_t>(y) * width + x) * channels + c];
  }
  float at(int x, int y, int c) const {
    return pixels[(static_cast<size_t>(y) * width + x) * channels + c];
  }
};

// An image of the given shape with every sample set to `value`.
Image MakeImage(int width, int height, int channels, float value = 0.0f);

struct ImageSize {
  int width = 0;  // upright: after a JPEG's EXIF orientation
  int height = 0;
  int orientation = 1;  // a JPEG's EXIF Orientation (1 to 8; 1: stored upright, and every PNG)
};

// Decodes a PNG (8 or 16 bit; gray, gray+alpha, RGB, RGBA, palette; tRNS becomes an alpha
// channel) or a baseline/progressive JPEG (gray or RGB). The format comes from the file's
// magic bytes, not its extension. Colour values are returned as stored: no gamma conversion.
// A JPEG is turned upright as its EXIF Orientation tag says (phones store photos sideways).
// Throws std::runtime_error naming the path for a missing, unrecognised, corrupt or truncated file.
// With `expected`, a file whose header gives another (upright) size is refused before it is
// decoded: "image is WxH but its camera says WxH" (a small PNG can hold 8192^2 pixels).
Image LoadImage(const std::string& path, const ImageSize* expected = nullptr);

// The largest image LoadImage decodes, checked from the file's header before decoding: 2^26
// pixels (8192 x 8192), the decoder's image limit too. A 16384^2 PNG of 1 MB would otherwise
// cost 7 GiB while loading.
inline constexpr int64_t kMaxImagePixels = int64_t{1} << 26;

// Width and height from the file header only (PNG reads 24 bytes), for datasets whose JSON
// leaves the image size implicit. Same errors as LoadImage.
ImageSize ReadImageSize(const std::string& path);

// Writes `image` (1 to 4 channels, values clamped to [0, 1]) as a PNG of 8 or 16 bits per
// sample. The file is encoded to a temporary file in the destination directory and renamed
// over `path`, so readers never see a half-written image. Throws std::runtime_error on failure.
void SavePng(const std::string& path, const Image& image, int bit_depth = 8);

// Blends onto a white background: rgb * a + (1 - a), returning 3 channels. Gray is replicated
// to RGB; images without alpha are treated as opaque.
Image CompositeOnWhite(const Image& image);

// Area (box) filter: each output pixel is the mean of a factor x factor block. The output is
// floor(width / factor) x floor(height / factor); leftover columns on the right and rows at the
// bottom are dropped, which keeps pixel (0, 0) anchored so intrinsics scale by 1/factor exactly.
// Averages every channel as is, so composite straight-alpha images first. factor must be >= 1.
Image DownscaleArea(const Image& image, int factor);

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_DATA_IMAGE_IO_H_
