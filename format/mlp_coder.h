// Coding of the appearance MLP and basis matrix (the MLPW chunk, SPEC.md 6.6).
//
// Precision 2 ("quantized", bitstream 1.1) stores each weight matrix as integer levels with one
// binary16 step per output row: the rows of a layer differ in scale by orders of magnitude, one
// step per tensor would waste bits on the small rows. A level is coded as its magnitude class
// (bit length, adaptive: the class carries almost all of the information in a bell-shaped weight
// distribution), then the bits below the leading one and the sign in bypass. Contexts: the
// matrix (W1 split by input kind: features, view direction, their positional encodings, whose
// weights differ in size) and the previous class in the row. The three bias vectors stay binary16
// (259 values). The encoder (mlp_encoder.cc) and the decoder (mlp_decoder.cc) share the layout and
// contexts defined here.
#ifndef ECRF_FORMAT_MLP_CODER_H_
#define ECRF_FORMAT_MLP_CODER_H_

#include <cstddef>
#include <cstdint>
#include <vector>

#include "format/byte_io.h"
#include "format/entropy/range_coder.h"
#include "format/status.h"

namespace ecrf {

constexpr uint8_t kMlpPrecisionFloat16 = 0;
constexpr uint8_t kMlpPrecisionFloat32 = 1;
constexpr uint8_t kMlpPrecisionQuantized = 2;
// The container minor version a stream with a quantized MLP needs at least (the version rule of
// SPEC.md 2.1; kSceneModelMinVersionMinor and kWideContextsMinVersionMinor are the others).
constexpr uint8_t kQuantizedMlpMinVersionMinor = 1;

// Where the MLP runs (the MLPW `head` byte, SPEC.md 6.6 and 7.6). The weights and their coding are
// the same for both; the deferred head saves the per-sample MLP (most of a frame's work, and of a
// training step's) by compositing the appearance products along the ray first, which is exact
// for the basis (linear) and an approximation the trainer learns around for the MLP.
enum class HeadKind : uint8_t {
  kPerSample = 0,  // TensoRF: the MLP colours every sample whose weight passes the threshold
  kDeferred = 1,   // the weighted products of a ray's coloured samples, then the MLP once per ray
};
constexpr int kNumHeadKinds = 2;
// The container minor version a stream with this head needs at least (2.1).
constexpr uint8_t kHeadKindMinVersionMinor[kNumHeadKinds] = {0, 6};
// The names tools show and take (ecrf info, ecrf train --head), by head byte.
constexpr const char* kHeadKindNames[kNumHeadKinds] = {"mlp", "deferred"};
// Its name; "unknown" for other values.
inline const char* HeadKindName(HeadKind k) {
  const int i = static_cast<int>(k);
  return i < kNumHeadKinds ? kHeadKindNames[i] : "unknown";
}

// The MLPW `layers` byte (SPEC.md 6.6): how many hidden layers the MLP has. 0 stands for two
// (TensoRF's, every stream before 1.8, when the byte was reserved); 1 for one, without W2 and b2:
// about half the multiply-adds of a head of the same width (7.6).
constexpr uint8_t kMlpTwoHiddenLayers = 0;
constexpr uint8_t kMlpOneHiddenLayer = 1;
constexpr uint8_t kOneHiddenLayerMinVersionMinor = 8;
// The number of hidden layers a `layers` byte stands for (the byte is checked before).
inline int MlpHiddenLayers(uint8_t layers_byte) {
  return layers_byte == kMlpOneHiddenLayer ? 1 : 2;
}

// The head as tools name it (ecrf train --head, info, eval, metrics.json): with HEAD hidden 0 the
// colour is spherical harmonics (SPEC.md 7.6.2), "sh" once per ray as --head sh trains it.
constexpr const char* kShHeadName = "sh";
inline const char* AppearanceName(HeadKind k, int hidden) {
  if (hidden != 0) return HeadKindName(k);
  return k == HeadKind::kDeferred    ? kShHeadName
         : k == HeadKind::kPerSample ? "sh per sample"
                                     : "unknown";
}

// Magnitude classes: 0 for level 0, else the bit length of |level| (1 for 1, 2 for 2..3, 3 for
// 4..7, ...). Classes 0..14 are symbols of a 16-symbol alphabet; symbol 15 escapes to
// 15 + an Exp-Golomb value of order 0.
constexpr int kMlpClassEscape = 15;
// Largest level magnitude a stream may carry (class 24): every level converts exactly to binary32.
constexpr int kMlpMaxClass = 24;
constexpr int32_t kMlpMaxLevel = (1 << 24) - 1;
constexpr int kMlpContextGroups = 7;  // B, W1 x 4 input kinds, W2, W3

// The flat parameter array of 6.6: B [F][P], W1 [H][In], b1 [H], W2 [H][H], b2 [H], W3 [3][H], b3
// [3]; W2 and b2 only with two hidden layers.
struct MlpLayout {
  int feature_dim = 0;       // F
  int num_products = 0;      // P
  int hidden = 0;            // H
  int input_dim = 0;         // In = F + 3 + feature_pe_width + 2 * 3 * Fv
  int feature_pe_width = 0;  // 2 * F * Ff
  int hidden_layers = 2;     // 1: no W2, b2 (they have no row)
};

struct MlpMatrixSpan {
  size_t offset;  // first value in the flat array
  int rows;       // output channels (one step each)
  int cols;
};

// The layout of a head with these widths and positional-encoding frequencies (feature PE width
// 2*F*Ff, input width F + 3 + 2*F*Ff + 2*3*Fv) and 1 or 2 hidden layers.
MlpLayout MakeMlpLayout(int feature_dim, int num_products, int hidden, int feature_pe_freqs,
                        int viewdir_pe_freqs, int hidden_layers = 2);

// The four matrices (B, W1, W2, W3) and the three bias vectors (b1, b2, b3), in stream order;
// with one hidden layer W2 and b2 are empty (0 rows, 0 columns) and W3 reads the first layer.
void MlpMatrices(const MlpLayout& layout, MlpMatrixSpan matrices[4], MlpMatrixSpan biases[3]);
size_t MlpParamCount(const MlpLayout& layout);

// Adaptive class alphabets: [group][previous class bucket].
struct MlpLevelContexts {
  uint16_t level_class[kMlpContextGroups][3][kMlpClassEscape + 2];
  MlpLevelContexts();
};

// Context group of column `col` of matrix `matrix` (0 B, 1 W1, 2 W2, 3 W3): W1's columns are
// [features F | view direction 3 | feature PE 2*F*Ff | view PE], groups 1..4.
int MlpContextGroup(const MlpLayout& layout, int matrix, int col);
// Bucket of the previous class in the row (class 0 before the first level of a row).
inline int MlpClassBucket(int level_class) { return level_class < 3 ? 0 : level_class < 6 ? 1 : 2; }
// Bit length of a magnitude (0 for 0).
inline int MlpLevelClass(uint32_t magnitude) {
  int c = 0;
  while (magnitude >> c) ++c;
  return c;
}

// Quantizes `params` (MlpParamCount values) with max_level as the largest level of each row
// and returns the payload after the 4-byte precision/reserved header. The values the decoder
// will reconstruct are written to `reconstructed` when it is not null.
std::vector<uint8_t> EncodeQuantizedMlp(const MlpLayout& layout, const float* params, int max_level,
                                        std::vector<float>* reconstructed);

// The four bytes that open an MLPW payload (SPEC.md 6.6).
struct MlpChunkHeader {
  uint8_t precision = kMlpPrecisionFloat16;
  uint8_t head = 0;    // HeadKind
  uint8_t layers = 0;  // kMlpTwoHiddenLayers or kMlpOneHiddenLayer
};
// Reads them and checks them in the order of 6.6: the reserved byte, then each field's value
// (unsupported when unknown) and the version it needs (corrupt before it); one hidden layer
// needs an MLP (hidden > 0).
Status ReadMlpChunkHeader(ByteReader* r, int version_minor, int hidden, MlpChunkHeader* out);

// Decodes that payload into params_out (MlpParamCount values). Every step and bias must be a
// finite binary16; the level stream must end exactly where the payload ends.
Status DecodeQuantizedMlp(const MlpLayout& layout, const uint8_t* data, size_t size,
                          float* params_out);

}  // namespace ecrf

#endif  // ECRF_FORMAT_MLP_CODER_H_
