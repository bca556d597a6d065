// How a must-reject stream (tests/conformance/reject/, SPEC.md 7.7) is checked against the
// reference decoder at its default budgets: a "decode"-stage stream fails to decode, a
// "render"-stage one decodes and its renderer refuses it when prepared. format/ and decoder/ only,
// so the portable checksum program (tests/decoder/conformance_checksums.cc) uses it too.
#ifndef ECRF_CONFORMANCE_REJECT_CHECK_H_
#define ECRF_CONFORMANCE_REJECT_CHECK_H_

#include <cstddef>
#include <cstdint>
#include <string>

#include "decoder/ray_marcher.h"
#include "decoder/scene_decoder.h"
#include "format/status.h"

namespace ecrf {
namespace conformance {

struct RejectOutcome {
  bool at_expected_stage = false;  // decoded (or not) as the stage says
  Status status;                   // the refusal (or Ok when nothing refused the stream)
  bool RefusedWith(int code) const { return at_expected_stage && status.code() == code; }
};

inline RejectOutcome CheckReject(const uint8_t* bytes, size_t size, const std::string& stage) {
  const bool at_render = stage == "render";
  dec::SceneField field;
  RejectOutcome out;
  out.status = dec::DecodeScene(bytes, size, dec::DecodeOptions(), &field, nullptr);
  out.at_expected_stage = at_render == out.status.ok();
  if (out.status.ok() && at_render) {
    dec::RayMarcher marcher;
    out.status = marcher.Init(&field, dec::RenderOptions());
  }
  return out;
}

}  // namespace conformance
}  // namespace ecrf

#endif  // ECRF_CONFORMANCE_REJECT_CHECK_H_
