// Reading numpy .npy arrays of floats (as LLFF's poses_bounds.npy), without numpy.
#ifndef ECRF_TRAINER_DATA_NPY_H_
#define ECRF_TRAINER_DATA_NPY_H_

#include <cstdint>
#include <string>
#include <vector>

namespace ecrf::trainer {

struct NpyMatrix {
  int64_t rows = 0, cols = 0;
  std::vector<double> values;  // row-major, rows * cols

  double at(int64_t r, int64_t c) const { return values[size_t(r * cols + c)]; }
};

// A 2-D array of little-endian float64 ('<f8', as np.save writes on every common machine) or
// float32 ('<f4'), C order, from a .npy file of format version 1, 2 or 3.
// Throws std::runtime_error naming the file and what is wrong: not a .npy file, an unsupported
// version, dtype, order or shape, a malformed header, or fewer bytes than the shape needs.
NpyMatrix ReadNpyMatrix(const std::string& path);

// Parses the bytes of a .npy file; `name` is used in error messages.
NpyMatrix ParseNpyMatrix(const std::string& name, const std::vector<uint8_t>& bytes);

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_DATA_NPY_H_
