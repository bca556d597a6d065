// What a capture's cameras say about its scene: the region of interest (where the views meet)
// and the scene model that suits the layout (a bounded object, or an unbounded scene whose
// surroundings are contracted, SPEC.md 7.2.1).
#ifndef ECRF_TRAINER_DATA_SCENE_FIT_H_
#define ECRF_TRAINER_DATA_SCENE_FIT_H_

#include <string>
#include <vector>

#include "format/ndc_frame.h"
#include "format/scene_header.h"
#include "trainer/data/aabb.h"
#include "trainer/data/camera.h"
#include "trainer/data/dataset.h"
#include "trainer/data/named_choice.h"

namespace ecrf::trainer {

// The share of the cameras that must see a point for it to belong to the region of interest.
inline constexpr double kRoiViewShare = 0.9;
// The fitted box grows by this share of its extent on each side.
inline constexpr double kRoiMargin = 0.1;
// A fitted box holding at least this share of the dataset box's volume means the box already
// is the object's: the object model keeps it.
inline constexpr double kObjectRoiShare = 0.25;

// The box of the points of `box` that at least kRoiViewShare of the cameras see (in front of the
// camera, inside its image, lens distortion applied), on a 64^3 lattice and then on a 64^3
// lattice over what the first found, grown by kRoiMargin of its extent and one step of the second
// lattice: where the frusta meet. `box` itself when fewer than 8 lattice
// points qualify.
Aabb FitRegionOfInterest(const std::vector<Camera>& cameras, const double box[2][3]);

// True when every camera looks within 35 degrees of their mean viewing direction (an LLFF-style
// forward-facing capture).
bool CamerasFaceOneWay(const std::vector<Camera>& cameras);

// TensoRF's NDC near plane on LLFF data is 0.75 of the nearest depth bound; loaders give `near`
// as 0.9 of it (trainer/data/llff.h), so the plane is this share of the dataset's near.
inline constexpr double kNdcNearShare = 0.75 / 0.9;
// The NDC box grows by this share of its x and y extents on each side.
inline constexpr double kNdcBoxMargin = 0.05;

// The NDC frame of a forward-facing capture: the reference camera is the cameras' average pose
// (NeRF's poses_avg: mean centre, mean viewing axis, mean up orthogonalised), its scale 2 f / size
// the cameras' mean, its near plane kNdcNearShare * near.
NdcFrame FitNdcFrame(const std::vector<Camera>& cameras, double near);

// The NDC box every training ray passes through: x and y from the image corners of every camera
// at NDC z = -1 and z = 1, grown by kNdcBoxMargin; z is [-1, 1] (the near plane to infinity).
Aabb FitNdcBox(const std::vector<Camera>& cameras, const NdcFrame& frame);

// The scene model a run asks for (--scene-type).
enum class SceneType { kAuto, kObject, kUnbounded, kForward };
template <>
struct ChoiceNames<SceneType> {
  static constexpr const char* what = "scene type";
  static constexpr const char* names[] = {"auto", "object", "unbounded", "forward"};
};

// Whether a run asking for `scene_type` models its scene as forward-facing (NDC): when asked to,
// or under kAuto when the background is not white and every camera looks one way
// (CamerasFaceOneWay). FitScene and the choice of the default preset both ask this.
bool ModelsForwardFacing(SceneType scene_type, bool white_background,
                         const std::vector<Camera>& cameras);

struct SceneFit {
  SceneModel model = SceneModel::kObject;
  NdcFrame ndc;            // forward: the reference camera; roi is then the NDC box
  Aabb roi;                // the fitted region of interest
  double roi_share = 1.0;  // its volume over the dataset box's
  bool forward_facing = false;
  std::string reason;  // why this model (for the log)
};

// SceneType::kAuto chooses from the layout: the object model for white-background datasets
// (Blender) and boxes the views already fill (roi_share >= kObjectRoiShare), the forward-facing
// model when every camera looks one way (CamerasFaceOneWay), the unbounded model otherwise.
// The other types force their model.
SceneFit FitScene(SceneType scene_type, const Dataset& data);

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_DATA_SCENE_FIT_H_
