// The integer inverse DCT against the float64 orthonormal inverse: error bounds per block shape,
// worst-case magnitudes, exact zero handling, and the normative tables.
#include "format/coefficients/int_idct.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "format/coefficients/block_shape.h"
#include "format/coefficients/float_dct.h"

namespace ecrf {
namespace {

struct ErrorStats {
  double max_error = 0.0;
  double sum_error = 0.0;
  long count = 0;
};

// |integer output - float64 IDCT * 2^P| for one block, in output units.
void Accumulate(const std::vector<int32_t>& q, const int dims[3], int bits, ErrorStats* stats) {
  const int volume = BlockVolume(dims);
  std::vector<double> ref(q.begin(), q.end());
  InverseDct(ref.data(), dims);
  std::vector<int32_t> out(volume);
  InverseDctInt(q.data(), dims, bits, out.data());
  const double scale = std::ldexp(1.0, IdctOutputFracBits(bits));
  for (int i = 0; i < volume; ++i) {
    const double e = std::fabs(out[i] - ref[i] * scale);
    stats->max_error = std::max(stats->max_error, e);
    stats->sum_error += e;
  }
  stats->count += volume;
}

std::vector<std::array<int, 3>> AllShapes() {
  std::vector<std::array<int, 3>> shapes;
  const int lengths[] = {1, 2, 4, 8, 16, 32};
  for (int a : lengths)
    for (int b : lengths)
      for (int c : lengths) {
        const int d[3] = {a, b, c};
        if (IsValidBlockShape(d)) shapes.push_back({a, b, c});
      }
  return shapes;
}

TEST(IntIdct, TablesMatchTheirDefinition) {
  for (int n = 2; n <= 32; n *= 2) {
    const int32_t* t = IdctCosineTable(n);
    ASSERT_NE(t, nullptr);
    for (int j = 0; j <= n; ++j) {
      const double v = std::ldexp(std::sqrt(2.0 / n) * std::cos(M_PI * j / (2.0 * n)), 26);
      EXPECT_EQ(t[j], int32_t(std::floor(v + 0.5))) << "N=" << n << " j=" << j;
    }
    // The DC row reuses K_N[N/2] = round(2^26 sqrt(1/N)).
    EXPECT_EQ(IdctMatrixEntry(n, 0, 0),
              int32_t(std::floor(std::ldexp(std::sqrt(1.0 / n), 26) + 0.5)));
    // Every entry matches the rounded real matrix.
    const double* m = DctMatrix(n);
    for (int k = 0; k < n; ++k)
      for (int i = 0; i < n; ++i)
        EXPECT_NEAR(IdctMatrixEntry(n, k, i), std::ldexp(m[k * n + i], 26), 0.5 + 1e-6);
  }
  EXPECT_EQ(IdctCosineTable(3), nullptr);
}

class IntIdctShapes : public ::testing::TestWithParam<int> {};

TEST_P(IntIdctShapes, RandomBlocksWithinOneUnitOfFloat64) {
  const int bits = GetParam();
  const int max_q = bits == 8 ? 127 : 32767;
  std::mt19937 rng(1234 + bits);
  for (const auto& s : AllShapes()) {
    const int dims[3] = {s[0], s[1], s[2]};
    const int volume = BlockVolume(dims);
    ErrorStats uniform, laplacian;
    const int trials = volume >= 1024 ? 6 : 24;
    for (int t = 0; t < trials; ++t) {
      std::vector<int32_t> q(volume);
      std::uniform_int_distribution<int> u(-max_q, max_q);
      for (auto& v : q) v = u(rng);
      Accumulate(q, dims, bits, &uniform);
      // Laplacian coefficients whose scale decays with frequency: the realistic case.
      for (int i0 = 0; i0 < dims[0]; ++i0)
        for (int i1 = 0; i1 < dims[1]; ++i1)
          for (int i2 = 0; i2 < dims[2]; ++i2) {
            const double scale = max_q / 4.0 / (1.0 + i0 + i1 + i2);
            std::exponential_distribution<double> e(1.0 / scale);
            const double mag = std::min(double(max_q), std::floor(e(rng)));
            q[(i0 * dims[1] + i1) * dims[2] + i2] = int32_t((rng() & 1) ? mag : -mag);
          }
      Accumulate(q, dims, bits, &laplacian);
    }
    EXPECT_LE(uniform.max_error, 1.0) << s[0] << "x" << s[1] << "x" << s[2];
    EXPECT_LE(laplacian.max_error, 1.0) << s[0] << "x" << s[1] << "x" << s[2];
    if (::testing::Test::HasFailure() || (s[0] == 16 && s[1] == 16 && s[2] == 16) ||
        (s[0] == 1 && s[1] == 8 && s[2] == 8) || (s[0] == 1 && s[1] == 32 && s[2] == 32)) {
      std::printf(
          "  %d-bit %2dx%2dx%2d: uniform max %.3f mean %.4f, laplacian max %.3f mean %.4f\n", bits,
          s[0], s[1], s[2], uniform.max_error, uniform.sum_error / uniform.count,
          laplacian.max_error, laplacian.sum_error / laplacian.count);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(BitDepths, IntIdctShapes, ::testing::Values(8, 16));

TEST(IntIdct, WorstCaseInputsStayExactAndInRange) {
  for (int bits : {8, 16}) {
    const int max_q = bits == 8 ? 127 : 32767;
    for (const auto& s : AllShapes()) {
      const int dims[3] = {s[0], s[1], s[2]};
      const int volume = BlockVolume(dims);
      std::vector<std::vector<int32_t>> cases;
      cases.push_back(std::vector<int32_t>(volume, max_q));
      cases.push_back(std::vector<int32_t>(volume, -max_q));
      std::vector<int32_t> alt(volume), dc(volume, 0), high(volume, 0);
      for (int i = 0; i < volume; ++i) alt[i] = (i % 2) ? -max_q : max_q;
      dc[0] = max_q;
      high[volume - 1] = -max_q;
      cases.push_back(alt);
      cases.push_back(dc);
      cases.push_back(high);
      // Signs matched to the basis of sample 0 maximise that sample: the largest possible output.
      std::vector<int32_t> peak(volume);
      for (int i0 = 0; i0 < dims[0]; ++i0)
        for (int i1 = 0; i1 < dims[1]; ++i1)
          for (int i2 = 0; i2 < dims[2]; ++i2) {
            auto sign = [](int n, int k) {
              return n == 1 || IdctMatrixEntry(n, k, 0) >= 0 ? 1 : -1;
            };
            peak[(i0 * dims[1] + i1) * dims[2] + i2] =
                max_q * sign(dims[0], i0) * sign(dims[1], i1) * sign(dims[2], i2);
          }
      cases.push_back(peak);
      for (const auto& q : cases) {
        ErrorStats st;
        Accumulate(q, dims, bits, &st);
        // Worst cases are held to the same bound: nothing clipped or overflowed on the way.
        EXPECT_LE(st.max_error, 1.0) << bits << "-bit " << s[0] << "x" << s[1] << "x" << s[2];
      }
    }
  }
}

TEST(IntIdct, AllZeroBlockGivesZeros) {
  const int dims[3] = {16, 16, 16};
  std::vector<int32_t> q(4096, 0), out(4096, 77);
  InverseDctInt(q.data(), dims, 8, out.data());
  for (int v : out) ASSERT_EQ(v, 0);
}

TEST(IntIdct, SingleCoefficientBlockIsScaledIdentity) {
  const int dims[3] = {1, 1, 1};
  int32_t q = -100, out = 0;
  InverseDctInt(&q, dims, 8, &out);
  EXPECT_EQ(out, -100 * 256);
  InverseDctInt(&q, dims, 16, &out);
  EXPECT_EQ(out, -100 * 16);
}

TEST(IntIdct, DcOnlyBlockIsFlat) {
  // A DC-only block must decode to a constant: the same integer at every position.
  const int dims[3] = {16, 16, 16};
  std::vector<int32_t> q(4096, 0), out(4096);
  q[0] = 64;  // value 64 / sqrt(4096) = 1 step everywhere
  InverseDctInt(q.data(), dims, 8, out.data());
  for (int v : out) ASSERT_EQ(v, out[0]);
  EXPECT_EQ(out[0], 256);
}

TEST(IntIdct, ForwardThenIntegerInverseRecoversQuantizedSignal) {
  // Quantize the float DCT of a smooth signal; the integer inverse must land within half a step
  // plus the quantization error bound of the original samples.
  std::mt19937 rng(7);
  const int dims[3] = {4, 8, 8};
  std::vector<double> x(256);
  for (int i = 0; i < 256; ++i)
    x[i] = 20.0 * std::sin(0.1 * i) + std::normal_distribution<>(0, 2)(rng);
  std::vector<double> c = x;
  ForwardDct(c.data(), dims);
  std::vector<int32_t> q(256);
  for (int i = 0; i < 256; ++i) q[i] = int32_t(std::lround(c[i]));
  std::vector<int32_t> out(256);
  InverseDctInt(q.data(), dims, 8, out.data());
  // Orthonormal: the L2 reconstruction error equals the L2 quantization error (<= sqrt(N)/2).
  double err2 = 0;
  for (int i = 0; i < 256; ++i) {
    const double d = out[i] / 256.0 - x[i];
    err2 += d * d;
  }
  EXPECT_LE(std::sqrt(err2), std::sqrt(256.0) * 0.5 + 0.05);
}

}  // namespace
}  // namespace ecrf
