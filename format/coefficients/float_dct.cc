#include "format/coefficients/float_dct.h"

#include <cmath>

#include "format/coefficients/block_shape.h"

namespace ecrf {
namespace {

struct DctTables {
  // tables[log2(N)] holds N*N entries; N = 1 .. 32.
  double matrix[6][kMaxBlockLength * kMaxBlockLength];
  DctTables() {
    const double pi = 3.14159265358979323846;
    for (int level = 0; level < 6; ++level) {
      const int n = 1 << level;
      for (int k = 0; k < n; ++k) {
        const double a = k == 0 ? std::sqrt(1.0 / n) : std::sqrt(2.0 / n);
        for (int i = 0; i < n; ++i) {
          matrix[level][k * n + i] = a * std::cos(pi * (2 * i + 1) * k / (2.0 * n));
        }
      }
    }
  }
};

const DctTables& Tables() {
  static const DctTables tables;
  return tables;
}

int Log2(int n) {
  int l = 0;
  while ((1 << l) < n) ++l;
  return l;
}

// One separable pass along `axis`: each line x becomes M x (forward) or M^T x (inverse).
template <typename T>
void Pass(T* data, const int dims[3], int axis, bool inverse) {
  const int n = dims[axis];
  if (n == 1) return;
  const double* m = Tables().matrix[Log2(n)];
  const int stride = axis == 2 ? 1 : axis == 1 ? dims[2] : dims[1] * dims[2];
  const int outer = axis == 0 ? 1 : dims[0];
  const int inner = axis == 2 ? dims[1] : axis == 1 ? dims[2] : dims[1] * dims[2];
  const int outer_stride = axis == 0 ? 0 : dims[1] * dims[2];
  const int inner_stride = axis == 2 ? dims[2] : 1;
  double in[kMaxBlockLength];
  for (int o = 0; o < outer; ++o) {
    for (int i = 0; i < inner; ++i) {
      T* line = data + o * outer_stride + i * inner_stride;
      for (int j = 0; j < n; ++j) in[j] = double(line[j * stride]);
      for (int k = 0; k < n; ++k) {
        double acc = 0.0;
        if (inverse) {
          for (int j = 0; j < n; ++j) acc += m[j * n + k] * in[j];
        } else {
          for (int j = 0; j < n; ++j) acc += m[k * n + j] * in[j];
        }
        line[k * stride] = T(acc);
      }
    }
  }
}

template <typename T>
void Transform(T* data, const int dims[3], bool inverse) {
  for (int axis = 2; axis >= 0; --axis) Pass(data, dims, axis, inverse);
}

}  // namespace

const double* DctMatrix(int n) { return Tables().matrix[Log2(n)]; }

void ForwardDct(double* data, const int dims[3]) { Transform(data, dims, false); }
void InverseDct(double* data, const int dims[3]) { Transform(data, dims, true); }
void ForwardDct(float* data, const int dims[3]) { Transform(data, dims, false); }
void InverseDct(float* data, const int dims[3]) { Transform(data, dims, true); }

}  // namespace ecrf
