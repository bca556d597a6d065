// FP exceptions are never enabled here; without trapping math GCC if-converts the clamps of the
// exp approximation and vectorises the per-coefficient loops (SSE2 baseline: ~4x).
#pragma GCC optimize("no-trapping-math")

#include "trainer/rate/entropy_model.h"
#include "decoder/multiversion.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace ecrf {
namespace trainer {
namespace {

constexpr int kChunk = 64;          // values per inner chunk (2 * kChunk network inputs)
constexpr size_t kWorkItem = 2048;  // values per OpenMP work item
constexpr long kSumSlots = 16;      // runs of work items summed apart, then in order
constexpr int kP = kEntropyParamsPerModel;

uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// exp for float arrays: Cephes expf (range reduction by ln2, degree-6 polynomial, ~1 ulp),
// written without library calls so that loops over it vectorise.
__attribute__((always_inline)) inline float ExpT(float x) {
  x = std::min(std::max(x, -87.0f), 88.0f);
  const float t = x * 1.44269504088896341f + 12582912.f;  // round to nearest via magic number
  const float n = t - 12582912.f;
  float r = x - n * 0.693359375f;
  r = r - n * -2.12194440e-4f;
  float p = 1.9875691500E-4f;
  p = p * r + 1.3981999507E-3f;
  p = p * r + 8.3334519073E-3f;
  p = p * r + 4.1665795894E-2f;
  p = p * r + 1.6666665459E-1f;
  p = p * r + 5.0000001201E-1f;
  const float y = p * r * r + r + 1.f;
  // n sits in the low mantissa bits of t (t = 1.5 * 2^23 + n): no float -> int conversion.
  int32_t ti;
  std::memcpy(&ti, &t, sizeof(ti));
  const int32_t e = (ti - 0x4B400000 + 127) << 23;
  float s;
  std::memcpy(&s, &e, sizeof(s));
  return y * s;
}
inline double ExpT(double x) { return std::exp(x); }

// tanh(a) = 1 - 2 / (exp(2a) + 1); absolute error ~1e-7 in float.
__attribute__((always_inline)) inline float TanhT(float a) {
  return 1.f - 2.f / (ExpT(2.f * a) + 1.f);
}
inline double TanhT(double a) { return std::tanh(a); }

__attribute__((always_inline)) inline float SigmoidT(float z) { return 1.f / (1.f + ExpT(-z)); }
inline double SigmoidT(double z) { return 1.0 / (1.0 + std::exp(-z)); }

// log2 for positive normal floats: exponent + atanh series on the mantissa in [sqrt.5, sqrt2).
__attribute__((always_inline)) inline float Log2T(float x) {
  int32_t i;
  std::memcpy(&i, &x, sizeof(i));
  int32_t e = ((i >> 23) & 0xff) - 127;
  int32_t mi = (i & 0x007fffff) | 0x3f800000;
  float m;
  std::memcpy(&m, &mi, sizeof(m));
  const bool big = m > 1.41421356f;
  m = big ? m * 0.5f : m;
  e = big ? e + 1 : e;
  const float f = (m - 1.f) / (m + 1.f);
  const float f2 = f * f;
  const float s =
      f * (2.f + f2 * (0.666666667f + f2 * (0.4f + f2 * (0.285714286f + f2 * 0.222222222f))));
  return static_cast<float>(e) + s * 1.44269504088896341f;
}
inline double Log2T(double x) { return std::log2(x); }

// Derived parameters of one model.
template <typename T>
struct ModelView {
  T sp[4][9];   // softplus(matrix_i), [k * fin + j]
  T dsp[4][9];  // sigmoid(matrix_i) = d softplus / d matrix
  T bias[4][3];
  T g[3][3];  // tanh(factor_i)
  explicit ModelView(const float* p) {
    const int fin[4] = {1, 3, 3, 3}, fout[4] = {3, 3, 3, 1};
    for (int l = 0; l < 4; ++l) {
      for (int i = 0; i < fin[l] * fout[l]; ++i) {
        const double m = p[kEntropyMatrixOffset[l] + i];
        // softplus as torch (threshold 20).
        sp[l][i] = static_cast<T>(m > 20.0 ? m : std::log1p(std::exp(m)));
        dsp[l][i] = static_cast<T>(1.0 / (1.0 + std::exp(-m)));
      }
      for (int k = 0; k < fout[l]; ++k) bias[l][k] = static_cast<T>(p[kEntropyBiasOffset[l] + k]);
    }
    for (int l = 0; l < 3; ++l) {
      for (int k = 0; k < 3; ++k)
        g[l][k] = static_cast<T>(std::tanh(double(p[kEntropyFactorOffset[l] + k])));
    }
  }
};

// The parameter gradients of chunks, w.r.t. softplus(W), bias and tanh(factor) (AddParamGrads
// converts them to gradients w.r.t. the raw parameters).
template <typename T>
struct ChunkGrad {
  T dsp[4][9];
  T db[4][3];
  T dg[3][3];
  void Zero() {
    std::fill(&dsp[0][0], &dsp[0][0] + 36, T(0));
    std::fill(&db[0][0], &db[0][0] + 12, T(0));
    std::fill(&dg[0][0], &dg[0][0] + 9, T(0));
  }
};

template <typename T>
struct alignas(64) ChunkState {
  static constexpr int M = 2 * kChunk;
  T h[4][3][M];  // h[0][0] = input; h[l+1] = output of layer l (l < 3)
  T t[3][3][M];  // tanh of pre-activation of layer l
  T logit[M];
  T bits[kChunk];
  T dh[3][M];
  T dh2[3][M];
};

// The chunk's network inputs: lanes 0..kChunk-1 are x - 1/2 (lower), kChunk.. x + 1/2 (upper);
// lanes past n hold 0, so that every loop below runs over all lanes at a fixed length.
template <typename T>
__attribute__((always_inline)) inline void LoadChunkInputs(const float* x_f, const double* x_d,
                                                           int n, ChunkState<T>& st) {
  for (int i = 0; i < kChunk; ++i) {
    const T xi = i < n ? (x_f ? static_cast<T>(x_f[i]) : static_cast<T>(x_d[i])) : T(0);
    st.h[0][0][i] = xi - T(0.5);
    st.h[0][0][kChunk + i] = xi + T(0.5);
  }
}

// Forward through the four layers: h[l+1] = sp_l . h[l] + b_l + g_l * tanh(.), the last layer's
// output (no tanh term) into logit.
template <typename T>
__attribute__((always_inline)) inline void ForwardChunk(const ModelView<T>& mv, ChunkState<T>& st) {
  constexpr int m = ChunkState<T>::M;
  for (int l = 0; l < 4; ++l) {
    const int fin = l == 0 ? 1 : 3;
    const int fout = l == 3 ? 1 : 3;
    for (int k = 0; k < fout; ++k) {
      T* out = l == 3 ? st.logit : st.h[l + 1][k];
      const T b = mv.bias[l][k];
      const T w0 = mv.sp[l][k * fin];
      const T* in0 = st.h[l][0];
      if (fin == 1) {
#pragma omp simd
        for (int i = 0; i < m; ++i) out[i] = w0 * in0[i] + b;
      } else {
        const T w1 = mv.sp[l][k * fin + 1], w2 = mv.sp[l][k * fin + 2];
        const T* in1 = st.h[l][1];
        const T* in2 = st.h[l][2];
#pragma omp simd
        for (int i = 0; i < m; ++i) out[i] = w0 * in0[i] + w1 * in1[i] + w2 * in2[i] + b;
      }
      if (l < 3) {
        const T g = mv.g[l][k];
        T* tt = st.t[l][k];
#pragma omp simd
        for (int i = 0; i < m; ++i) {
          const T th = TanhT(out[i]);
          tt[i] = th;
          out[i] += g * th;
        }
      }
    }
  }
}

// Likelihood (the difference of the sigmoids of the upper and lower logits, bounded below), the
// bits of each value into st.bits and d (grad_scale * bits) / d logit into st.dh[0], lanes as
// logit. Returns the bits of the n valid values.
template <typename T>
__attribute__((always_inline)) inline T ChunkBits(const EntropyModelOptions& opt, int n,
                                                  T grad_scale, ChunkState<T>& st) {
  const T bound = static_cast<T>(opt.likelihood_lower_bound);
  const bool pass_inc = opt.pass_gradient_if_increasing;
  T bits_sum = 0;
  T* dl = st.dh[0];
  const T inv_ln2 = T(1.4426950408889634);
#pragma omp simd reduction(+ : bits_sum)
  for (int i = 0; i < kChunk; ++i) {
    const T lo = st.logit[i], up = st.logit[kChunk + i];
    const T s = (lo + up > T(0)) ? T(-1) : T(1);
    const T su = SigmoidT(s * up), sl = SigmoidT(s * lo);
    const T d = su - sl;
    const T lik = d < T(0) ? -d : d;
    const bool clamped = lik < bound;
    const T likc = clamped ? bound : lik;
    const T b = -Log2T(likc);
    const T valid = i < n ? T(1) : T(0);
    bits_sum += valid * b;
    st.bits[i] = b;
    T g = -grad_scale * inv_ln2 / likc * valid;  // d (scale * bits) / d likc
    const bool pass = !clamped || (pass_inc && g < T(0));
    g = pass ? g : T(0);
    const T gd = d > T(0) ? g : (d < T(0) ? -g : T(0));  // through |.|
    dl[kChunk + i] = gd * s * su * (T(1) - su);
    dl[i] = -gd * s * sl * (T(1) - sl);
  }
  return bits_sum;
}

// Backward through layer 3, logit = sp3 . h[3] + b3: its parameter gradients into acc (when not
// null) and d / d h[3] into st.dh2.
template <typename T>
__attribute__((always_inline)) inline void BackwardOutputLayer(const ModelView<T>& mv,
                                                               ChunkGrad<T>* acc,
                                                               ChunkState<T>& st) {
  constexpr int m = ChunkState<T>::M;
  const T* dl = st.dh[0];
  T(*dh)[m] = st.dh2;
  T sdl = 0;
#pragma omp simd reduction(+ : sdl)
  for (int i = 0; i < m; ++i) sdl += dl[i];
  if (acc) acc->db[3][0] += sdl;
  for (int j = 0; j < 3; ++j) {
    const T* hj = st.h[3][j];
    T s = 0;
#pragma omp simd reduction(+ : s)
    for (int i = 0; i < m; ++i) s += dl[i] * hj[i];
    if (acc) acc->dsp[3][j] += s;
    const T w = mv.sp[3][j];
#pragma omp simd
    for (int i = 0; i < m; ++i) dh[j][i] = w * dl[i];
  }
}

// Backward through layers 2, 1, 0 from d / d h[3] in st.dh2: their parameter gradients into acc
// (when not null), and d / d input left in st.dh2[0].
template <typename T>
__attribute__((always_inline)) inline void BackwardHiddenLayers(const ModelView<T>& mv,
                                                                ChunkGrad<T>* acc,
                                                                ChunkState<T>& st) {
  constexpr int m = ChunkState<T>::M;
  T(*dh)[m] = st.dh2;  // gradient w.r.t. h[l+1] (3 rows)
  T(*da)[m] = st.dh;   // reuse: pre-activation gradient of the current layer (rows 0..2)
  for (int l = 2; l >= 0; --l) {
    const int fin = l == 0 ? 1 : 3;
    for (int k = 0; k < 3; ++k) {
      const T g = mv.g[l][k];
      const T* tt = st.t[l][k];
      T* dak = da[k];
      const T* dhk = dh[k];
      T sg = 0, sb = 0;
#pragma omp simd reduction(+ : sg, sb)
      for (int i = 0; i < m; ++i) {
        sg += dhk[i] * tt[i];
        const T v = dhk[i] * (T(1) + g * (T(1) - tt[i] * tt[i]));
        dak[i] = v;
        sb += v;
      }
      if (acc) {
        acc->dg[l][k] += sg;
        acc->db[l][k] += sb;
      }
      for (int j = 0; j < fin; ++j) {
        const T* hj = st.h[l][j];
        T s = 0;
#pragma omp simd reduction(+ : s)
        for (int i = 0; i < m; ++i) s += dak[i] * hj[i];
        if (acc) acc->dsp[l][k * fin + j] += s;
      }
    }
    // dh for the layer input (rows 0..fin-1), written into dh (da is consumed here).
    for (int j = 0; j < fin; ++j) {
      const T w0 = mv.sp[l][0 * fin + j], w1 = mv.sp[l][1 * fin + j], w2 = mv.sp[l][2 * fin + j];
      T* out = dh[j];
#pragma omp simd
      for (int i = 0; i < m; ++i) out[i] = w0 * da[0][i] + w1 * da[1][i] + w2 * da[2][i];
    }
  }
}

// Per-chunk forward + backward on n <= kChunk values: the bits of each value into bits_out and
// d bits / d x into dx_out_f or dx_out_d (each when not null), the parameter gradients (w.r.t.
// softplus(W), bias, tanh(factor)) added into acc when acc != nullptr. Returns the chunk's bits.
template <typename T>
__attribute__((always_inline)) inline double RunChunk(const ModelView<T>& mv,
                                                      const EntropyModelOptions& opt,
                                                      const float* x_f, const double* x_d, int n,
                                                      T grad_scale, float* bits_out,
                                                      float* dx_out_f, double* dx_out_d,
                                                      ChunkGrad<T>* acc, ChunkState<T>& st) {
  const bool backward = acc != nullptr || dx_out_f != nullptr || dx_out_d != nullptr;
  LoadChunkInputs(x_f, x_d, n, st);
  ForwardChunk(mv, st);
  const T bits_sum = ChunkBits(opt, n, grad_scale, st);
  if (bits_out) {
    for (int i = 0; i < n; ++i) bits_out[i] = static_cast<float>(st.bits[i]);
  }
  if (!backward) return static_cast<double>(bits_sum);
  BackwardOutputLayer(mv, acc, st);
  BackwardHiddenLayers(mv, acc, st);
  // st.dh2[0] = d / d input; x feeds both lanes.
  const T* dx = st.dh2[0];
  if (dx_out_f) {
    for (int i = 0; i < n; ++i) dx_out_f[i] = static_cast<float>(dx[i] + dx[kChunk + i]);
  }
  if (dx_out_d) {
    for (int i = 0; i < n; ++i) dx_out_d[i] = static_cast<double>(dx[i] + dx[kChunk + i]);
  }
  return static_cast<double>(bits_sum);
}

// Converts gradients w.r.t. (softplus(W), bias, tanh(factor)) to gradients w.r.t. the raw
// parameters and adds them to out[43].
template <typename T>
void AddParamGrads(const ModelView<T>& mv, const ChunkGrad<T>& cg, double* out) {
  const int count[4] = {3, 9, 9, 3};
  for (int l = 0; l < 4; ++l) {
    for (int i = 0; i < count[l]; ++i) {
      out[kEntropyMatrixOffset[l] + i] += double(cg.dsp[l][i]) * double(mv.dsp[l][i]);
    }
    for (int k = 0; k < (l == 3 ? 1 : 3); ++k)
      out[kEntropyBiasOffset[l] + k] += double(cg.db[l][k]);
  }
  for (int l = 0; l < 3; ++l) {
    for (int k = 0; k < 3; ++k) {
      const double g = double(mv.g[l][k]);
      out[kEntropyFactorOffset[l] + k] += double(cg.dg[l][k]) * (1.0 - g * g);
    }
  }
}

ECRF_MULTIVERSION
double RunItemFloat(const ModelView<float>& mv, const EntropyModelOptions& opt, const float* x,
                    size_t begin, size_t end, float grad_scale, float* bits, float* dbits_dx,
                    ChunkGrad<float>* acc, ChunkState<float>& st) {
  double total = 0.0;
  for (size_t b = begin; b < end; b += kChunk) {
    const int n = static_cast<int>(std::min<size_t>(kChunk, end - b));
    total += RunChunk<float>(mv, opt, x + b, nullptr, n, grad_scale, bits ? bits + b : nullptr,
                             dbits_dx ? dbits_dx + b : nullptr, nullptr, acc, st);
  }
  return total;
}

}  // namespace

void FactorizedEntropyModel::Init(int num_models, uint64_t seed,
                                  const EntropyModelOptions& options) {
  if (num_models < 1) throw std::invalid_argument("FactorizedEntropyModel: num_models < 1");
  num_models_ = num_models;
  options_ = options;
  params_.assign(static_cast<size_t>(num_models) * kP, 0.f);
  grads_.assign(params_.size(), 0.f);
  const int filters[5] = {1, 3, 3, 3, 1};
  const double scale = std::pow(static_cast<double>(options.init_scale), 1.0 / 4.0);
  for (int c = 0; c < num_models; ++c) {
    float* p = model_params(c);
    for (int l = 0; l < 4; ++l) {
      const float init = static_cast<float>(std::log(std::expm1(1.0 / scale / filters[l + 1])));
      for (int i = 0; i < filters[l] * filters[l + 1]; ++i) p[kEntropyMatrixOffset[l] + i] = init;
      for (int k = 0; k < filters[l + 1]; ++k) {
        const uint64_t h = SplitMix64(seed * 0x2545F4914F6CDD1Dull + c * 16 + l * 4 + k);
        p[kEntropyBiasOffset[l] + k] =
            static_cast<float>(static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0) - 0.5);
      }
    }
    // factors stay 0.
  }
}

void FactorizedEntropyModel::ZeroGrads() { std::fill(grads_.begin(), grads_.end(), 0.f); }

double FactorizedEntropyModel::Bits(const float* x, const EntropySegment* segments,
                                    int num_segments, float* bits, float* dbits_dx,
                                    float grad_scale, bool accumulate_param_grads) {
  struct Item {
    int model;
    size_t begin, end;
  };
  std::vector<Item> items;
  for (int s = 0; s < num_segments; ++s) {
    const EntropySegment& seg = segments[s];
    if (seg.model < 0 || seg.model >= num_models_) {
      throw std::invalid_argument("FactorizedEntropyModel::Bits: model index out of range");
    }
    for (size_t b = seg.begin; b < seg.end; b += kWorkItem) {
      items.push_back({seg.model, b, std::min(seg.end, b + kWorkItem)});
    }
  }
  const long num_items = static_cast<long>(items.size());
  size_t num_values = 0;
  for (const Item& item : items) num_values += item.end - item.begin;
  std::vector<ModelView<float>> views;
  views.reserve(num_models_);
  for (int c = 0; c < num_models_; ++c) views.emplace_back(model_params(c));
  // Items are summed in fixed runs (slots) and the slots in order, so the totals and parameter
  // gradients are the same bits for any thread count and schedule.
  const long slots = std::min<long>(kSumSlots, num_items);
  const size_t np = accumulate_param_grads ? params_.size() : 0;
  std::vector<double> slot_totals(static_cast<size_t>(slots), 0.0);
  std::vector<double> slot_grads(np * static_cast<size_t>(slots), 0.0);
  // Small calls run serially (a parallel region costs more than ~10k values' evaluation).
#pragma omp parallel if (num_items > 1 && num_values > 16384)
  {
    ChunkState<float>* st = new ChunkState<float>;
    ChunkGrad<float> cg;
#pragma omp for schedule(dynamic, 1)
    for (long slot = 0; slot < slots; ++slot) {
      double* local = slot_grads.data() + np * slot;
      for (long it = slot * num_items / slots; it < (slot + 1) * num_items / slots; ++it) {
        const Item& item = items[it];
        const ModelView<float>& mv = views[item.model];
        cg.Zero();
        slot_totals[slot] += RunItemFloat(mv, options_, x, item.begin, item.end, grad_scale, bits,
                                          dbits_dx, accumulate_param_grads ? &cg : nullptr, *st);
        if (accumulate_param_grads) AddParamGrads(mv, cg, local + item.model * kP);
      }
    }
    delete st;
  }
  double total = 0.0;
  for (long slot = 0; slot < slots; ++slot) {
    total += slot_totals[slot];
    const double* local = slot_grads.data() + np * slot;
    for (size_t i = 0; i < np; ++i) grads_[i] += static_cast<float>(local[i]);
  }
  return total;
}

double FactorizedEntropyModel::BitsDouble(int model, double x, double* dbits_dx,
                                          double* dparams) const {
  const ModelView<double> mv(model_params(model));
  ChunkState<double>* st = new ChunkState<double>;
  ChunkGrad<double> cg;
  cg.Zero();
  double dx = 0.0;
  const double bits = RunChunk<double>(mv, options_, nullptr, &x, 1, 1.0, nullptr, nullptr, &dx,
                                       dparams ? &cg : nullptr, *st);
  delete st;
  if (dbits_dx) *dbits_dx = dx;
  if (dparams) AddParamGrads(mv, cg, dparams);
  return bits;
}

double FactorizedEntropyModel::LogitsCumulative(int model, double x) const {
  const ModelView<double> mv(model_params(model));
  double h[3] = {x, 0, 0};
  for (int l = 0; l < 4; ++l) {
    const int fin = l == 0 ? 1 : 3, fout = l == 3 ? 1 : 3;
    double o[3];
    for (int k = 0; k < fout; ++k) {
      double a = mv.bias[l][k];
      for (int j = 0; j < fin; ++j) a += mv.sp[l][k * fin + j] * h[j];
      if (l < 3) a += mv.g[l][k] * std::tanh(a);
      o[k] = a;
    }
    for (int k = 0; k < fout; ++k) h[k] = o[k];
  }
  return h[0];
}

double FactorizedEntropyModel::Likelihood(int model, double x) const {
  const double lo = LogitsCumulative(model, x - 0.5), up = LogitsCumulative(model, x + 0.5);
  const double s = lo + up > 0 ? -1.0 : 1.0;
  const double lik = std::abs(SigmoidT(s * up) - SigmoidT(s * lo));
  return std::max(lik, static_cast<double>(options_.likelihood_lower_bound));
}

}  // namespace trainer
}  // namespace ecrf
