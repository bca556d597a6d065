#include "trainer/data/exif_orientation.h"

#include <libexif/exif-data.h>

#include <cstring>

namespace ecrf::trainer {

int ExifOrientation(const uint8_t* app1, size_t size) {
  static const uint8_t kExifHeader[6] = {'E', 'x', 'i', 'f', 0, 0};
  if (app1 == nullptr || size < sizeof kExifHeader ||
      std::memcmp(app1, kExifHeader, sizeof kExifHeader) != 0) {
    return 1;  // an XMP or other APP1 segment
  }
  ExifData* data = exif_data_new_from_data(app1, static_cast<unsigned int>(size));
  if (data == nullptr) return 1;
  int orientation = 1;
  if (ExifEntry* e = exif_data_get_entry(data, EXIF_TAG_ORIENTATION);
      e != nullptr && e->format == EXIF_FORMAT_SHORT && e->components >= 1 && e->size >= 2) {
    const int v = exif_get_short(e->data, exif_data_get_byte_order(data));
    if (v >= 1 && v <= 8) orientation = v;
  }
  exif_data_unref(data);
  return orientation;
}

void ApplyOrientation(int orientation, int channels, int* width, int* height,
                      std::vector<uint8_t>* pixels) {
  if (orientation < 2 || orientation > 8) return;
  const int w = *width, h = *height;
  const bool swap = OrientationSwapsAxes(orientation);
  const int out_w = swap ? h : w, out_h = swap ? w : h;
  std::vector<uint8_t> out(pixels->size());
  for (int y = 0; y < out_h; ++y) {
    for (int x = 0; x < out_w; ++x) {
      int sx = x, sy = y;  // the stored pixel shown at (x, y)
      switch (orientation) {
        case 2:
          sx = w - 1 - x;
          break;
        case 3:
          sx = w - 1 - x;
          sy = h - 1 - y;
          break;
        case 4:
          sy = h - 1 - y;
          break;
        case 5:
          sx = y;
          sy = x;
          break;
        case 6:
          sx = y;
          sy = h - 1 - x;
          break;
        case 7:
          sx = w - 1 - y;
          sy = h - 1 - x;
          break;
        case 8:
          sx = w - 1 - y;
          sy = x;
          break;
      }
      std::memcpy(&out[(static_cast<size_t>(y) * out_w + x) * channels],
                  &(*pixels)[(static_cast<size_t>(sy) * w + sx) * channels], channels);
    }
  }
  pixels->swap(out);
  *width = out_w;
  *height = out_h;
}

}  // namespace ecrf::trainer
