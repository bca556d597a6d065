#include "format/coefficients/coef_contexts.h"

#include <algorithm>

#include "format/entropy/range_coder.h"

namespace ecrf {

Status CoefContexts::Init(const BlockShape& shape, CoefContextSet context_set) {
  ECRF_CHECK_OR_RETURN(IsValidBlockShape(shape), kErrInvalidArgument,
                       "invalid coefficient block shape %dx%dx%d", shape.n0, shape.n1, shape.n2);
  BuildScanTable(shape, &scan);
  set = context_set;
  num_eob_classes = 1 + (31 - __builtin_clz(static_cast<uint32_t>(shape.Volume())));
  levels.assign(static_cast<size_t>(scan.padded_volume), 0);
  Reset();
  return Status::Ok();
}

void CoefContexts::Reset() {
  std::fill(levels.begin(), levels.end(), uint8_t{0});
  prev_coded[0] = prev_coded[1] = 0;
  escape_stat = 0;
  for (auto& cdf : coded_cdf) InitUniformCdf(cdf, 2);
  InitUniformCdf(eob_class_cdf, num_eob_classes > 1 ? num_eob_classes : 2);
  for (auto& cdf : eob_extra_cdf) InitUniformCdf(cdf, 2);
  for (auto& cdf : last_base_cdf) InitUniformCdf(cdf, kLastBaseSymbols);
  for (auto& cdf : base_cdf) InitUniformCdf(cdf, kBaseSymbols);
  for (auto& cdf : range_cdf) InitUniformCdf(cdf, kRangeSymbols);
}

}  // namespace ecrf
