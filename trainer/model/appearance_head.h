// AppearanceHead: TensoRF's "MLP_Fea" colour decoder, from appearance-plane/line products to RGB.
//
// products (P = total appearance rank, 144 for VM-192) -> basis matrix (P x 27, no bias)
// -> [features 27, viewdir 3, PE(features, 2 freqs), PE(viewdir, 2 freqs)] = 150
// -> Linear 128 -> ReLU -> Linear 128 -> ReLU -> Linear 3 -> sigmoid (hidden_layers 1: without the
// second Linear 128 -> ReLU).
// PE(x, F) follows TensoRF's positional_encoding: for each input channel c and frequency f the
// argument x_c * 2^f (c-major), then all sines followed by all cosines.
//
// Whole batches go through at once so every layer is one GEMM; Forward keeps what Backward needs.
#ifndef ECRF_TRAINER_MODEL_APPEARANCE_HEAD_H_
#define ECRF_TRAINER_MODEL_APPEARANCE_HEAD_H_

#include <cstddef>
#include <cstdint>
#include <vector>

#include "format/mlp_coder.h"  // HeadKind

namespace ecrf {
namespace trainer {

struct AppearanceHeadConfig {
  int num_products = 144;  // P: input width (sum of the appearance ranks over the 3 modes)
  int feature_dim = 27;    // basis output width
  int feature_pe_freqs = 2;
  int viewdir_pe_freqs = 2;
  int hidden = 128;
  // 2: TensoRF's two hidden layers; 1: one (no W2, b2; W3 reads the first layer), about half the
  // multiply-adds (the MLPW layers byte, SPEC.md 6.6, bitstream 1.8).
  int hidden_layers = 2;
  // kPerSample: Forward sees one row per coloured sample; kDeferred: one row per ray, the sum of
  // its coloured samples' products weighted by their weights (SPEC.md 7.6; volume_render.cc).
  // The head's arithmetic is the same; only what its rows are differs.
  HeadKind kind = HeadKind::kPerSample;
};

// The head with spherical-harmonics colour of this degree (hidden 0, SPEC.md 7.6.2): 3 (D + 1)^2
// features, no positional encoding, no MLP; `base` gives the products and the kind.
inline AppearanceHeadConfig ShHeadConfig(AppearanceHeadConfig base, int degree) {
  base.hidden = 0;
  base.hidden_layers = 2;  // no MLP; 2 is the stream's value for that (SPEC.md 6.6)
  base.feature_dim = 3 * (degree + 1) * (degree + 1);
  base.feature_pe_freqs = 0;
  base.viewdir_pe_freqs = 0;
  return base;
}

// All parameters in one flat float array so Adam and checkpoints treat them uniformly.
// Layout (row-major, out x in): basis [feature_dim x P], W1 [hidden x in], b1 [hidden],
// W2 [hidden x hidden], b2 [hidden], W3 [3 x hidden], b3 [3]; W2 and b2 empty with one layer.
class AppearanceHead {
 public:
  explicit AppearanceHead(const AppearanceHeadConfig& config);

  const AppearanceHeadConfig& config() const { return config_; }
  // Where the head runs from now on (the weights stay: --head auto, train/head_choice.h).
  void set_kind(HeadKind kind) { config_.kind = kind; }
  int mlp_input_dim() const;  // 150 for the defaults

  // PyTorch default init (kaiming-uniform-like U(-1/sqrt(in), 1/sqrt(in)) for weights and biases,
  // basis too, last-layer bias 0), deterministic for a seed.
  void Initialize(uint32_t seed);

  std::vector<float>& params() { return params_; }
  const std::vector<float>& params() const { return params_; }
  std::vector<float>& grads() { return grads_; }
  void ZeroGrads();

  // Offsets of each tensor inside params() (for export to the bitstream).
  size_t basis_offset() const;
  size_t w1_offset() const;
  size_t b1_offset() const;
  size_t w2_offset() const;
  size_t b2_offset() const;
  size_t w3_offset() const;
  size_t b3_offset() const;

  // products: n x P row-major; viewdirs: n x 3 (unit vectors); rgb: n x 3 in (0,1).
  // Keeps the activations of this batch for Backward (training). Threads with OpenMP/Eigen.
  void Forward(int n, const float* products, const float* viewdirs, float* rgb);
  // Inference only: no activations kept, processes in cache-sized chunks.
  void Infer(int n, const float* products, const float* viewdirs, float* rgb) const;
  // Given dL/drgb (n x 3) for the batch of the last Forward: adds parameter gradients into
  // grads() and writes dL/dproducts (n x P). viewdirs get no gradient (they are inputs).
  void Backward(int n, const float* dl_drgb, float* dl_dproducts);

  // --- Additions (not in the original interface) ---
  size_t num_params() const { return params_.size(); }
  // Indices into params() of the values a head keeping only the inputs (products) with
  // keep[p] != 0 holds, in its own order (keep has num_products entries): every MLP parameter and
  // the kept columns of the basis. Select the same positions of an optimizer's moments.
  std::vector<size_t> KeptIndices(const std::vector<uint8_t>& keep) const;
  // Removes the basis columns of the inputs with keep[p] == 0 (the appearance components a
  // pruned grid no longer has); num_products shrinks. Grads are re-allocated (zero).
  void KeepProducts(const std::vector<uint8_t>& keep);
  // The same for hidden units: keep1[i] for unit i of the first hidden layer (its row of W1 and
  // b1, its column of W2), keep2[j] for unit j of the second (its row of W2 and b2, its column
  // of W3). The stream has one width for both layers (SPEC.md 6.2), so both keep as many. With one
  // hidden layer keep2 must equal keep1 (W3's columns are the first layer's units).
  std::vector<size_t> KeptHiddenIndices(const std::vector<uint8_t>& keep1,
                                        const std::vector<uint8_t>& keep2) const;
  void KeepHidden(const std::vector<uint8_t>& keep1, const std::vector<uint8_t>& keep2);
  // Off by default: Forward copies `products` for Backward's dL/dbasis. When on, Forward only
  // keeps the pointer, and the caller must keep that buffer alive and unchanged until Backward
  // (saves n * P floats of memory and their copy). Takes effect at the next Forward.
  void set_borrow_products(bool borrow) { borrow_products_ = borrow; }
  // Rows per unit of work (each OpenMP thread runs its rows through all layers chunk by chunk
  // so they stay in cache). Tuning knob for benchmarks; default 256.
  void set_chunk_rows(int rows) { chunk_rows_ = rows < 16 ? 16 : rows; }
  int chunk_rows() const { return chunk_rows_; }

 private:
  struct Activations;
  Activations ActivationsFor(int n, bool products_borrowed);
  AppearanceHeadConfig config_;
  std::vector<float> params_;
  std::vector<float> grads_;
  std::vector<float> scratch_;  // activations of the last Forward (reused, no per-call allocation)
  std::vector<float> transposed_;      // the weights transposed for Forward's GEMMs
  std::vector<float> thread_scratch_;  // per-thread chunk temporaries of Forward / Backward
  std::vector<float> slot_grads_;      // Backward's gradient partial sums, one per run of chunks
  int last_n_ = -1;                    // batch size of the last Forward (-1: none)
  bool borrow_products_ = false;
  bool last_borrowed_ = false;  // borrow_products_ as it was at the last Forward
  const float* borrowed_products_ = nullptr;
  int chunk_rows_ = 256;
};

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_MODEL_APPEARANCE_HEAD_H_
