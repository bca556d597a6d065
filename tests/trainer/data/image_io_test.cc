#include "trainer/data/image_io.h"

#include <gtest/gtest.h>

// jpeglib.h uses FILE and size_t without including their headers.
#include <cstddef>
#include <cstdio>

#include <jpeglib.h>
#include <png.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "tests/common/error_of.h"

namespace ecrf::trainer {
namespace {

using testing_errors::ErrorOf;

namespace fs = std::filesystem;

// A fresh directory per test so parallel ctest runs never collide.
class ImageIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("ecrf_image_io_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

std::vector<uint8_t> ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

void WriteAll(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

// Every sample distinct and exactly representable at the given bit depth.
Image Ramp(int width, int height, int channels, int levels) {
  Image image = MakeImage(width, height, channels);
  for (size_t i = 0; i < image.pixels.size(); ++i) {
    image.pixels[i] = static_cast<float>((i * 37) % (levels + 1)) / static_cast<float>(levels);
  }
  return image;
}

// Encodes RGB, gray or (4 channels) CMYK bytes with libjpeg, quality 95, with an APP1 segment
// when app1 is given.
void WriteJpeg(const std::string& path, int width, int height, int channels,
               const std::vector<uint8_t>& bytes, const std::vector<uint8_t>& app1 = {}) {
  jpeg_compress_struct cinfo;
  jpeg_error_mgr errors;
  cinfo.err = jpeg_std_error(&errors);
  jpeg_create_compress(&cinfo);
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&cinfo, &buffer, &size);
  cinfo.image_width = width;
  cinfo.image_height = height;
  cinfo.input_components = channels;
  cinfo.in_color_space = channels == 4 ? JCS_CMYK : (channels == 3 ? JCS_RGB : JCS_GRAYSCALE);
  jpeg_set_defaults(&cinfo);
  jpeg_set_quality(&cinfo, 95, TRUE);
  jpeg_start_compress(&cinfo, TRUE);
  if (!app1.empty()) {
    jpeg_write_marker(&cinfo, JPEG_APP0 + 1, app1.data(), static_cast<unsigned>(app1.size()));
  }
  while (cinfo.next_scanline < cinfo.image_height) {
    JSAMPROW row =
        const_cast<uint8_t*>(bytes.data()) + size_t{cinfo.next_scanline} * width * channels;
    jpeg_write_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_compress(&cinfo);
  jpeg_destroy_compress(&cinfo);
  WriteAll(path, std::vector<uint8_t>(buffer, buffer + size));
  free(buffer);
}

// Four flat quadrants: red, green, blue, white; flat areas survive JPEG almost exactly.
void WriteQuadrantJpeg(const std::string& path) {
  const int size = 32;
  std::vector<uint8_t> rgb(size * size * 3);
  const uint8_t colours[4][3] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {255, 255, 255}};
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const uint8_t* c = colours[(y >= size / 2) * 2 + (x >= size / 2)];
      for (int k = 0; k < 3; ++k) rgb[(y * size + x) * 3 + k] = c[k];
    }
  }
  WriteJpeg(path, size, size, 3, rgb);
}

// An EXIF APP1 payload whose IFD0 holds only the Orientation tag (0x0112, SHORT), in the byte
// order a camera chose: "II" little-endian or "MM" big-endian.
std::vector<uint8_t> ExifWithOrientation(int orientation, bool big_endian) {
  std::vector<uint8_t> b = {'E', 'x', 'i', 'f', 0, 0};
  auto u16 = [&](int v) {
    const uint8_t lo = static_cast<uint8_t>(v & 0xff), hi = static_cast<uint8_t>(v >> 8);
    b.insert(b.end(), big_endian ? std::initializer_list<uint8_t>{hi, lo}
                                 : std::initializer_list<uint8_t>{lo, hi});
  };
  auto u32 = [&](uint32_t v) {
    big_endian ? (u16(int(v >> 16)), u16(int(v & 0xffff)))
               : (u16(int(v & 0xffff)), u16(int(v >> 16)));
  };
  b.push_back(big_endian ? 'M' : 'I');
  b.push_back(big_endian ? 'M' : 'I');
  u16(42);
  u32(8);  // IFD0 right after the header
  u16(1);  // one entry
  u16(0x0112);
  u16(3);  // SHORT
  u32(1);
  u16(orientation);
  u16(0);  // the value field's unused half
  u32(0);  // no next IFD
  return b;
}

// A 48x32 JPEG of four flat quadrants (top-left red, top-right green, bottom-left blue,
// bottom-right white) stored with the given EXIF orientation.
void WriteOrientedJpeg(const std::string& path, const std::vector<uint8_t>& app1) {
  const int w = 48, h = 32;
  std::vector<uint8_t> rgb(w * h * 3);
  const uint8_t colours[4][3] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {255, 255, 255}};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const uint8_t* c = colours[(y >= h / 2) * 2 + (x >= w / 2)];
      for (int k = 0; k < 3; ++k) rgb[(y * w + x) * 3 + k] = c[k];
    }
  }
  WriteJpeg(path, w, h, 3, rgb, app1);
}

// Phones store photos sideways and say so in EXIF: each orientation loads upright. Where the stored
// top-left (red) and top-right (green) quadrants land pins each of the eight down.
TEST_F(ImageIoTest, JpegsLoadUprightAsTheirExifOrientationSays) {
  enum Corner { kTL, kTR, kBL, kBR };
  const Corner red_at[9] = {kTL, kTL, kTR, kBR, kBL, kTL, kTR, kBR, kBL};
  const Corner green_at[9] = {kTR, kTR, kTL, kBL, kBR, kBL, kBR, kTR, kTL};
  for (const bool big_endian : {false, true}) {
    for (int o = 1; o <= 8; ++o) {
      SCOPED_TRACE(testing::Message() << "orientation " << o << (big_endian ? " MM" : " II"));
      const std::string path = Path("oriented_" + std::to_string(o) + ".jpg");
      WriteOrientedJpeg(path, ExifWithOrientation(o, big_endian));
      const Image image = LoadImage(path);
      const bool swapped = o >= 5;
      ASSERT_EQ(image.width, swapped ? 32 : 48);
      ASSERT_EQ(image.height, swapped ? 48 : 32);
      const ImageSize size = ReadImageSize(path);
      EXPECT_EQ(size.width, image.width);
      EXPECT_EQ(size.height, image.height);
      EXPECT_EQ(size.orientation, o);
      auto colour_at = [&](Corner c) {  // a pixel well inside that quadrant
        const int x = (c == kTR || c == kBR) ? image.width - 4 : 3;
        const int y = (c == kBL || c == kBR) ? image.height - 4 : 3;
        return std::vector<float>{image.at(x, y, 0), image.at(x, y, 1), image.at(x, y, 2)};
      };
      const std::vector<float> red = colour_at(red_at[o]), green = colour_at(green_at[o]);
      EXPECT_GT(red[0], 0.9f);
      EXPECT_LT(red[1], 0.1f);
      EXPECT_LT(green[0], 0.1f);
      EXPECT_GT(green[1], 0.9f);
      EXPECT_LT(green[2], 0.1f);
    }
  }
  // An APP1 segment that is not EXIF (XMP), or an orientation outside 1 to 8, leaves it as stored.
  const std::string xmp_text = "http://ns.adobe.com/xap/1.0/";
  WriteOrientedJpeg(Path("xmp.jpg"), std::vector<uint8_t>(xmp_text.begin(), xmp_text.end()));
  EXPECT_EQ(ReadImageSize(Path("xmp.jpg")).orientation, 1);
  EXPECT_EQ(LoadImage(Path("xmp.jpg")).width, 48);
  WriteOrientedJpeg(Path("nine.jpg"), ExifWithOrientation(9, false));
  EXPECT_EQ(LoadImage(Path("nine.jpg")).width, 48);
}

class PngRoundTrip : public ImageIoTest,
                     public ::testing::WithParamInterface<std::tuple<int, int>> {};

TEST_P(PngRoundTrip, LoadsWhatWasSaved) {
  const auto [channels, bit_depth] = GetParam();
  const Image original = Ramp(7, 5, channels, bit_depth == 8 ? 255 : 65535);
  const std::string path = Path("round_trip.png");
  SavePng(path, original, bit_depth);
  const Image loaded = LoadImage(path);
  ASSERT_EQ(loaded.width, 7);
  ASSERT_EQ(loaded.height, 5);
  ASSERT_EQ(loaded.channels, channels);
  for (size_t i = 0; i < original.pixels.size(); ++i) {
    ASSERT_NEAR(loaded.pixels[i], original.pixels[i], 1e-7) << "sample " << i;
  }
  const ImageSize size = ReadImageSize(path);
  EXPECT_EQ(size.width, 7);
  EXPECT_EQ(size.height, 5);
}

INSTANTIATE_TEST_SUITE_P(AllLayouts, PngRoundTrip,
                         ::testing::Combine(::testing::Values(1, 2, 3, 4),
                                            ::testing::Values(8, 16)));

TEST_F(ImageIoTest, SavePngQuantisesAndClamps) {
  Image image = MakeImage(3, 1, 1);
  image.pixels = {-0.5f, 0.5f, 2.0f};
  SavePng(Path("clamp.png"), image);
  const Image loaded = LoadImage(Path("clamp.png"));
  EXPECT_EQ(loaded.pixels[0], 0.0f);
  EXPECT_NEAR(loaded.pixels[1], 128.0f / 255.0f, 1e-7);  // 127.5 rounds up
  EXPECT_EQ(loaded.pixels[2], 1.0f);
}

TEST_F(ImageIoTest, PalettePngWithTransparencyExpandsToRgba) {
  // libpng directly, since SavePng never writes palettes.
  const std::string path = Path("palette.png");
  FILE* file = std::fopen(path.c_str(), "wb");
  ASSERT_NE(file, nullptr);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  png_init_io(png, file);
  png_set_IHDR(png, info, 2, 1, 8, PNG_COLOR_TYPE_PALETTE, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_color palette[2] = {{255, 0, 0}, {0, 0, 255}};
  png_set_PLTE(png, info, palette, 2);
  png_byte alpha[1] = {0};  // entry 0 transparent
  png_set_tRNS(png, info, alpha, 1, nullptr);
  png_write_info(png, info);
  png_byte row[2] = {0, 1};
  png_write_row(png, row);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(file);

  const Image image = LoadImage(path);
  ASSERT_EQ(image.channels, 4);
  ASSERT_EQ(image.width, 2);
  EXPECT_EQ(image.at(0, 0, 0), 1.0f);
  EXPECT_EQ(image.at(0, 0, 3), 0.0f);
  EXPECT_EQ(image.at(1, 0, 2), 1.0f);
  EXPECT_EQ(image.at(1, 0, 3), 1.0f);
}

TEST_F(ImageIoTest, DecodesJpegColours) {
  const std::string path = Path("quadrants.jpg");
  WriteQuadrantJpeg(path);
  const Image image = LoadImage(path);
  ASSERT_EQ(image.width, 32);
  ASSERT_EQ(image.height, 32);
  ASSERT_EQ(image.channels, 3);
  const float expected[4][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  const int centres[4][2] = {{8, 8}, {24, 8}, {8, 24}, {24, 24}};
  for (int q = 0; q < 4; ++q) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(image.at(centres[q][0], centres[q][1], c), expected[q][c], 0.04)
          << "quadrant " << q;
    }
  }
  const ImageSize size = ReadImageSize(path);
  EXPECT_EQ(size.width, 32);
  EXPECT_EQ(size.height, 32);
}

// A CMYK JPEG (print workflows) is a valid file this loader does not read: said so, not
// "corrupt".
TEST_F(ImageIoTest, CmykJpegIsUnsupportedNotCorrupt) {
  WriteJpeg(Path("cmyk.jpg"), 8, 8, 4, std::vector<uint8_t>(8 * 8 * 4, 128));
  const std::string error = ErrorOf([&] { LoadImage(Path("cmyk.jpg")); });
  EXPECT_NE(error.find("unsupported JPEG: CMYK"), std::string::npos) << error;
  EXPECT_EQ(error.find("corrupt"), std::string::npos) << error;
}

TEST_F(ImageIoTest, DetectsFormatByContentNotExtension) {
  WriteQuadrantJpeg(Path("actually_jpeg.png"));
  EXPECT_EQ(LoadImage(Path("actually_jpeg.png")).channels, 3);
  SavePng(Path("actually_png.jpg"), Ramp(4, 4, 2, 255));
  EXPECT_EQ(LoadImage(Path("actually_png.jpg")).channels, 2);
}

TEST_F(ImageIoTest, DecodesGrayJpeg) {
  std::vector<uint8_t> gray(16 * 16, 128);
  WriteJpeg(Path("gray.jpg"), 16, 16, 1, gray);
  const Image image = LoadImage(Path("gray.jpg"));
  ASSERT_EQ(image.channels, 1);
  EXPECT_NEAR(image.at(8, 8, 0), 128.0f / 255.0f, 0.01);
}

TEST_F(ImageIoTest, MissingFileNamesPath) {
  const std::string path = Path("nope.png");
  const std::string error = ErrorOf([&] { LoadImage(path); });
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("cannot open"), std::string::npos) << error;
  EXPECT_NE(ErrorOf([&] { ReadImageSize(path); }).find(path), std::string::npos);
}

TEST_F(ImageIoTest, NonImageNamesPath) {
  const std::string path = Path("notes.png");
  WriteAll(path, {'h', 'e', 'l', 'l', 'o', '\n'});
  const std::string error = ErrorOf([&] { LoadImage(path); });
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("not a PNG or JPEG"), std::string::npos) << error;
  WriteAll(Path("empty.png"), {});
  EXPECT_NE(ErrorOf([&] { LoadImage(Path("empty.png")); }).find("empty file"), std::string::npos);
}

// A small file whose header claims a huge image is refused from the header, before decoding
// allocates anything (a 1 MB PNG of 16384^2 pixels used to cost 7 GiB while loading).
TEST_F(ImageIoTest, HugeImagesAreRefusedFromTheHeader) {
  const std::string path = Path("huge.png");
  SavePng(path, Ramp(64, 64, 3, 255));
  std::vector<uint8_t> bytes = ReadAll(path);
  for (size_t at : {size_t(16), size_t(20)}) {  // IHDR width and height, big-endian
    bytes[at] = 0;
    bytes[at + 1] = 0;
    bytes[at + 2] = 0x40;  // 16384
    bytes[at + 3] = 0;
  }
  WriteAll(path, bytes);
  const std::string error = ErrorOf([&] { LoadImage(path); });
  EXPECT_NE(error.find(path + ": image is 16384x16384 = 268435456 pixels; ecrf loads at most "
                              "67108864 pixels per image"),
            std::string::npos)
      << error;
}

TEST_F(ImageIoTest, TruncatedPngIsAnError) {
  const std::string path = Path("cut.png");
  SavePng(path, Ramp(64, 64, 3, 255));
  std::vector<uint8_t> bytes = ReadAll(path);
  // Cut inside the data, and separately drop only the final IEND chunk.
  for (size_t keep : {bytes.size() / 2, bytes.size() - 12}) {
    WriteAll(path, std::vector<uint8_t>(bytes.begin(), bytes.begin() + keep));
    const std::string error = ErrorOf([&] { LoadImage(path); });
    EXPECT_NE(error.find(path), std::string::npos) << error;
    EXPECT_NE(error.find("truncated"), std::string::npos) << error;
  }
}

TEST_F(ImageIoTest, CorruptPngIsAnError) {
  const std::string path = Path("corrupt.png");
  SavePng(path, Ramp(64, 64, 3, 255));
  std::vector<uint8_t> bytes = ReadAll(path);
  for (size_t i = 60; i < 80; ++i) bytes[i] ^= 0x5a;  // inside IDAT: checksum mismatch
  WriteAll(path, bytes);
  const std::string error = ErrorOf([&] { LoadImage(path); });
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("PNG"), std::string::npos) << error;
}

TEST_F(ImageIoTest, TruncatedJpegIsAnError) {
  const std::string path = Path("cut.jpg");
  WriteQuadrantJpeg(path);
  std::vector<uint8_t> bytes = ReadAll(path);
  WriteAll(path, std::vector<uint8_t>(bytes.begin(), bytes.begin() + bytes.size() * 2 / 3));
  const std::string error = ErrorOf([&] { LoadImage(path); });
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("JPEG"), std::string::npos) << error;
}

TEST_F(ImageIoTest, SavePngReplacesAtomicallyAndLeavesNoTemporaries) {
  const std::string path = Path("out.png");
  SavePng(path, Ramp(4, 4, 3, 255));
  SavePng(path, MakeImage(2, 3, 1, 1.0f));
  const Image loaded = LoadImage(path);
  EXPECT_EQ(loaded.width, 2);
  EXPECT_EQ(loaded.channels, 1);
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    ++files;
    EXPECT_EQ(entry.path().filename(), "out.png");
  }
  EXPECT_EQ(files, 1);
}

TEST_F(ImageIoTest, SavePngReportsBadInput) {
  const std::string missing_dir = Path("no/such/dir/out.png");
  EXPECT_NE(ErrorOf([&] { SavePng(missing_dir, Ramp(2, 2, 3, 255)); }).find(missing_dir),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { SavePng(Path("a.png"), MakeImage(2, 2, 5)); }).find("5 channels"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { SavePng(Path("a.png"), MakeImage(2, 2, 3), 12); }).find("bit depth"),
            std::string::npos);
}

TEST(CompositeOnWhite, BlendsStraightAlpha) {
  Image rgba = MakeImage(2, 1, 4);
  rgba.pixels = {1.0f, 0.0f, 0.0f, 0.5f, 0.2f, 0.4f, 0.6f, 0.0f};
  const Image rgb = CompositeOnWhite(rgba);
  ASSERT_EQ(rgb.channels, 3);
  EXPECT_FLOAT_EQ(rgb.at(0, 0, 0), 1.0f);
  EXPECT_FLOAT_EQ(rgb.at(0, 0, 1), 0.5f);
  EXPECT_FLOAT_EQ(rgb.at(0, 0, 2), 0.5f);
  for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(rgb.at(1, 0, c), 1.0f);  // fully transparent -> white
}

TEST(CompositeOnWhite, ReplicatesGrayAndKeepsOpaqueRgb) {
  Image gray_alpha = MakeImage(1, 1, 2);
  gray_alpha.pixels = {0.0f, 0.25f};
  const Image from_gray = CompositeOnWhite(gray_alpha);
  for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(from_gray.at(0, 0, c), 0.75f);
  Image rgb = MakeImage(1, 1, 3);
  rgb.pixels = {0.1f, 0.2f, 0.3f};
  EXPECT_EQ(CompositeOnWhite(rgb).pixels, rgb.pixels);
}

TEST(DownscaleArea, AveragesBlocksAndDropsRemainder) {
  Image image = MakeImage(5, 3, 1);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 5; ++x) image.at(x, y, 0) = static_cast<float>(y * 5 + x);
  }
  const Image half = DownscaleArea(image, 2);
  ASSERT_EQ(half.width, 2);
  ASSERT_EQ(half.height, 1);
  EXPECT_FLOAT_EQ(half.at(0, 0, 0), (0 + 1 + 5 + 6) / 4.0f);
  EXPECT_FLOAT_EQ(half.at(1, 0, 0), (2 + 3 + 7 + 8) / 4.0f);
  EXPECT_EQ(DownscaleArea(image, 1).pixels, image.pixels);
  EXPECT_THROW(DownscaleArea(image, 0), std::runtime_error);
}

TEST(DownscaleArea, KeepsChannelsSeparate) {
  Image image = MakeImage(2, 2, 3);
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 2; ++x) {
      image.at(x, y, 0) = 1.0f;
      image.at(x, y, 2) = static_cast<float>(x);
    }
  }
  const Image small = DownscaleArea(image, 2);
  ASSERT_EQ(small.channels, 3);
  EXPECT_FLOAT_EQ(small.at(0, 0, 0), 1.0f);
  EXPECT_FLOAT_EQ(small.at(0, 0, 1), 0.0f);
  EXPECT_FLOAT_EQ(small.at(0, 0, 2), 0.5f);
}

}  // namespace
}  // namespace ecrf::trainer
