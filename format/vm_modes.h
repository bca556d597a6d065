// The axis pairing of the VM decomposition (SPEC.md 4.3), one rule for the bitstream, the
// decoder and the trainer: plane m spans u = kMatMode[m][0] (columns) and v = kMatMode[m][1]
// (rows); line m spans w = kVecMode[m], the axis the plane leaves out.
#ifndef ECRF_FORMAT_VM_MODES_H_
#define ECRF_FORMAT_VM_MODES_H_

namespace ecrf {

inline constexpr int kMatMode[3][2] = {{0, 1}, {0, 2}, {1, 2}};
inline constexpr int kVecMode[3] = {2, 1, 0};

}  // namespace ecrf

#endif  // ECRF_FORMAT_VM_MODES_H_
