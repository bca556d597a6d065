#include "trainer/model/small_gemm.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#if defined(__unix__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace ecrf {
namespace trainer {
namespace {

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
constexpr float kSentinel = -777.25f;
constexpr int kPad = 80;  // guard floats on each side of every buffer, more than one zmm

struct Case {
  int M, N, K;
  std::ptrdiff_t a_row, a_col, ldb, ldc;
  bool accumulate;
  std::string Describe() const {
    return "M=" + std::to_string(M) + " N=" + std::to_string(N) + " K=" + std::to_string(K) +
           " a_row=" + std::to_string(a_row) + " a_col=" + std::to_string(a_col) +
           " ldb=" + std::to_string(ldb) + " ldc=" + std::to_string(ldc) +
           (accumulate ? " acc" : " overwrite");
  }
};

// Row-major A with leading dimension lda, or its transpose stored K x M with leading dimension lda.
Case RowA(int M, int N, int K, std::ptrdiff_t lda, std::ptrdiff_t ldb, std::ptrdiff_t ldc,
          bool acc) {
  return {M, N, K, lda, 1, ldb, ldc, acc};
}
Case TransA(int M, int N, int K, std::ptrdiff_t lda, std::ptrdiff_t ldb, std::ptrdiff_t ldc,
            bool acc) {
  return {M, N, K, 1, lda, ldb, ldc, acc};
}

// Operands surrounded by guards: every float of A and B that is not an operand is NaN (so reading
// one poisons the result), every float of C's buffer outside the M x N block is a sentinel that
// must survive, and without accumulate the block itself starts as NaN (so reading it poisons too).
struct Buffers {
  std::vector<float> a, b, c;
  std::ptrdiff_t a_span = 0, b_span = 0, c_span = 0;

  Buffers(const Case& t, std::mt19937* rng) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    if (t.M > 0 && t.K > 0) a_span = (t.M - 1) * t.a_row + (t.K - 1) * t.a_col + 1;
    if (t.K > 0 && t.N > 0) b_span = (t.K - 1) * t.ldb + t.N;
    if (t.M > 0 && t.N > 0) c_span = (t.M - 1) * t.ldc + t.N;
    a.assign(a_span + 2 * kPad, kNan);
    b.assign(b_span + 2 * kPad, kNan);
    c.assign(c_span + 2 * kPad, kSentinel);
    for (int i = 0; i < t.M; ++i) {
      for (int p = 0; p < t.K; ++p) A(t, i, p) = u(*rng);
    }
    for (int p = 0; p < t.K; ++p) {
      for (int j = 0; j < t.N; ++j) B(t, p, j) = u(*rng);
    }
    for (int i = 0; i < t.M; ++i) {
      for (int j = 0; j < t.N; ++j) C(t, i, j) = t.accumulate ? u(*rng) : kNan;
    }
  }
  float& A(const Case& t, int i, int p) { return a[kPad + i * t.a_row + p * t.a_col]; }
  float& B(const Case& t, int p, int j) { return b[kPad + p * t.ldb + j]; }
  float& C(const Case& t, int i, int j) { return c[kPad + i * t.ldc + j]; }
  void Run(const Case& t) {
    SmallGemm(t.M, t.N, t.K, a.data() + kPad, t.a_row, t.a_col, b.data() + kPad, t.ldb,
              c.data() + kPad, t.ldc, t.accumulate);
  }
};

// Checks one case against a double-precision reference and the guards; returns false (after
// reporting) on the first mismatch so a broken kernel does not flood the log.
bool CheckCase(const Case& t, std::mt19937* rng) {
  SCOPED_TRACE(t.Describe());
  Buffers buf(t, rng);
  const std::vector<float> c0 = buf.c;
  buf.Run(t);
  for (std::ptrdiff_t k = 0; k < static_cast<std::ptrdiff_t>(buf.c.size()); ++k) {
    const std::ptrdiff_t rel = k - kPad;
    const bool in_block = rel >= 0 && rel < buf.c_span && rel % t.ldc < t.N;
    if (in_block) continue;
    if (std::memcmp(&buf.c[k], &c0[k], sizeof(float)) != 0) {
      ADD_FAILURE() << "C guard at offset " << rel << " overwritten with " << buf.c[k];
      return false;
    }
  }
  for (int i = 0; i < t.M; ++i) {
    for (int j = 0; j < t.N; ++j) {
      const float init = c0[kPad + i * t.ldc + j];
      double ref = t.accumulate ? init : 0.0;
      double scale = t.accumulate ? std::fabs(init) : 0.0;
      for (int p = 0; p < t.K; ++p) {
        const double prod = static_cast<double>(buf.A(t, i, p)) * buf.B(t, p, j);
        ref += prod;
        scale += std::fabs(prod);
      }
      const float got = buf.C(t, i, j);
      // Summing K + 1 float terms errs by at most about (K + 1) * eps / 2 * sum |term| (plus one
      // rounding per product without FMA); allow four times that.
      const double tol = 2.0 * (t.K + 2) * std::numeric_limits<float>::epsilon() * scale + 1e-30;
      if (!std::isfinite(got) || std::fabs(got - ref) > tol) {
        ADD_FAILURE() << "C(" << i << "," << j << ") = " << got << ", want " << ref << " +- "
                      << tol;
        return false;
      }
    }
  }
  return true;
}

TEST(SmallGemm, ReportsCompiledIsa) {
  const std::string isa = SmallGemmIsa();
  EXPECT_TRUE(isa == "avx512" || isa == "avx2" || isa == "portable") << isa;
#if defined(__AVX512F__)
  EXPECT_EQ(isa, "avx512");
#endif
}

TEST(SmallGemm, MatchesReferenceOnMlpShapes) {
  std::mt19937 rng(7);
  const std::vector<Case> cases = {
      RowA(256, 128, 150, 150, 128, 128, false),   // forward layer 1
      RowA(256, 128, 150, 160, 128, 128, false),   // ... lda > K
      RowA(256, 128, 128, 128, 128, 128, false),   // forward layer 2, backward dX
      RowA(256, 27, 144, 144, 27, 150, false),     // basis into a strided sub-block of C
      RowA(256, 3, 128, 128, 3, 3, false),         // last layer
      TransA(128, 128, 256, 128, 128, 128, true),  // weight gradients
      TransA(128, 150, 256, 128, 150, 150, true),
      RowA(256, 150, 128, 128, 150, 150, false),  // dX = dB * W1
      RowA(256, 138, 128, 128, 150, 150, false),
      TransA(27, 144, 256, 27, 144, 144, true),  // basis gradient
      RowA(256, 144, 27, 27, 144, 144, false),   // dproducts
      TransA(3, 128, 256, 3, 128, 128, true),    // last-layer gradient
      RowA(256, 128, 3, 3, 128, 128, false),
  };
  for (const Case& base : cases) {
    for (int chunk : {256, 37, 1}) {  // full chunk, a ragged tail chunk, a single row
      for (bool acc : {false, true}) {
        Case t = base;
        t.accumulate = acc;
        // The chunk's rows are M of a forward-style product and K of a weight gradient.
        (t.a_col == 1 ? t.M : t.K) = chunk;
        if (!CheckCase(t, &rng)) return;
      }
    }
  }
}

TEST(SmallGemm, MatchesReferenceOnRandomSmallShapes) {
  std::mt19937 rng(11);
  const int sizes[] = {0,  1,  2,  3,  4,  5,  7,  8,  9,  15, 16, 17,
                       23, 31, 32, 33, 47, 48, 49, 63, 64, 65, 70};
  const int nsizes = sizeof(sizes) / sizeof(sizes[0]);
  std::uniform_int_distribution<int> pick(0, nsizes - 1), extra(0, 5), coin(0, 1);
  for (int iter = 0; iter < 600; ++iter) {
    const int M = sizes[pick(rng)], N = sizes[pick(rng)], K = sizes[pick(rng)];
    const std::ptrdiff_t ldb = N + extra(rng) * coin(rng), ldc = N + extra(rng) * coin(rng);
    const bool acc = coin(rng);
    Case t;
    switch (iter % 3) {
      case 0:
        t = RowA(M, N, K, K + extra(rng), ldb, ldc, acc);
        break;
      case 1:
        t = TransA(M, N, K, M + extra(rng), ldb, ldc, acc);
        break;
      default:
        t = {M, N, K, 2 * (K + 1), 2, ldb, ldc, acc};  // neither stride unit: packed path
    }
    if (!CheckCase(t, &rng)) return;
  }
}

TEST(SmallGemm, LongKIsSplitIntoBlocks) {
  std::mt19937 rng(3);
  for (bool acc : {false, true}) {
    ASSERT_TRUE(CheckCase(RowA(61, 150, 700, 700, 150, 150, acc), &rng));
    ASSERT_TRUE(CheckCase(TransA(50, 144, 600, 50, 144, 160, acc), &rng));
    ASSERT_TRUE(CheckCase({40, 33, 530, 1, 3 * 40 + 1, 33, 40, acc}, &rng));  // transposed
    ASSERT_TRUE(CheckCase({29, 70, 300, 2 * 301, 2, 70, 70, acc}, &rng));     // packed A
    ASSERT_TRUE(CheckCase({29, 600, 40, 40, 1, 600, 600, acc}, &rng));        // wide N
  }
}

TEST(SmallGemm, OverwriteIgnoresNanInC) {
  // CheckCase already starts C as NaN without accumulate; this pins it on the main shape alone.
  std::mt19937 rng(5);
  Case t = RowA(256, 128, 150, 150, 128, 128, false);
  Buffers buf(t, &rng);
  buf.Run(t);
  for (int i = 0; i < t.M; ++i) {
    for (int j = 0; j < t.N; ++j) ASSERT_TRUE(std::isfinite(buf.C(t, i, j))) << i << "," << j;
  }
}

TEST(SmallGemm, EmptyDimensions) {
  std::mt19937 rng(9);
  // K = 0: overwrite zeroes the block, accumulate leaves it; M or N = 0 touches nothing.
  for (bool acc : {false, true}) {
    ASSERT_TRUE(CheckCase(RowA(5, 19, 0, 1, 19, 21, acc), &rng));
    ASSERT_TRUE(CheckCase(RowA(0, 19, 4, 4, 19, 19, acc), &rng));
    ASSERT_TRUE(CheckCase(RowA(5, 0, 4, 4, 1, 1, acc), &rng));
  }
  Case t = RowA(3, 17, 0, 1, 17, 20, false);
  Buffers buf(t, &rng);
  buf.Run(t);
  for (int i = 0; i < t.M; ++i) {
    for (int j = 0; j < t.N; ++j) EXPECT_EQ(buf.C(t, i, j), 0.0f);
  }
}

TEST(SmallGemm, BitwiseRepeatableAndIndependentOfAlignment) {
  std::mt19937 rng(13);
  for (const Case& t :
       {RowA(256, 150, 128, 128, 150, 150, false), TransA(128, 150, 256, 128, 150, 150, true),
        RowA(37, 27, 144, 150, 27, 150, true)}) {
    SCOPED_TRACE(t.Describe());
    Buffers buf(t, &rng);
    const std::vector<float> c0 = buf.c;
    buf.Run(t);
    const std::vector<float> first = buf.c;
    buf.c = c0;
    buf.Run(t);
    ASSERT_EQ(std::memcmp(first.data(), buf.c.data(), first.size() * sizeof(float)), 0);
    // The same operands one float further into their buffers (a different alignment).
    std::vector<float> a(buf.a.size() + 1), b(buf.b.size() + 1), c(c0.size() + 1);
    std::copy(buf.a.begin(), buf.a.end(), a.begin() + 1);
    std::copy(buf.b.begin(), buf.b.end(), b.begin() + 1);
    std::copy(c0.begin(), c0.end(), c.begin() + 1);
    SmallGemm(t.M, t.N, t.K, a.data() + 1 + kPad, t.a_row, t.a_col, b.data() + 1 + kPad, t.ldb,
              c.data() + 1 + kPad, t.ldc, t.accumulate);
    ASSERT_EQ(std::memcmp(first.data(), c.data() + 1, first.size() * sizeof(float)), 0);
  }
}

#if defined(__unix__)
// n floats ending exactly where an inaccessible page begins, so that reading or writing even one
// float past the end faults. Needed because an over-read of B's or C's last row past column N-1
// only feeds lanes the kernel then masks off: no value check can see it.
class FloatsBeforeGuardPage {
 public:
  explicit FloatsBeforeGuardPage(size_t n) {
    const size_t page = static_cast<size_t>(sysconf(_SC_PAGESIZE));
    data_bytes_ = (n * sizeof(float) + page - 1) / page * page;
    size_ = data_bytes_ + page;
    void* m = mmap(nullptr, size_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (m == MAP_FAILED) return;
    base_ = static_cast<char*>(m);
    if (mprotect(base_ + data_bytes_, page, PROT_NONE) != 0) return;
    floats_ = reinterpret_cast<float*>(base_ + data_bytes_) - n;
  }
  ~FloatsBeforeGuardPage() {
    if (base_ != nullptr) munmap(base_, size_);
  }
  float* get() const { return floats_; }

 private:
  char* base_ = nullptr;
  size_t size_ = 0, data_bytes_ = 0;
  float* floats_ = nullptr;
};

TEST(SmallGemm, NeverTouchesMemoryPastOperandEnds) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int n : {1, 3, 15, 17, 27, 138, 150}) {
    for (bool trans : {false, true}) {
      for (bool acc : {false, true}) {
        const int m = 37, k = 29;
        SCOPED_TRACE("N=" + std::to_string(n) + (trans ? " trans" : "") + (acc ? " acc" : ""));
        FloatsBeforeGuardPage a(m * k), b(k * n), c(m * n);
        ASSERT_NE(a.get(), nullptr);
        ASSERT_NE(b.get(), nullptr);
        ASSERT_NE(c.get(), nullptr);
        for (int i = 0; i < m * k; ++i) a.get()[i] = u(rng);
        for (int i = 0; i < k * n; ++i) b.get()[i] = u(rng);
        for (int i = 0; i < m * n; ++i) c.get()[i] = acc ? u(rng) : kNan;
        const std::vector<float> c0(c.get(), c.get() + m * n);
        SmallGemm(m, n, k, a.get(), trans ? 1 : k, trans ? m : 1, b.get(), n, c.get(), n, acc);
        for (int i = 0; i < m; ++i) {
          for (int j = 0; j < n; ++j) {
            double ref = acc ? c0[i * n + j] : 0.0;
            for (int p = 0; p < k; ++p) {
              ref +=
                  static_cast<double>(a.get()[trans ? p * m + i : i * k + p]) * b.get()[p * n + j];
            }
            ASSERT_NEAR(c.get()[i * n + j], ref, 1e-4) << i << "," << j;
          }
        }
      }
    }
  }
}
#endif

}  // namespace
}  // namespace trainer
}  // namespace ecrf
