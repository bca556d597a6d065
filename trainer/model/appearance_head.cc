#include "trainer/model/appearance_head.h"

#include <omp.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>
#include <utility>

#include "decoder/sh_basis.h"
#include "format/scene_header.h"
#include "trainer/model/positional_encoding.h"
#include "trainer/model/small_gemm.h"

namespace ecrf {
namespace trainer {
namespace {

using RowMat = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using MapM = Eigen::Map<RowMat>;
using CMapM = Eigen::Map<const RowMat>;

constexpr int kRgb = 3;
constexpr long kGradSlots = 16;  // partial sums of Backward's weight gradients
constexpr int kViewDim = 3;

// Fills n floats with U(-bound, bound) from a portable bit-exact recipe (24 random bits each).
void FillUniform(std::mt19937& rng, float bound, float* out, size_t n) {
  for (size_t i = 0; i < n; ++i) {
    const float u = static_cast<float>(rng() >> 8) * (1.0f / 16777216.0f);  // [0, 1)
    out[i] = (2.0f * u - 1.0f) * bound;
  }
}

// y[r, :] = max(y[r, :] + b, 0) for m rows of width w.
void BiasRelu(float* __restrict y, const float* __restrict b, int m, int w) {
  for (int r = 0; r < m; ++r) {
    float* __restrict row = y + static_cast<size_t>(r) * w;
    for (int j = 0; j < w; ++j) {
      const float v = row[j] + b[j];
      row[j] = v > 0.0f ? v : 0.0f;
    }
  }
}

// d[i] = h[i] > 0 ? d[i] : 0 (ReLU backward through its output h), and colsum[j] += sum_r d[r, j].
void ReluBackwardColSum(float* __restrict d, const float* __restrict h, int m, int w,
                        float* __restrict colsum) {
  for (int r = 0; r < m; ++r) {
    float* __restrict drow = d + static_cast<size_t>(r) * w;
    const float* __restrict hrow = h + static_cast<size_t>(r) * w;
    for (int j = 0; j < w; ++j) {
      const float v = hrow[j] > 0.0f ? drow[j] : 0.0f;
      drow[j] = v;
      colsum[j] += v;
    }
  }
}

struct Dims {
  int p, f, h, in, ff, fv;
  int h2;  // the second hidden layer's width: h, or 0 with one hidden layer
  int pe_feat_offset() const { return f + kViewDim; }
  int pe_view_offset() const { return f + kViewDim + 2 * f * ff; }
  // Per-row floats of the chunk temporaries: PE tmp, then Backward's dz3, da, db, dx, dfeat.
  size_t pe_tmp_per_row() const { return 3 * static_cast<size_t>(std::max(f, kViewDim)); }
  size_t thread_per_row() const {
    return pe_tmp_per_row() + kRgb + 2 * static_cast<size_t>(h) + in + f;
  }
};

Dims DimsOf(const AppearanceHeadConfig& c) {
  Dims d;
  d.p = c.num_products;
  d.f = c.feature_dim;
  d.h = c.hidden;
  d.h2 = c.hidden_layers == 2 ? c.hidden : 0;
  d.ff = c.feature_pe_freqs;
  d.fv = c.viewdir_pe_freqs;
  d.in = d.f + kViewDim + 2 * d.f * d.ff + 2 * kViewDim * d.fv;
  return d;
}

// Number of threads worth using for `chunks` units of work.
int ThreadsFor(long chunks) {
  const int max_threads = omp_in_parallel() ? 1 : omp_get_max_threads();
  return static_cast<int>(std::max(1L, std::min<long>(max_threads, chunks)));
}

// Runs body(chunk, thread) for chunk in [0, num_chunks), statically partitioned over `threads`
// OpenMP threads (contiguous ranges). With one thread no parallel region is opened.
template <typename Body>
void ForChunks(int threads, long num_chunks, Body&& body) {
  if (threads <= 1) {
    for (long c = 0; c < num_chunks; ++c) body(c, 0);
    return;
  }
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num();
#pragma omp for schedule(static)
    for (long c = 0; c < num_chunks; ++c) body(c, t);
  }
}

struct Params {
  const float *basis, *w1, *b1, *w2, *b2, *w3, *b3;
};

// The weights transposed to in x out, the layout SmallGemm multiplies by from the right.
struct TransposedWeights {
  const float *basis, *w1, *w2, *w3;
};

// Fills `storage` with basis^T, W1^T, W2^T, W3^T and returns pointers into it.
TransposedWeights TransposeWeights(const Dims& d, const Params& w, std::vector<float>* storage) {
  const size_t sizes[4] = {static_cast<size_t>(d.p) * d.f, static_cast<size_t>(d.in) * d.h,
                           static_cast<size_t>(d.h2) * d.h2, static_cast<size_t>(d.h) * kRgb};
  storage->resize(sizes[0] + sizes[1] + sizes[2] + sizes[3]);
  float* out = storage->data();
  const float* src[4] = {w.basis, w.w1, w.w2, w.w3};
  const int rows[4] = {d.f, d.h, d.h2, kRgb};  // out
  const int cols[4] = {d.p, d.in, d.h2, d.h};  // in
  const float* dst[4];
  for (int t = 0; t < 4; ++t) {
    MapM(out, cols[t], rows[t]) = CMapM(src[t], rows[t], cols[t]).transpose();
    dst[t] = out;
    out += sizes[t];
  }
  return TransposedWeights{dst[0], dst[1], dst[2], dst[3]};
}

// hidden 0 (SPEC.md 7.6.2): rgb[c] = sigmoid(b3[c] + sum_k Y_k(d) x[c K + k]) over the m rows of x
// (stride d.in; the features first, then the view direction), as the decoder evaluates it.
void ShForwardRows(const Dims& d, const float* b3, int m, const float* x, float* rgb) {
  const int degree = ShDegreeForFeatureDim(d.f), K = (degree + 1) * (degree + 1);
  float y[kMaxShFunctions];
  for (int r = 0; r < m; ++r) {
    const float* xr = x + static_cast<size_t>(r) * d.in;
    ShBasis(xr + d.f, degree, y);
    for (int c = 0; c < kRgb; ++c) {
      float z = b3[c];
      for (int k = 0; k < K; ++k) z += y[k] * xr[c * K + k];
      rgb[r * kRgb + c] = 1.0f / (1.0f + std::exp(-z));
    }
  }
}

// Its backward: dfeat[r][c K + k] = dz[r][c] Y_k(d).
void ShBackwardRows(const Dims& d, int m, const float* x, const float* dz, float* dfeat) {
  const int degree = ShDegreeForFeatureDim(d.f), K = (degree + 1) * (degree + 1);
  float y[kMaxShFunctions];
  for (int r = 0; r < m; ++r) {
    ShBasis(x + static_cast<size_t>(r) * d.in + d.f, degree, y);
    float* df = dfeat + static_cast<size_t>(r) * d.f;
    for (int c = 0; c < kRgb; ++c) {
      for (int k = 0; k < K; ++k) df[c * K + k] = dz[r * kRgb + c] * y[k];
    }
  }
}

// Runs the forward pass of rows [0, m) of a chunk. x: m x in (written), h1/h2: m x h (written;
// h2 unused with one hidden layer), rgb: m x 3 (written). pe_tmp: pe_tmp_per_row() * m floats.
void ForwardChunk(const Dims& d, const Params& w, const TransposedWeights& wt, int m,
                  const float* products, const float* viewdirs, float* x, float* h1, float* h2,
                  float* rgb, float* pe_tmp) {
  // features = products @ basis^T, written straight into x's first f columns.
  SmallGemm(m, d.f, d.p, products, d.p, 1, wt.basis, d.f, x, d.in, false);
  for (int r = 0; r < m; ++r) {
    float* xr = x + static_cast<size_t>(r) * d.in + d.f;
    const float* v = viewdirs + static_cast<size_t>(r) * kViewDim;
    xr[0] = v[0];
    xr[1] = v[1];
    xr[2] = v[2];
  }
  if (d.h == 0) {
    ShForwardRows(d, w.b3, m, x, rgb);
    return;
  }
  PositionalEncodingRows(x, d.in, m, d.f, d.ff, x + d.pe_feat_offset(), d.in, pe_tmp);
  PositionalEncodingRows(x + d.f, d.in, m, kViewDim, d.fv, x + d.pe_view_offset(), d.in, pe_tmp);

  SmallGemm(m, d.h, d.in, x, d.in, 1, wt.w1, d.h, h1, d.h, false);
  BiasRelu(h1, w.b1, m, d.h);
  const float* last = h1;  // what W3 reads
  if (d.h2 > 0) {
    SmallGemm(m, d.h, d.h, h1, d.h, 1, wt.w2, d.h, h2, d.h, false);
    BiasRelu(h2, w.b2, m, d.h);
    last = h2;
  }
  SmallGemm(m, kRgb, d.h, last, d.h, 1, wt.w3, kRgb, rgb, kRgb, false);
  // Sigmoid, element by element: Eigen's vectorised exp would give a row different bits
  // depending on the buffer's alignment, and the training step promises the same gradients for
  // any thread count.
  for (int r = 0; r < m; ++r) {
    for (int j = 0; j < kRgb; ++j) {
      float& z = rgb[r * kRgb + j];
      z = 1.0f / (1.0f + std::exp(-(z + w.b3[j])));
    }
  }
}

}  // namespace

struct AppearanceHead::Activations {
  float* products;  // n x P (null when borrowed)
  float* x;         // n x in: MLP input (features, viewdirs, PEs)
  float* h1;        // n x hidden, after ReLU
  float* h2;        // n x hidden, after ReLU
  float* rgb;       // n x 3, after sigmoid
};

AppearanceHead::AppearanceHead(const AppearanceHeadConfig& config) : config_(config) {
  if (config.num_products <= 0 || config.feature_dim <= 0 || config.hidden < 0 ||
      config.feature_pe_freqs < 0 || config.viewdir_pe_freqs < 0) {
    throw std::invalid_argument("AppearanceHead: bad config");
  }
  if (config.hidden_layers != 2 && (config.hidden_layers != 1 || config.hidden == 0)) {
    throw std::invalid_argument("AppearanceHead: 2 hidden layers, or 1 with a width above 0");
  }
  if (config.hidden == 0 && (ShDegreeForFeatureDim(config.feature_dim) < 0 ||
                             config.feature_pe_freqs != 0 || config.viewdir_pe_freqs != 0)) {
    throw std::invalid_argument(
        "AppearanceHead: hidden 0 (spherical harmonics) needs feature_dim 3, 12, 27 or 48 and no "
        "positional encoding");
  }
  params_.assign(b3_offset() + kRgb, 0.0f);
  grads_.assign(params_.size(), 0.0f);
}

std::vector<size_t> AppearanceHead::KeptIndices(const std::vector<uint8_t>& keep) const {
  if (keep.size() != static_cast<size_t>(config_.num_products)) {
    throw std::invalid_argument("AppearanceHead::KeptIndices: one flag per product expected");
  }
  std::vector<size_t> idx;
  for (int f = 0; f < config_.feature_dim; ++f) {
    for (int p = 0; p < config_.num_products; ++p) {
      if (keep[p])
        idx.push_back(basis_offset() + static_cast<size_t>(f) * config_.num_products + p);
    }
  }
  for (size_t i = w1_offset(); i < params_.size(); ++i) idx.push_back(i);
  return idx;
}

void AppearanceHead::KeepProducts(const std::vector<uint8_t>& keep) {
  const std::vector<size_t> idx = KeptIndices(keep);
  int kept = 0;
  for (uint8_t k : keep) kept += k ? 1 : 0;
  if (kept < 1) throw std::invalid_argument("AppearanceHead::KeepProducts: no input would remain");
  std::vector<float> params(idx.size());
  for (size_t i = 0; i < idx.size(); ++i) params[i] = params_[idx[i]];
  config_.num_products = kept;
  params_ = std::move(params);
  grads_.assign(params_.size(), 0.0f);
  last_n_ = -1;  // the kept activations no longer match the shape
}

std::vector<size_t> AppearanceHead::KeptHiddenIndices(const std::vector<uint8_t>& keep1,
                                                      const std::vector<uint8_t>& keep2) const {
  const int h = config_.hidden, in = mlp_input_dim();
  if (keep1.size() != size_t(h) || keep2.size() != size_t(h) ||
      std::count(keep1.begin(), keep1.end(), 0) != std::count(keep2.begin(), keep2.end(), 0) ||
      std::count(keep1.begin(), keep1.end(), 0) == h ||
      (config_.hidden_layers == 1 && keep1 != keep2)) {
    throw std::invalid_argument(
        "AppearanceHead::KeptHiddenIndices: one flag per unit of each layer, as many kept in "
        "both, at least one");
  }
  std::vector<size_t> idx;
  for (size_t i = 0; i < w1_offset(); ++i) idx.push_back(i);  // the basis
  for (int i = 0; i < h; ++i) {
    if (!keep1[i]) continue;
    for (int c = 0; c < in; ++c) idx.push_back(w1_offset() + size_t(i) * in + c);
  }
  for (int i = 0; i < h; ++i) {
    if (keep1[i]) idx.push_back(b1_offset() + i);
  }
  const int h2 = config_.hidden_layers == 2 ? h : 0;
  for (int j = 0; j < h2; ++j) {
    if (!keep2[j]) continue;
    for (int i = 0; i < h; ++i) {
      if (keep1[i]) idx.push_back(w2_offset() + size_t(j) * h + i);
    }
  }
  for (int j = 0; j < h2; ++j) {
    if (keep2[j]) idx.push_back(b2_offset() + j);
  }
  for (int c = 0; c < kRgb; ++c) {
    for (int j = 0; j < h; ++j) {
      if (keep2[j]) idx.push_back(w3_offset() + size_t(c) * h + j);
    }
  }
  for (int c = 0; c < kRgb; ++c) idx.push_back(b3_offset() + c);
  return idx;
}

void AppearanceHead::KeepHidden(const std::vector<uint8_t>& keep1,
                                const std::vector<uint8_t>& keep2) {
  const std::vector<size_t> idx = KeptHiddenIndices(keep1, keep2);
  std::vector<float> params(idx.size());
  for (size_t i = 0; i < idx.size(); ++i) params[i] = params_[idx[i]];
  config_.hidden -= static_cast<int>(std::count(keep1.begin(), keep1.end(), 0));
  params_ = std::move(params);
  grads_.assign(params_.size(), 0.0f);
  last_n_ = -1;
}

int AppearanceHead::mlp_input_dim() const { return DimsOf(config_).in; }

size_t AppearanceHead::basis_offset() const { return 0; }
size_t AppearanceHead::w1_offset() const {
  return basis_offset() + static_cast<size_t>(config_.feature_dim) * config_.num_products;
}
size_t AppearanceHead::b1_offset() const {
  return w1_offset() + static_cast<size_t>(config_.hidden) * mlp_input_dim();
}
size_t AppearanceHead::w2_offset() const { return b1_offset() + config_.hidden; }
size_t AppearanceHead::b2_offset() const {
  const size_t h2 = config_.hidden_layers == 2 ? config_.hidden : 0;
  return w2_offset() + h2 * h2;
}
size_t AppearanceHead::w3_offset() const {
  return b2_offset() + (config_.hidden_layers == 2 ? config_.hidden : 0);
}
size_t AppearanceHead::b3_offset() const {
  return w3_offset() + static_cast<size_t>(kRgb) * config_.hidden;
}

void AppearanceHead::Initialize(uint32_t seed) {
  std::mt19937 rng(seed);
  const Dims d = DimsOf(config_);
  float* p = params_.data();
  const float bound_basis = 1.0f / std::sqrt(static_cast<float>(d.p));
  const float bound_in = 1.0f / std::sqrt(static_cast<float>(d.in));
  const float bound_h = 1.0f / std::sqrt(static_cast<float>(d.h));
  FillUniform(rng, bound_basis, p + basis_offset(), static_cast<size_t>(d.f) * d.p);
  FillUniform(rng, bound_in, p + w1_offset(), static_cast<size_t>(d.h) * d.in);
  FillUniform(rng, bound_in, p + b1_offset(), d.h);
  FillUniform(rng, bound_h, p + w2_offset(), static_cast<size_t>(d.h2) * d.h2);
  FillUniform(rng, bound_h, p + b2_offset(), d.h2);
  FillUniform(rng, bound_h, p + w3_offset(), static_cast<size_t>(kRgb) * d.h);
  std::fill(p + b3_offset(), p + b3_offset() + kRgb, 0.0f);  // TensoRF: last bias = 0
}

void AppearanceHead::ZeroGrads() { std::fill(grads_.begin(), grads_.end(), 0.0f); }

AppearanceHead::Activations AppearanceHead::ActivationsFor(int n, bool products_borrowed) {
  const Dims d = DimsOf(config_);
  const size_t nn = static_cast<size_t>(n);
  const size_t prod_floats = products_borrowed ? 0 : nn * d.p;
  const size_t total = prod_floats + nn * (d.in + 2 * static_cast<size_t>(d.h) + kRgb);
  if (scratch_.size() < total) scratch_.resize(total);
  float* s = scratch_.data();
  Activations a;
  a.products = products_borrowed ? nullptr : s;
  s += prod_floats;
  a.x = s;
  s += nn * d.in;
  a.h1 = s;
  s += nn * d.h;
  a.h2 = s;
  s += nn * d.h;
  a.rgb = s;
  return a;
}

void AppearanceHead::Forward(int n, const float* products, const float* viewdirs, float* rgb) {
  if (n < 0) throw std::invalid_argument("AppearanceHead::Forward: n < 0");
  last_n_ = n;
  last_borrowed_ = borrow_products_;
  borrowed_products_ = borrow_products_ ? products : nullptr;
  if (n == 0) return;
  const Dims d = DimsOf(config_);
  const Activations act = ActivationsFor(n, last_borrowed_);
  const Params w{params_.data() + basis_offset(), params_.data() + w1_offset(),
                 params_.data() + b1_offset(),    params_.data() + w2_offset(),
                 params_.data() + b2_offset(),    params_.data() + w3_offset(),
                 params_.data() + b3_offset()};
  const TransposedWeights wt = TransposeWeights(d, w, &transposed_);
  const int chunk = chunk_rows_;
  const long num_chunks = (n + chunk - 1) / chunk;
  const int threads = ThreadsFor(num_chunks);
  const size_t per_thread = d.pe_tmp_per_row() * chunk;
  if (thread_scratch_.size() < per_thread * threads) thread_scratch_.resize(per_thread * threads);
  float* const thread_scratch = thread_scratch_.data();
  ForChunks(threads, num_chunks, [&](long c, int t) {
    float* pe_tmp = thread_scratch + per_thread * t;
    const size_t r0 = static_cast<size_t>(c) * chunk;
    const int m = static_cast<int>(std::min<size_t>(chunk, n - r0));
    const float* prod = products + r0 * d.p;
    if (act.products != nullptr) {
      std::memcpy(act.products + r0 * d.p, prod, sizeof(float) * m * d.p);
      prod = act.products + r0 * d.p;
    }
    float* out = act.rgb + r0 * kRgb;
    ForwardChunk(d, w, wt, m, prod, viewdirs + r0 * kViewDim, act.x + r0 * d.in, act.h1 + r0 * d.h,
                 act.h2 + r0 * d.h, out, pe_tmp);
    std::memcpy(rgb + r0 * kRgb, out, sizeof(float) * m * kRgb);
  });
}

void AppearanceHead::Infer(int n, const float* products, const float* viewdirs, float* rgb) const {
  if (n <= 0) return;
  const Dims d = DimsOf(config_);
  const Params w{params_.data() + basis_offset(), params_.data() + w1_offset(),
                 params_.data() + b1_offset(),    params_.data() + w2_offset(),
                 params_.data() + b2_offset(),    params_.data() + w3_offset(),
                 params_.data() + b3_offset()};
  // Local: Infer is const and may run concurrently on one head.
  std::vector<float> transposed;
  const TransposedWeights wt = TransposeWeights(d, w, &transposed);
  const int chunk = chunk_rows_;
  const long num_chunks = (n + chunk - 1) / chunk;
  const int threads = ThreadsFor(num_chunks);
  const size_t per_thread =
      static_cast<size_t>(chunk) * (d.pe_tmp_per_row() + d.in + 2 * static_cast<size_t>(d.h));
  ForChunks(threads, num_chunks, [&](long c, int) {
    // Per OS thread, grown once: Infer is const and may run concurrently on several heads.
    static thread_local std::vector<float> tls;
    if (tls.size() < per_thread) tls.resize(per_thread);
    float* pe_tmp = tls.data();
    float* x = pe_tmp + d.pe_tmp_per_row() * chunk;
    float* h1 = x + static_cast<size_t>(chunk) * d.in;
    float* h2 = h1 + static_cast<size_t>(chunk) * d.h;
    const size_t r0 = static_cast<size_t>(c) * chunk;
    const int m = static_cast<int>(std::min<size_t>(chunk, n - r0));
    ForwardChunk(d, w, wt, m, products + r0 * d.p, viewdirs + r0 * kViewDim, x, h1, h2,
                 rgb + r0 * kRgb, pe_tmp);
  });
}

void AppearanceHead::Backward(int n, const float* dl_drgb, float* dl_dproducts) {
  if (n != last_n_) {
    throw std::logic_error("AppearanceHead::Backward: n differs from the last Forward");
  }
  if (n == 0) return;
  const Dims d = DimsOf(config_);
  const Activations act = ActivationsFor(n, last_borrowed_);
  const float* stored_products = last_borrowed_ ? borrowed_products_ : act.products;
  const float* basis = params_.data() + basis_offset();
  const float* w1 = params_.data() + w1_offset();
  const float* w2 = params_.data() + w2_offset();
  const float* w3 = params_.data() + w3_offset();
  const int chunk = chunk_rows_;
  const long num_chunks = (n + chunk - 1) / chunk;
  // Weight gradients are summed per slot (a fixed run of consecutive chunks) and the slots in
  // order: the same bits for any thread count, unlike per-thread partial sums.
  const long slots = std::min<long>(kGradSlots, num_chunks);
  const int threads = ThreadsFor(slots);
  const size_t per_thread = d.thread_per_row() * chunk;
  if (thread_scratch_.size() < per_thread * threads) thread_scratch_.resize(per_thread * threads);
  const size_t np = params_.size();
  if (slot_grads_.size() < np * slots) slot_grads_.resize(np * slots);
  const int ff = d.ff;
  std::fill(slot_grads_.begin(), slot_grads_.begin() + np * slots, 0.0f);
  float* const thread_scratch = thread_scratch_.data();
  float* const slot_grads = slot_grads_.data();
  auto backward_chunk = [&](long c, float* scratch, float* g) {
    float* dz3 = scratch + d.pe_tmp_per_row() * chunk;
    float* da = dz3 + static_cast<size_t>(chunk) * kRgb;
    float* db = da + static_cast<size_t>(chunk) * d.h;
    float* dx = db + static_cast<size_t>(chunk) * d.h;
    float* dfeat = dx + static_cast<size_t>(chunk) * d.in;
    float* g_basis = g + basis_offset();
    float* g_w1 = g + w1_offset();
    float* g_w2 = g + w2_offset();
    float* g_w3 = g + w3_offset();
    float* g_b1 = g + b1_offset();
    float* g_b2 = g + b2_offset();
    float* g_b3 = g + b3_offset();
    const size_t r0 = static_cast<size_t>(c) * chunk;
    const int m = static_cast<int>(std::min<size_t>(chunk, n - r0));
    const float* x = act.x + r0 * d.in;
    const float* h1 = act.h1 + r0 * d.h;
    const float* h2 = act.h2 + r0 * d.h;
    const float* rgb = act.rgb + r0 * kRgb;
    const float* dl = dl_drgb + r0 * kRgb;
    const float* products = stored_products + r0 * d.p;
    // Sigmoid.
    for (int i = 0; i < m * kRgb; ++i) dz3[i] = dl[i] * rgb[i] * (1.0f - rgb[i]);
    for (int r = 0; r < m; ++r) {
      for (int j = 0; j < kRgb; ++j) g_b3[j] += dz3[r * kRgb + j];
    }
    if (d.h == 0) {
      ShBackwardRows(d, m, x, dz3, dfeat);
    } else {
      // Weight gradients are (dL/dout)^T @ in: SmallGemm reads the transpose through a_row = 1.
      const float* last = d.h2 > 0 ? h2 : h1;  // what W3 read
      SmallGemm(kRgb, d.h, m, dz3, 1, kRgb, last, d.h, g_w3, d.h, true);
      if (d.h2 > 0) {  // layer 2
        SmallGemm(m, d.h, kRgb, dz3, kRgb, 1, w3, d.h, da, d.h, false);
        ReluBackwardColSum(da, h2, m, d.h, g_b2);
        SmallGemm(d.h, d.h, m, da, 1, d.h, h1, d.h, g_w2, d.h, true);
        SmallGemm(m, d.h, d.h, da, d.h, 1, w2, d.h, db, d.h, false);
      } else {
        SmallGemm(m, d.h, kRgb, dz3, kRgb, 1, w3, d.h, db, d.h, false);
      }
      // Layer 1.
      ReluBackwardColSum(db, h1, m, d.h, g_b1);
      SmallGemm(d.h, d.in, m, db, 1, d.h, x, d.in, g_w1, d.in, true);
      // dL/dx only for the columns that depend on the features (the view-direction PE columns
      // at the end have no gradient path).
      SmallGemm(m, d.pe_view_offset(), d.h, db, d.h, 1, w1, d.in, dx, d.in, false);
      // Features: direct input plus their positional encoding.
      for (int r = 0; r < m; ++r) {
        const float* dxr = dx + static_cast<size_t>(r) * d.in;
        const float* xr = x + static_cast<size_t>(r) * d.in;
        float* df = dfeat + static_cast<size_t>(r) * d.f;
        for (int k = 0; k < d.f; ++k) df[k] = dxr[k];
        PositionalEncodingBackward(xr + d.pe_feat_offset(), dxr + d.pe_feat_offset(), d.f, ff, df);
      }
    }
    // Basis.
    SmallGemm(m, d.p, d.f, dfeat, d.f, 1, basis, d.p, dl_dproducts + r0 * d.p, d.p, false);
    SmallGemm(d.f, d.p, m, dfeat, 1, d.f, products, d.p, g_basis, d.p, true);
  };
  ForChunks(threads, slots, [&](long slot, int t) {
    for (long c = slot * num_chunks / slots; c < (slot + 1) * num_chunks / slots; ++c)
      backward_chunk(c, thread_scratch + per_thread * t, slot_grads + np * slot);
  });
  for (long slot = 0; slot < slots; ++slot) {
    const float* g = slot_grads_.data() + np * slot;
    float* out = grads_.data();
    for (size_t i = 0; i < np; ++i) out[i] += g[i];
  }
}

}  // namespace trainer
}  // namespace ecrf
