// EXIF orientation of camera JPEGs: phones store most photos sideways (the sensor's way) and say
// in the EXIF Orientation tag how to turn them for display. Training on the stored pixels would
// train on sideways views; LoadImage turns them upright with these.
#ifndef ECRF_TRAINER_DATA_EXIF_ORIENTATION_H_
#define ECRF_TRAINER_DATA_EXIF_ORIENTATION_H_

#include <cstddef>
#include <cstdint>
#include <vector>

namespace ecrf::trainer {

// The Orientation tag (1 to 8) of a JPEG APP1 segment's payload ("Exif\0\0" and a TIFF header,
// as libjpeg's saved marker holds it), read with libexif; 1 (as stored) when the segment is not
// EXIF, has no such tag, or holds a value outside 1 to 8.
int ExifOrientation(const uint8_t* app1, size_t size);

// True for the orientations that swap width and height (5 to 8: a quarter turn).
inline bool OrientationSwapsAxes(int orientation) { return orientation >= 5 && orientation <= 8; }

// Turns interleaved 8-bit pixels (width x height x channels, rows top to bottom) from the stored
// orientation to the upright one: 2 mirror left-right, 3 turn 180 degrees, 4 mirror top-bottom,
// 5 transpose, 6 turn 90 degrees clockwise, 7 transverse, 8 turn 90 degrees anticlockwise.
// Width and height are swapped for 5 to 8. Orientation 1 (or any other value) leaves them as they
// are.
void ApplyOrientation(int orientation, int channels, int* width, int* height,
                      std::vector<uint8_t>* pixels);

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_DATA_EXIF_ORIENTATION_H_
