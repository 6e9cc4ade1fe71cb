// Internal: camera placement of the hands and the static background of a scene.
#pragma once

#include <vector>

#include "dynahand/synth.h"
#include "dynahand/synth_render.h"

namespace dynahand::synth::detail {

// The right hand's rest pose (forearm body frame: x radial, y dorsal, z distal, origin at
// the wrist) in the camera frame, for a hand at `handDistance` m.
Pose restPlacement(CameraPlacement placement, float handDistance);

// Where the upper arm of a hand meets the body, camera frame (m), for a hand at `handDistance`:
// below and beside a head-mounted camera (the right shoulder to the right of the eyes); below
// the view and behind the hand of a desk camera facing the user.
Vec3 shoulderPosition(CameraPlacement placement, bool leftHand, float handDistance);

// World "down" in the camera frame (unit).
Vec3 downDirection(CameraPlacement placement);

// Static background of the scene: planes (wall, table) and solids (torso).
struct SceneGeometry {
  std::vector<Plane> planes;
  std::vector<RoundCone> solids;
};
SceneGeometry sceneGeometry(const Scene& scene, float handDistance);

// Draws the scene's held object (none: nothing) against the palm of the hand whose keypoints
// are given (MediaPipe order, camera frame), labelled PixelLabel::HeldObject. `scale`: the
// hand's size relative to the reference hand (the palm's thickness scales with it).
void drawHeldObject(const Scene& scene, const HandKeypoints& keypoints, bool leftHand, float scale,
                    DepthRenderer& renderer);

// The hand distance the scene uses for a profile (resolves handDistance = 0).
float resolvedHandDistance(const Scene& scene, const SensorProfile& profile);

}  // namespace dynahand::synth::detail
