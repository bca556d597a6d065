// Block DCT of the VM feature tensors (the planes and lines of a grid), with its adjoint for
// training.
//
// A tensor is viewed through three "block axes" (a0, a1, a2), each with a logical extent and a
// memory stride; a block is an n0 x n1 x n2 tile over them, transformed by the orthonormal DCT of
// format/coefficients/float_dct.h and stored in raster order [n0][n1][n2] (n2 fastest):
//   plane m ([res[v]][res[u]][rank], channels-last): a0 = channel, a1 = v (H), a2 = u (W);
//                                                   default block 16 x 16 x 16.
//   line m  ([res[w]][rank]):                        a0 = (none, extent 1), a1 = channel,
//                                                   a2 = position along w; default block 1 x 8 x 8.
// Blocks are numbered in raster order over the block grid: id = (b0 * blocks[1] + b1) * blocks[2]
// + b2, and coefficient arrays hold the blocks one after another (block id order, or the order
// of an explicit block list).
//
// Padding: an extent that is not a multiple of the block length is padded to blocks[a] * n[a] by
// EDGE REPLICATION (index i >= extent reads element extent-1, independently per axis, so a
// corner replicates the corner element). A smooth continuation costs fewer bits than zeros; the
// decoder crops the padded positions, so the rule only affects the rate. The encoder and SPEC use
// the same rule. Adjoint: a padded copy adds its gradient to the edge element it replicates.
//
// All block loops run in parallel (OpenMP). Every tensor element lies in exactly one block (the
// replicated edge lies in the last block of its axis), so backward accumulation needs no atomics.
// Functions must not be called from inside an OpenMP parallel region that expects them to run
// in parallel (nested regions run serially).
#ifndef ECRF_ENCODER_GRID_DCT_H_
#define ECRF_ENCODER_GRID_DCT_H_

#include <array>
#include <cstddef>

namespace ecrf {
namespace encoder {

struct GridBlockLayout {
  int block[3] = {1, 1, 1};    // n0, n1, n2 (IsValidBlockShape)
  int extent[3] = {1, 1, 1};   // logical extent along each block axis (>= 1)
  long stride[3] = {0, 0, 0};  // memory stride (elements) of each block axis in the tensor
  int blocks[3] = {0, 0, 0};   // blocks per axis: ceil(extent / block)
  int padded[3] = {0, 0, 0};   // blocks[a] * block[a]

  int num_blocks() const { return blocks[0] * blocks[1] * blocks[2]; }
  int block_volume() const { return block[0] * block[1] * block[2]; }
  size_t num_coeffs() const { return static_cast<size_t>(num_blocks()) * block_volume(); }
  size_t tensor_size() const { return static_cast<size_t>(extent[0]) * extent[1] * extent[2]; }
};

// Generic layout; throws std::invalid_argument on an invalid block shape or extent.
GridBlockLayout MakeBlockLayout(const int extent[3], const long stride[3], const int block[3]);
// Plane m of a grid with resolution res and rank `rank`: extent {rank, res[v], res[u]}.
GridBlockLayout PlaneBlockLayout(const std::array<int, 3>& res, int rank, int m,
                                 const int block[3]);
// Line m: extent {1, rank, res[w]}; block[0] must be 1.
GridBlockLayout LineBlockLayout(const std::array<int, 3>& res, int rank, int m, const int block[3]);

// coeffs[num_coeffs()] = DCT of every (edge-padded) block.
void ForwardBlocks(const float* tensor, const GridBlockLayout& layout, float* coeffs);
// dl_dtensor += pad^T(DCT^T(dl_dcoeffs)): the gradient of ForwardBlocks (accumulates).
void BackwardBlocks(const float* dl_dcoeffs, const GridBlockLayout& layout, float* dl_dtensor);
// tensor = crop(DCT^-1(coeffs)): the reconstruction (overwrites the logical elements; padded
// positions are dropped).
void InverseBlocks(const float* coeffs, const GridBlockLayout& layout, float* tensor);

// out = crop(DCT^-1(Q(DCT(pad(tensor))))), Q the encoder's quantizer (coef_quantizer.h) with
// this step: what the file's grid decodes to before the integer transform's rounding, as
// quantization-aware training needs it. ForwardBlocks, QuantizeLevel * step and InverseBlocks
// give the same values; this runs them block by block. out may not alias tensor.
void QuantizeBlocks(const float* tensor, const GridBlockLayout& layout, double step,
                    double rounding_offset, float* out);

// Subset versions: block_ids[0..count) (distinct ids in [0, num_blocks())); coeffs holds
// count * block_volume() values in list order.
void ForwardBlockList(const float* tensor, const GridBlockLayout& layout, const int* block_ids,
                      int count, float* coeffs);
void BackwardBlockList(const float* dl_dcoeffs, const GridBlockLayout& layout, const int* block_ids,
                       int count, float* dl_dtensor);

}  // namespace encoder
}  // namespace ecrf

#endif  // ECRF_ENCODER_GRID_DCT_H_
