// AppearanceMlp: float32 inference of TensoRF's MLPRender_Fea colour head (no allocation, no
// exceptions, no BLAS).
//
// products (P) -> basis [F x P, no bias] -> features (F)
// -> input [features F, viewdir 3, PE(features, Ff), PE(viewdir, Fv)]
// -> Linear(hidden) ReLU -> Linear(hidden) ReLU (absent with one hidden layer) -> Linear(3)
// -> sigmoid;
// with hidden 0, features = spherical-harmonics coefficients -> + b3 -> sigmoid (SPEC.md 7.6.2).
// PE(x, Fr): arguments x_c * 2^f ordered c-major, then all sines, then all cosines.
// Widths come from MlpConfig (read from the scene), not constants.
//
// Weights are kept transposed ([in x out], out padded to a multiple of 8) so every layer is a
// row-blocked product whose inner loop runs over contiguous outputs and auto-vectorises. Each row
// goes through exactly the same arithmetic whatever the batch size or its position in the batch,
// so results do not depend on batching (or on the renderer's thread count).
#ifndef ECRF_DECODER_MLP_H_
#define ECRF_DECODER_MLP_H_

#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "decoder/mlp_gemm.h"
#include "format/scene_header.h"
#include "format/status.h"

namespace ecrf {
namespace dec {

struct MlpConfig {
  int num_products = 0;  // P: sum of the appearance ranks
  int feature_dim = 27;
  int feature_pe_freqs = 2;
  int viewdir_pe_freqs = 2;
  int hidden = 128;
  // 2: TensoRF's Linear(hidden) ReLU Linear(hidden) ReLU; 1: one Linear(hidden) ReLU, whose
  // output W3 reads (the MLPW layers field, SPEC.md 6.6, bitstream 1.8).
  int hidden_layers = 2;
  // hidden 0: no MLP, the features are spherical-harmonics coefficients (SPEC.md 7.6.2) of this
  // degree (-1: feature_dim fits none).
  int sh_degree() const { return ShDegreeForFeatureDim(feature_dim); }
  int input_dim() const {
    return feature_dim + 3 + 2 * feature_dim * feature_pe_freqs + 2 * 3 * viewdir_pe_freqs;
  }
};

// Limits checked by Init.
inline constexpr int kMaxMlpProducts = 3 * 1024;
inline constexpr int kMaxMlpFeatureDim = kMaxSceneFeatureDim;
inline constexpr int kMaxMlpPeFreqs = kMaxScenePeFreqs;
inline constexpr int kMaxMlpHidden = kMaxSceneHidden;

class AppearanceMlp {
 public:
  AppearanceMlp() = default;
  ~AppearanceMlp();
  AppearanceMlp(const AppearanceMlp&) = delete;
  AppearanceMlp& operator=(const AppearanceMlp&) = delete;
  AppearanceMlp(AppearanceMlp&& o) noexcept;
  AppearanceMlp& operator=(AppearanceMlp&& o) noexcept;

  // Validates the widths and allocates zero weights; picks the widest GEMM kernel the CPU runs.
  Status Init(const MlpConfig& config);
  // Another kernel (all give bit-identical results, decoder/mlp_gemm.h): for tests and benchmarks.
  // kErrInvalidArgument when this build or CPU lacks it.
  Status UseGemmKernel(GemmKernel kernel);
  GemmKernel gemm_kernel() const { return kernel_; }
  bool initialized() const { return weights_ != nullptr; }
  const MlpConfig& config() const { return config_; }

  // Number of floats in the trainer's flat layout (trainer/model/appearance_head.h): basis [F x P],
  // W1 [H x in], b1 [H], W2 [H x H], b2 [H], W3 [3 x H], b3 [3]; row-major (out x in); no W2, b2
  // with one hidden layer.
  size_t num_params() const;
  // Loads weights from that layout (count must equal num_params()); rejects non-finite values.
  Status SetParams(const float* params, size_t count);
  // The parameters back in that layout, exactly as loaded (the checksum of SPEC.md 6.5).
  Status GetParams(float* params, size_t count) const;

  // Scratch floats Infer needs (independent of the number of rows).
  size_t ScratchFloats() const;
  // rgb[r*3 + c] for `rows` rows: products row r at products + r * products_stride (P floats),
  // viewdir row r at viewdirs + r * 3 (unit vectors). scratch: ScratchFloats() floats, 32-byte
  // alignment recommended. Processes kChunkRows rows at a time so activations stay in cache.
  // Returns how many positional-encoding arguments fell outside FastSinCos's fast range (the
  // renderer charges them what the library sin and cos cost: kWideSinCosWork).
  uint64_t Infer(int rows, const float* products, size_t products_stride, const float* viewdirs,
                 float* rgb, float* scratch) const;

  static constexpr int kChunkRows = 32;

 private:
  void Release();
  // hidden 0: rgb of n rows of features (stride fd_pad_) by the spherical harmonics of 7.6.2.
  void ShColour(int n, const float* feat, const float* viewdirs, float* rgb) const;
  MlpConfig config_;
  int fd_pad_ = 0, hid_pad_ = 0, in_dim_ = 0, in_stride_ = 0;
  // One allocation: basis_t [P x fd_pad], w1_t [in x hid_pad], b1 [hid_pad], w2_t [H x hid_pad],
  // b2 [hid_pad], w3_t [H x 8], b3 [8], zero bias [fd_pad].
  GemmKernel kernel_ = GemmKernel::kPortable;
  Gemm8Fn gemm8_ = nullptr;
  float* weights_ = nullptr;
  size_t weights_count_ = 0;
  size_t o_basis_ = 0, o_w1_ = 0, o_b1_ = 0, o_w2_ = 0, o_b2_ = 0, o_w3_ = 0, o_b3_ = 0,
         o_zero_ = 0;
};

// s[i] = sin(x[i]), c[i] = cos(x[i]); absolute error ~1e-7 for |x| <= 8192 (Cody-Waite reduction
// and minimax polynomials, branch-free so it vectorises), std::sin/std::cos beyond. Returns how
// many x took that slower path (|x| > 8192 or not finite).
int FastSinCos(const float* x, int count, float* s, float* c);

}  // namespace dec
}  // namespace ecrf

#endif  // ECRF_DECODER_MLP_H_
