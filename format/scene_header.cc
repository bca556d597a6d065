#include "format/scene_header.h"

#include <cmath>

#include "format/vm_modes.h"

namespace ecrf {
namespace {

Status ReadFinite(ByteReader* r, float* v, const char* what) {
  ECRF_RETURN_IF_ERROR(r->ReadF32(v, what));
  ECRF_CHECK_OR_RETURN(std::isfinite(*v), kErrCorrupt, "HEAD: %s is not finite", what);
  return Status::Ok();
}

}  // namespace

Status ParseSceneHeader(const uint8_t* payload, size_t size, int version_minor, SceneHeader* h) {
  const size_t expected = SceneHeaderBytes(version_minor);
  const bool newer = version_minor > kVersionMinor;  // its later fields: zero when unused
  ECRF_CHECK_OR_RETURN(
      size == expected || (newer && size > expected), kErrCorrupt,
      "HEAD: payload is %zu bytes, must be %zu%s with version_minor %d (SPEC.md 6.2)", size,
      expected, newer ? " or more" : "", version_minor);
  for (size_t k = expected; k < size; ++k) {
    ECRF_CHECK_OR_RETURN(payload[k] == 0, kErrUnsupported,
                         "HEAD: byte %zu is %u, a field of a version after 1.%d (the stream says "
                         "1.%d and needs a newer decoder)",
                         k, payload[k], kVersionMinor, version_minor);
  }
  ByteReader r(payload, size);
  for (float& v : h->aabb_min) ECRF_RETURN_IF_ERROR(ReadFinite(&r, &v, "aabb_min"));
  for (float& v : h->aabb_max) ECRF_RETURN_IF_ERROR(ReadFinite(&r, &v, "aabb_max"));
  for (int a = 0; a < 3; ++a) {
    ECRF_CHECK_OR_RETURN(
        h->aabb_max[a] > h->aabb_min[a] && std::isfinite(h->aabb_max[a] - h->aabb_min[a]),
        kErrCorrupt, "HEAD: aabb is empty or too wide on axis %d (%g, %g)", a,
        double(h->aabb_min[a]), double(h->aabb_max[a]));
  }
  for (int a = 0; a < 3; ++a) {
    ECRF_RETURN_IF_ERROR(r.ReadU16(&h->res[a], "grid resolution"));
    ECRF_CHECK_OR_RETURN(h->res[a] >= 2 && h->res[a] <= kMaxSceneGridRes, kErrLimit,
                         "HEAD: grid resolution %u on axis %d is outside [2, %d]", h->res[a], a,
                         kMaxSceneGridRes);
  }
  for (int g = 0; g < kNumSceneGrids; ++g) {
    for (int m = 0; m < 3; ++m) {
      ECRF_RETURN_IF_ERROR(r.ReadU16(&h->ranks[g][m], "rank"));
      ECRF_CHECK_OR_RETURN(h->ranks[g][m] <= kMaxSceneRank, kErrLimit,
                           "HEAD: %s rank %u of mode %d exceeds %d",
                           g == 0 ? "density" : "appearance", h->ranks[g][m], m, kMaxSceneRank);
    }
  }
  const uint64_t values = SceneGridValues(*h);
  ECRF_CHECK_OR_RETURN(values <= kMaxSceneGridValues, kErrLimit,
                       "HEAD: the grids hold %llu values, more than the limit of %llu",
                       static_cast<unsigned long long>(values),
                       static_cast<unsigned long long>(kMaxSceneGridValues));
  ECRF_RETURN_IF_ERROR(ReadFinite(&r, &h->density_shift, "density_shift"));
  ECRF_RETURN_IF_ERROR(ReadFinite(&r, &h->distance_scale, "distance_scale"));
  ECRF_CHECK_OR_RETURN(h->distance_scale >= 0.f, kErrCorrupt, "HEAD: distance_scale is negative");
  ECRF_RETURN_IF_ERROR(ReadFinite(&r, &h->step_size, "step_size"));
  ECRF_CHECK_OR_RETURN(h->step_size > 0.f, kErrCorrupt, "HEAD: step_size must be positive");
  ECRF_RETURN_IF_ERROR(r.ReadU32(&h->num_samples, "num_samples"));
  ECRF_CHECK_OR_RETURN(h->num_samples >= 1 && h->num_samples <= kMaxSceneSamples, kErrLimit,
                       "HEAD: num_samples %u is outside [1, %u]", h->num_samples, kMaxSceneSamples);
  ECRF_RETURN_IF_ERROR(ReadFinite(&r, &h->weight_threshold, "weight_threshold"));
  ECRF_CHECK_OR_RETURN(h->weight_threshold >= 0.f, kErrCorrupt,
                       "HEAD: weight_threshold is negative");
  ECRF_RETURN_IF_ERROR(ReadFinite(&r, &h->near_far[0], "near"));
  ECRF_RETURN_IF_ERROR(ReadFinite(&r, &h->near_far[1], "far"));
  ECRF_CHECK_OR_RETURN(h->near_far[0] <= h->near_far[1], kErrCorrupt, "HEAD: near > far");
  for (float& v : h->background) {
    ECRF_RETURN_IF_ERROR(ReadFinite(&r, &v, "background"));
    ECRF_CHECK_OR_RETURN(v >= 0.f && v <= 1.f, kErrCorrupt, "HEAD: background outside [0, 1]");
  }
  ECRF_RETURN_IF_ERROR(r.ReadU16(&h->feature_dim, "feature_dim"));
  ECRF_RETURN_IF_ERROR(r.ReadU8(&h->feature_pe_freqs, "feature_pe_freqs"));
  ECRF_RETURN_IF_ERROR(r.ReadU8(&h->viewdir_pe_freqs, "viewdir_pe_freqs"));
  ECRF_RETURN_IF_ERROR(r.ReadU16(&h->hidden, "hidden"));
  ECRF_CHECK_OR_RETURN(h->feature_dim >= 1 && h->feature_dim <= kMaxSceneFeatureDim, kErrLimit,
                       "HEAD: feature_dim %u is outside [1, %d]", h->feature_dim,
                       kMaxSceneFeatureDim);
  ECRF_CHECK_OR_RETURN(
      h->feature_pe_freqs <= kMaxScenePeFreqs && h->viewdir_pe_freqs <= kMaxScenePeFreqs, kErrLimit,
      "HEAD: positional-encoding frequencies exceed %d", kMaxScenePeFreqs);
  ECRF_CHECK_OR_RETURN(h->hidden <= kMaxSceneHidden, kErrLimit,
                       "HEAD: hidden width %u is outside [0, %d]", h->hidden, kMaxSceneHidden);
  if (h->hidden == 0) {  // spherical-harmonics colour: the basis output is its coefficients
    ECRF_CHECK_OR_RETURN(ShDegreeForFeatureDim(h->feature_dim) >= 0, kErrCorrupt,
                         "HEAD: hidden 0 (spherical harmonics) needs feature_dim 3 (D + 1)^2 for a "
                         "degree D <= %d (3, 12, 27 or 48), not %u",
                         kMaxShDegree, h->feature_dim);
    ECRF_CHECK_OR_RETURN(h->feature_pe_freqs == 0 && h->viewdir_pe_freqs == 0, kErrCorrupt,
                         "HEAD: hidden 0 (spherical harmonics) has no positional encoding, but "
                         "the frequencies are %u and %u",
                         h->feature_pe_freqs, h->viewdir_pe_freqs);
  }
  ECRF_CHECK_OR_RETURN(h->total_rank(1) >= 1, kErrCorrupt,
                       "HEAD: the appearance grid has no component (the MLP needs at least one)");
  ECRF_RETURN_IF_ERROR(r.ReadU8(&h->has_occupancy, "has_occupancy"));
  ECRF_CHECK_OR_RETURN(h->has_occupancy <= 1, kErrCorrupt, "HEAD: has_occupancy is %u",
                       h->has_occupancy);
  ECRF_RETURN_IF_ERROR(r.ReadU8(&h->scene_model, "scene_model"));
  ECRF_CHECK_OR_RETURN(
      h->scene_model < kNumSceneModels, kErrUnsupported,
      "HEAD: scene model %u is unknown (this decoder knows 0, object, 1, unbounded, and 2, "
      "forward-facing; "
      "the stream needs a newer decoder)",
      h->scene_model);
  // The unbounded model samples from `near` on with t only growing (7.2.1).
  ECRF_CHECK_OR_RETURN(
      h->scene_model != static_cast<uint8_t>(SceneModel::kUnbounded) || h->near_far[0] >= 0.f,
      kErrCorrupt, "HEAD: near is negative in an unbounded scene");
  h->density_activation = static_cast<uint8_t>(DensityActivation::kSoftplus);
  if (version_minor >= kDensityActivationMinVersionMinor) {
    ECRF_RETURN_IF_ERROR(r.ReadU8(&h->density_activation, "density_activation"));
    ECRF_CHECK_OR_RETURN(h->density_activation < kNumDensityActivations, kErrUnsupported,
                         "HEAD: density activation %u is unknown (this decoder knows 0, softplus, "
                         "and 1, relu; the stream needs a newer decoder)",
                         h->density_activation);
  }
  return Status::Ok();
}

uint64_t SceneGridValues(const SceneHeader& h) {
  uint64_t values = 0;
  for (int g = 0; g < kNumSceneGrids; ++g) {
    for (int m = 0; m < 3; ++m) {
      const uint64_t plane = uint64_t(h.res[kMatMode[m][0]]) * h.res[kMatMode[m][1]];
      values += (plane + h.res[kVecMode[m]]) * h.ranks[g][m];
    }
  }
  return values;
}

void SceneTensorExtent(const SceneHeader& h, int grid, int tensor, int extent[3]) {
  const int m = tensor % 3;
  const int rank = h.ranks[grid][m];
  if (tensor < 3) {
    extent[0] = rank;
    extent[1] = h.res[kMatMode[m][1]];
    extent[2] = h.res[kMatMode[m][0]];
  } else {
    extent[0] = 1;
    extent[1] = rank;
    extent[2] = h.res[kVecMode[m]];
  }
}

}  // namespace ecrf
