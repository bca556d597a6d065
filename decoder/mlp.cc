#include "decoder/mlp.h"
#include "decoder/fast_sincos.h"
#include "decoder/mlp_gemm.h"
#include "decoder/sh_basis.h"
#include "format/mlp_coder.h"

#include <cmath>
#include <cstring>

namespace ecrf {
namespace dec {
namespace {

constexpr int kPad = 8;  // output widths of the hidden layers / basis are padded to this
constexpr int kOutPad = 8;
static_assert(kPad % 8 == 0 && kOutPad % 8 == 0, "Gemm8 writes columns in runs of 8");

int RoundUp(int v, int m) { return (v + m - 1) / m * m; }

// rows (multiple of 8) x K times wt, rows contiguous with strides ldx / ldy. With skip_zeros, each
// group of 8 rows sums only over the k where one of its inputs is not zero: the hidden layers'
// inputs come out of a ReLU and are about half zeros in trained scenes. Leaving out x * w = +-0
// changes no sum's value (decoder/mlp_gemm.h), so the results are the same bits either way
// (tests/decoder/mlp_test.cc checks this against a scalar reference).
void GemmRows(Gemm8Fn gemm8, int rows, const float* x, int ldx, int K, bool skip_zeros,
              const float* wt, int ldw, const float* bias, bool relu, float* y, int ldy) {
  int ks[kMaxMlpHidden];  // skip_zeros: K is a hidden width
  for (int r = 0; r < rows; r += 8) {
    const float* xr[8];
    float* yr[8];
    for (int q = 0; q < 8; ++q) {
      xr[q] = x + static_cast<size_t>(r + q) * ldx;
      yr[q] = y + static_cast<size_t>(r + q) * ldy;
    }
    const int* use = nullptr;
    int nk = K;
    if (skip_zeros) {
      nk = NonZeroColumns8(xr, K, ks);
      use = ks;
    }
    gemm8(xr, use, nk, wt, ldw, bias, ldw, relu, yr);
  }
}

bool AllFinite(const float* p, size_t n) {
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(p[i])) return false;
  }
  return true;
}

}  // namespace

int FastSinCos(const float* x, int count, float* s, float* c) {
  using namespace fast_sincos;  // NOLINT(google-build-using-namespace)
  constexpr float kLimit = 8192.f;
  // Float-only, select-based body so the loop vectorises (no int conversions, no branches).
  for (int i = 0; i < count; ++i) {
    const float v = x[i];  // NaN / huge give garbage here and are fixed up below
    const float kf = Quadrant(v);
    const float k4 = ((kf - 1.5f) * 0.25f + kRoundingMagic) - kRoundingMagic;  // floor(kf / 4)
    const float q = kf - 4.f * k4;  // kf mod 4 in {0,1,2,3}
    const float r = Reduce(v, kf);
    const float r2 = r * r;
    const float sr = SinPolynomial(r, r2);
    const float cr = CosPolynomial(r2);
    // sin(r + q pi/2) = A sin r + B cos r, cos(r + q pi/2) = A cos r - B sin r.
    // A = cos(q pi/2), B = sin(q pi/2) as exact cubic interpolants (no compares: they would
    // keep GCC from if-converting, hence from vectorising, under -ftrapping-math).
    const float qm = q - 1.f;
    const float A = (3.f - q - 3.f * q * q + q * q * q) * (1.f / 3.f);
    const float B = (3.f - qm - 3.f * qm * qm + qm * qm * qm) * (1.f / 3.f);
    const float sv = A * sr + B * cr;
    const float cv = A * cr - B * sr;
    s[i] = sv;
    c[i] = cv;
  }
  int big = 0;
  for (int i = 0; i < count; ++i) big += std::fabs(x[i]) <= kLimit ? 0 : 1;
  if (big != 0) {
    for (int i = 0; i < count; ++i) {
      if (!(std::fabs(x[i]) <= kLimit)) {
        s[i] = std::sin(x[i]);
        c[i] = std::cos(x[i]);
      }
    }
  }
  return big;
}

AppearanceMlp::~AppearanceMlp() { Release(); }

AppearanceMlp::AppearanceMlp(AppearanceMlp&& o) noexcept {
  *this = static_cast<AppearanceMlp&&>(o);
}

AppearanceMlp& AppearanceMlp::operator=(AppearanceMlp&& o) noexcept {
  if (this == &o) return *this;
  Release();
  config_ = o.config_;
  fd_pad_ = o.fd_pad_;
  hid_pad_ = o.hid_pad_;
  in_dim_ = o.in_dim_;
  in_stride_ = o.in_stride_;
  weights_ = o.weights_;
  weights_count_ = o.weights_count_;
  o_basis_ = o.o_basis_;
  o_w1_ = o.o_w1_;
  o_b1_ = o.o_b1_;
  o_w2_ = o.o_w2_;
  o_b2_ = o.o_b2_;
  o_w3_ = o.o_w3_;
  o_b3_ = o.o_b3_;
  o_zero_ = o.o_zero_;
  kernel_ = o.kernel_;
  gemm8_ = o.gemm8_;
  o.weights_ = nullptr;
  o.weights_count_ = 0;
  return *this;
}

void AppearanceMlp::Release() {
  std::free(weights_);
  weights_ = nullptr;
  weights_count_ = 0;
}

Status AppearanceMlp::Init(const MlpConfig& config) {
  Release();
  ECRF_CHECK_OR_RETURN(config.num_products >= 0 && config.num_products <= kMaxMlpProducts,
                       kErrLimit, "mlp: num_products %d out of range [0, %d]", config.num_products,
                       kMaxMlpProducts);
  ECRF_CHECK_OR_RETURN(config.feature_dim >= 1 && config.feature_dim <= kMaxMlpFeatureDim,
                       kErrLimit, "mlp: feature_dim %d out of range [1, %d]", config.feature_dim,
                       kMaxMlpFeatureDim);
  ECRF_CHECK_OR_RETURN(config.feature_pe_freqs >= 0 && config.feature_pe_freqs <= kMaxMlpPeFreqs &&
                           config.viewdir_pe_freqs >= 0 &&
                           config.viewdir_pe_freqs <= kMaxMlpPeFreqs,
                       kErrLimit, "mlp: PE frequencies %d/%d out of range [0, %d]",
                       config.feature_pe_freqs, config.viewdir_pe_freqs, kMaxMlpPeFreqs);
  ECRF_CHECK_OR_RETURN(config.hidden >= 0 && config.hidden <= kMaxMlpHidden, kErrLimit,
                       "mlp: hidden width %d out of range [0, %d]", config.hidden, kMaxMlpHidden);
  ECRF_CHECK_OR_RETURN(
      config.hidden > 0 ||
          (config.sh_degree() >= 0 && config.feature_pe_freqs == 0 && config.viewdir_pe_freqs == 0),
      kErrInvalidArgument,
      "mlp: hidden 0 (spherical harmonics) needs feature_dim 3, 12, 27 or 48 and "
      "no positional encoding, not %d, %d and %d",
      config.feature_dim, config.feature_pe_freqs, config.viewdir_pe_freqs);
  ECRF_CHECK_OR_RETURN(
      config.hidden_layers == 2 || (config.hidden_layers == 1 && config.hidden > 0),
      kErrInvalidArgument, "mlp: %d hidden layers (2, or 1 with a hidden width above 0)",
      config.hidden_layers);
  config_ = config;
  kernel_ = BestGemmKernel();
  gemm8_ = Gemm8For(kernel_);
  in_dim_ = config.input_dim();
  in_stride_ = RoundUp(in_dim_, 8);
  fd_pad_ = RoundUp(config.feature_dim, kPad);
  hid_pad_ = RoundUp(config.hidden, kPad);
  const size_t P = static_cast<size_t>(config.num_products);
  const size_t H = static_cast<size_t>(config.hidden);
  const size_t H2 = config.hidden_layers == 2 ? H : 0;  // W2's rows
  // All factors are bounded by the limits above, so these sizes cannot overflow.
  size_t off = 0;
  o_basis_ = off;
  off += P * fd_pad_;
  o_w1_ = off;
  off += static_cast<size_t>(in_dim_) * hid_pad_;
  o_b1_ = off;
  off += hid_pad_;
  o_w2_ = off;
  off += H2 * hid_pad_;
  o_b2_ = off;
  off += hid_pad_;
  o_w3_ = off;
  off += H * kOutPad;
  o_b3_ = off;
  off += kOutPad;
  o_zero_ = off;
  off += fd_pad_;
  weights_ = static_cast<float*>(std::calloc(off, sizeof(float)));
  ECRF_CHECK_OR_RETURN(weights_ != nullptr, kErrOutOfMemory, "mlp: out of memory (%zu floats)",
                       off);
  weights_count_ = off;
  return Status::Ok();
}

Status AppearanceMlp::UseGemmKernel(GemmKernel kernel) {
  ECRF_CHECK_OR_RETURN(GemmKernelAvailable(kernel), kErrInvalidArgument,
                       "mlp: the %s kernel is not available on this CPU or in this build",
                       GemmKernelName(kernel));
  kernel_ = kernel;
  gemm8_ = Gemm8For(kernel);
  return Status::Ok();
}

size_t AppearanceMlp::num_params() const {
  return MlpParamCount(MakeMlpLayout(config_.feature_dim, config_.num_products, config_.hidden,
                                     config_.feature_pe_freqs, config_.viewdir_pe_freqs,
                                     config_.hidden_layers));
}

Status AppearanceMlp::SetParams(const float* params, size_t count) {
  ECRF_CHECK_OR_RETURN(initialized(), kErrInvalidArgument, "mlp: SetParams before Init");
  ECRF_CHECK_OR_RETURN(params != nullptr && count == num_params(), kErrInvalidArgument,
                       "mlp: expected %zu parameters, got %zu", num_params(), count);
  ECRF_CHECK_OR_RETURN(AllFinite(params, count), kErrCorrupt, "mlp: non-finite parameter");
  const int P = config_.num_products, F = config_.feature_dim, H = config_.hidden;
  const int H2 = config_.hidden_layers == 2 ? H : 0;
  const int in = in_dim_;
  std::memset(weights_, 0, weights_count_ * sizeof(float));
  const float* p = params;
  auto transpose = [&](int out, int k_in, float* dst, int ldw) {
    for (int o = 0; o < out; ++o) {
      for (int k = 0; k < k_in; ++k)
        dst[static_cast<size_t>(k) * ldw + o] = p[static_cast<size_t>(o) * k_in + k];
    }
    p += static_cast<size_t>(out) * k_in;
  };
  transpose(F, P, weights_ + o_basis_, fd_pad_);
  transpose(H, in, weights_ + o_w1_, hid_pad_);
  std::memcpy(weights_ + o_b1_, p, H * sizeof(float));
  p += H;
  transpose(H2, H2, weights_ + o_w2_, hid_pad_);
  std::memcpy(weights_ + o_b2_, p, H2 * sizeof(float));
  p += H2;
  transpose(3, H, weights_ + o_w3_, kOutPad);
  std::memcpy(weights_ + o_b3_, p, 3 * sizeof(float));
  return Status::Ok();
}

Status AppearanceMlp::GetParams(float* params, size_t count) const {
  ECRF_CHECK_OR_RETURN(initialized(), kErrInvalidArgument, "mlp: GetParams before Init");
  ECRF_CHECK_OR_RETURN(params != nullptr && count == num_params(), kErrInvalidArgument,
                       "mlp: expected room for %zu parameters, got %zu", num_params(), count);
  const int P = config_.num_products, F = config_.feature_dim, H = config_.hidden;
  const int H2 = config_.hidden_layers == 2 ? H : 0;
  float* p = params;
  auto untranspose = [&](int out, int k_in, const float* src, int ldw) {
    for (int o = 0; o < out; ++o) {
      for (int k = 0; k < k_in; ++k)
        p[static_cast<size_t>(o) * k_in + k] = src[static_cast<size_t>(k) * ldw + o];
    }
    p += static_cast<size_t>(out) * k_in;
  };
  untranspose(F, P, weights_ + o_basis_, fd_pad_);
  untranspose(H, in_dim_, weights_ + o_w1_, hid_pad_);
  std::memcpy(p, weights_ + o_b1_, H * sizeof(float));
  p += H;
  untranspose(H2, H2, weights_ + o_w2_, hid_pad_);
  std::memcpy(p, weights_ + o_b2_, H2 * sizeof(float));
  p += H2;
  untranspose(3, H, weights_ + o_w3_, kOutPad);
  std::memcpy(p, weights_ + o_b3_, 3 * sizeof(float));
  return Status::Ok();
}

size_t AppearanceMlp::ScratchFloats() const {
  const size_t C = kChunkRows;
  const size_t pe = static_cast<size_t>(config_.feature_dim) * config_.feature_pe_freqs +
                    3 * static_cast<size_t>(config_.viewdir_pe_freqs);
  const size_t P = config_.num_products > 0 ? config_.num_products : 1;
  return C * (fd_pad_ + in_stride_ + 2 * hid_pad_ + kOutPad) + 3 * C * pe + 4 * P + 64;
}

void AppearanceMlp::ShColour(int n, const float* feat, const float* viewdirs, float* rgb) const {
  const int degree = config_.sh_degree();
  const int K = (degree + 1) * (degree + 1);
  const float* b3 = weights_ + o_b3_;
  float y[kMaxShFunctions];
  for (int r = 0; r < n; ++r) {
    ShBasis(viewdirs + static_cast<size_t>(r) * 3, degree, y);
    const float* f = feat + static_cast<size_t>(r) * fd_pad_;
    for (int c = 0; c < 3; ++c) {
      float z = b3[c];
      for (int k = 0; k < K; ++k) z += y[k] * f[c * K + k];
      rgb[static_cast<size_t>(r) * 3 + c] = 1.f / (1.f + std::exp(-z));
    }
  }
}

uint64_t AppearanceMlp::Infer(int rows, const float* products, size_t products_stride,
                              const float* viewdirs, float* rgb, float* scratch) const {
  uint64_t wide = 0;  // encoding arguments past the fast sin/cos range
  const int C = kChunkRows;
  const int P = config_.num_products, F = config_.feature_dim, H = config_.hidden;
  const int Ff = config_.feature_pe_freqs, Fv = config_.viewdir_pe_freqs;
  const int nf = F * Ff, nv = 3 * Fv;
  float* feat = scratch;
  float* in = feat + static_cast<size_t>(C) * fd_pad_;
  float* h1 = in + static_cast<size_t>(C) * in_stride_;
  float* h2 = h1 + static_cast<size_t>(C) * hid_pad_;
  float* out = h2 + static_cast<size_t>(C) * hid_pad_;
  float* pe_arg = out + static_cast<size_t>(C) * kOutPad;
  float* pe_sin = pe_arg + static_cast<size_t>(C) * (nf + nv);
  float* pe_cos = pe_sin + static_cast<size_t>(C) * (nf + nv);
  float* zero_row = pe_cos + static_cast<size_t>(C) * (nf + nv);  // 4 * P floats, kept zero
  const int zp = P > 0 ? P : 1;
  std::memset(zero_row, 0, static_cast<size_t>(zp) * sizeof(float));
  const float* wz = weights_ + o_zero_;

  for (int r0 = 0; r0 < rows; r0 += C) {
    const int n = rows - r0 < C ? rows - r0 : C;
    const int n8 = (n + 7) & ~7;
    // Basis: features = products * basis^T (no bias). Rows past n read the zero row.
    for (int r = 0; r < n8; r += 8) {
      const float* x[8];
      float* y[8];
      for (int q = 0; q < 8; ++q) {
        x[q] = r + q < n ? products + static_cast<size_t>(r0 + r + q) * products_stride : zero_row;
        y[q] = feat + static_cast<size_t>(r + q) * fd_pad_;
      }
      gemm8_(x, nullptr, P, weights_ + o_basis_, fd_pad_, wz, fd_pad_, false, y);
    }
    if (H == 0) {
      ShColour(n, feat, viewdirs + static_cast<size_t>(r0) * 3, rgb + static_cast<size_t>(r0) * 3);
      continue;
    }
    // PE arguments for the whole chunk, one vectorised sin/cos pass.
    for (int r = 0; r < n8; ++r) {
      const float* f = feat + static_cast<size_t>(r) * fd_pad_;
      const float* vd = r < n ? viewdirs + static_cast<size_t>(r0 + r) * 3 : wz;
      float* a = pe_arg + static_cast<size_t>(r) * (nf + nv);
      for (int c = 0; c < F; ++c) {
        float m = 1.f;
        for (int q = 0; q < Ff; ++q, m *= 2.f) a[c * Ff + q] = f[c] * m;
      }
      for (int c = 0; c < 3; ++c) {
        float m = 1.f;
        for (int q = 0; q < Fv; ++q, m *= 2.f) a[nf + c * Fv + q] = vd[c] * m;
      }
    }
    wide += static_cast<uint64_t>(FastSinCos(pe_arg, n8 * (nf + nv), pe_sin, pe_cos));
    // Input rows: [features, viewdir, sin(feat args), cos(feat args), sin(vd args), cos(vd args)].
    for (int r = 0; r < n8; ++r) {
      float* x = in + static_cast<size_t>(r) * in_stride_;
      const float* vd = r < n ? viewdirs + static_cast<size_t>(r0 + r) * 3 : wz;
      const float* s = pe_sin + static_cast<size_t>(r) * (nf + nv);
      const float* c = pe_cos + static_cast<size_t>(r) * (nf + nv);
      std::memcpy(x, feat + static_cast<size_t>(r) * fd_pad_, F * sizeof(float));
      x += F;
      x[0] = vd[0];
      x[1] = vd[1];
      x[2] = vd[2];
      x += 3;
      std::memcpy(x, s, nf * sizeof(float));
      std::memcpy(x + nf, c, nf * sizeof(float));
      x += 2 * nf;
      std::memcpy(x, s + nf, nv * sizeof(float));
      std::memcpy(x + nv, c + nf, nv * sizeof(float));
    }
    GemmRows(gemm8_, n8, in, in_stride_, in_dim_, false, weights_ + o_w1_, hid_pad_,
             weights_ + o_b1_, true, h1, hid_pad_);
    const float* last = h1;  // what W3 reads
    if (config_.hidden_layers == 2) {
      GemmRows(gemm8_, n8, h1, hid_pad_, H, true, weights_ + o_w2_, hid_pad_, weights_ + o_b2_,
               true, h2, hid_pad_);
      last = h2;
    }
    GemmRows(gemm8_, n8, last, hid_pad_, H, true, weights_ + o_w3_, kOutPad, weights_ + o_b3_,
             false, out, kOutPad);
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < 3; ++c) {
        rgb[static_cast<size_t>(r0 + r) * 3 + c] =
            1.f / (1.f + std::exp(-out[static_cast<size_t>(r) * kOutPad + c]));
      }
    }
  }
  return wide;
}

}  // namespace dec
}  // namespace ecrf
