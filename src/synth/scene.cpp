// Camera placements and background geometry (docs/synth.md, "Scene").
#include "scene.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace dynahand::synth {

const char* heldObjectName(HeldObject object) {
  switch (object) {
    case HeldObject::Ball:
      return "ball";
    case HeldObject::Cylinder:
      return "cylinder";
    case HeldObject::Box:
      return "box";
    case HeldObject::None:
      break;
  }
  return "none";
}

}  // namespace dynahand::synth

namespace dynahand::synth::detail {
namespace {

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;
constexpr float kHeadMountedPitch = 35.0f * kDeg;  // camera looking down, rad
constexpr float kDeskForearmTilt =
    15.0f * kDeg;  // elbow further from the camera than the wrist, rad

Quat fromAxes(const Vec3& x, const Vec3& y, const Vec3& z) {
  Mat3 m;
  m.col(0) = x;
  m.col(1) = y;
  m.col(2) = z;
  return Quat(m).normalized();
}

// World-horizontal forward (away from the eyes) in the head-mounted camera's frame.
Vec3 headForward() {
  return Vec3(0.0f, -std::sin(kHeadMountedPitch), std::cos(kHeadMountedPitch));
}

}  // namespace

Vec3 downDirection(CameraPlacement placement) {
  if (placement == CameraPlacement::HeadMounted)
    return Vec3(0.0f, std::cos(kHeadMountedPitch), std::sin(kHeadMountedPitch));
  return Vec3::UnitY();
}

Pose restPlacement(CameraPlacement placement, float handDistance) {
  Pose pose;
  if (placement == CameraPlacement::DeskFacing) {
    // Palm toward the camera, fingers up: radial = +x, dorsal = +z (away), distal = -y (up);
    // tilted so the forearm runs down and away, entering from the bottom border.
    const Quat upright = fromAxes(Vec3::UnitX(), Vec3::UnitZ(), -Vec3::UnitY());
    pose.q = (Quat(Eigen::AngleAxisf(kDeskForearmTilt, Vec3::UnitX())) * upright).normalized();
    pose.p = Vec3(0.0f, 0.07f, handDistance);
  } else {
    // Palm down, fingers forward, seen from behind and above: the back of the hand faces
    // the camera and the forearm comes up from the bottom border.
    const Vec3 forward = headForward();
    const Vec3 dorsal = -downDirection(placement);
    pose.q = fromAxes(dorsal.cross(forward), dorsal, forward);
    pose.p = Vec3(0.0f, 0.06f, handDistance);
  }
  return pose;
}

Vec3 shoulderPosition(CameraPlacement placement, bool leftHand, float handDistance) {
  if (placement == CameraPlacement::DeskFacing) {
    // The user faces the camera: the right shoulder is on the image's left, below the view and
    // behind the hand.
    constexpr float kShoulderBelowAxis = 0.45f;   // m
    constexpr float kShoulderBeside = 0.18f;      // m
    constexpr float kShoulderBehindHand = 0.30f;  // m
    return Vec3(leftHand ? kShoulderBeside : -kShoulderBeside, kShoulderBelowAxis,
                handDistance + kShoulderBehindHand);
  }
  constexpr float kShoulderBelowEyes = 0.25f;   // m
  constexpr float kShoulderBesideEyes = 0.18f;  // m, toward the hand's side
  constexpr float kShoulderBehindEyes = 0.05f;  // m
  const float side = leftHand ? -kShoulderBesideEyes : kShoulderBesideEyes;
  return Vec3(side, 0.0f, 0.0f) + kShoulderBelowEyes * downDirection(placement) -
         kShoulderBehindEyes * headForward();
}

float resolvedHandDistance(const Scene& scene, const SensorProfile& profile) {
  return scene.handDistance > 0.0f ? scene.handDistance : std::max(0.40f, profile.minRange + 0.2f);
}

void drawHeldObject(const Scene& scene, const HandKeypoints& keypoints, bool leftHand, float scale,
                    DepthRenderer& renderer) {
  if (scene.heldObject == HeldObject::None) return;
  // The palm's frame: along it (wrist to middle knuckle), across it (little to index knuckle),
  // and its palmar normal.
  const Vec3 along = (keypoints[9] - keypoints[0]).normalized();
  Vec3 across = keypoints[5] - keypoints[17];
  across = (across - across.dot(along) * along).normalized();
  Vec3 palmar = across.cross(along);
  if (leftHand) palmar = -palmar;
  // The palm's skin lies about its half-thickness (12.5 mm for the reference hand) plus a
  // little padding from the bones the keypoints sit on.
  constexpr float kPalmSkinM = 0.015f;
  constexpr float kHalfLengthM = 0.06f;  // the cylinder's and the box's half-length
  const float size = scene.heldObjectSize;
  const Vec3 centre = 0.5f * (keypoints[0] + keypoints[9]) + palmar * (size + kPalmSkinM * scale);
  switch (scene.heldObject) {
    case HeldObject::Ball: {
      const RoundCone ball{centre, centre, size, size};
      renderer.draw(std::span(&ball, 1), PixelLabel::HeldObject);
      break;
    }
    case HeldObject::Cylinder: {
      const RoundCone cylinder{centre - kHalfLengthM * across, centre + kHalfLengthM * across, size,
                               size};
      renderer.draw(std::span(&cylinder, 1), PixelLabel::HeldObject);
      break;
    }
    case HeldObject::Box: {
      OrientedBox box;
      box.centre = centre;
      box.axes.col(0) = across;
      box.axes.col(1) = palmar;
      box.axes.col(2) = across.cross(palmar);
      box.halfExtents = Vec3(kHalfLengthM, size, size);
      renderer.draw(box, PixelLabel::HeldObject);
      break;
    }
    case HeldObject::None:
      break;
  }
}

SceneGeometry sceneGeometry(const Scene& scene, float handDistance) {
  SceneGeometry g;
  const float behind = handDistance + scene.backgroundDistance;
  if (scene.background == Background::Wall) g.planes.push_back(Plane{Vec3::UnitZ(), behind});
  if (scene.background == Background::Torso) {
    // A standing torso: an upright, slightly tapered capsule, its front surface `behind` away.
    constexpr float kTorsoRadius = 0.16f;
    g.solids.push_back(RoundCone{Vec3(0.0f, -0.35f, behind + kTorsoRadius),
                                 Vec3(0.0f, 0.60f, behind + kTorsoRadius), kTorsoRadius,
                                 1.1f * kTorsoRadius});
  }
  if (scene.table) {
    const Vec3 down = downDirection(scene.placement);
    const Vec3 wrist = restPlacement(scene.placement, handDistance).p;
    g.planes.push_back(Plane{down, down.dot(wrist) + scene.tableDrop});
  }
  return g;
}

}  // namespace dynahand::synth::detail
