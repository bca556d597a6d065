#include "format/coefficients/coef_scan.h"

#include <cstddef>

namespace ecrf {

bool IsValidBlockShape(const BlockShape& shape) {
  return IsValidBlockLength(shape.n0) && IsValidBlockLength(shape.n1) &&
         IsValidBlockLength(shape.n2) && shape.Volume() <= kMaxBlockVolume;
}

int BaseBand(int frequency_sum) {
  if (frequency_sum <= 2) return frequency_sum;
  if (frequency_sum <= 4) return 3;
  if (frequency_sum <= 7) return 4;
  if (frequency_sum <= 11) return 5;
  return 6;
}

int RangeBand(int frequency_sum) {
  if (frequency_sum == 0) return 0;
  return frequency_sum <= 3 ? 1 : 2;
}

std::vector<uint16_t> ComputeScanOrder(const BlockShape& shape) {
  // Counting sort by frequency sum: stable, so ties keep raster order.
  const int max_sum = shape.n0 + shape.n1 + shape.n2 - 3;
  std::vector<int> start(static_cast<size_t>(max_sum) + 2, 0);
  for (int i = 0; i < shape.n0; ++i) {
    for (int j = 0; j < shape.n1; ++j) {
      for (int k = 0; k < shape.n2; ++k) ++start[static_cast<size_t>(i + j + k) + 1];
    }
  }
  for (size_t s = 1; s < start.size(); ++s) start[s] += start[s - 1];
  std::vector<uint16_t> order(static_cast<size_t>(shape.Volume()));
  int raster = 0;
  for (int i = 0; i < shape.n0; ++i) {
    for (int j = 0; j < shape.n1; ++j) {
      for (int k = 0; k < shape.n2; ++k, ++raster) {
        order[static_cast<size_t>(start[static_cast<size_t>(i + j + k)]++)] =
            static_cast<uint16_t>(raster);
      }
    }
  }
  return order;
}

void BuildScanTable(const BlockShape& shape, ScanTable* table) {
  table->shape = shape;
  table->padded_stride1 = shape.n2 + 2;
  table->padded_stride0 = (shape.n1 + 2) * table->padded_stride1;
  table->padded_volume = (shape.n0 + 2) * table->padded_stride0;
  const std::vector<uint16_t> order = ComputeScanOrder(shape);
  table->entries.resize(order.size());
  for (size_t s = 0; s < order.size(); ++s) {
    const int raster = order[s];
    const int k = raster % shape.n2;
    const int j = (raster / shape.n2) % shape.n1;
    const int i = raster / (shape.n2 * shape.n1);
    ScanEntry& e = table->entries[s];
    e.raster = static_cast<uint16_t>(raster);
    e.padded = static_cast<uint16_t>(i * table->padded_stride0 + j * table->padded_stride1 + k);
    e.base_band = static_cast<uint8_t>(BaseBand(i + j + k));
    e.range_band = static_cast<uint8_t>(RangeBand(i + j + k));
  }
}

}  // namespace ecrf
