/// @file
/// Poses of an articulated model: per-body world poses <-> root pose + joint angles,
/// interpolation, keypoints (21 MediaPipe, 26 OpenXR) and pose sequences as JSON lines
/// (docs/formats/pose.md). Angle conventions: docs/model.md.
///
/// The *Into functions write into caller-owned buffers and do not allocate once the buffers
/// have the right size; the tracker calls them every step.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "dynahand/model.h"

namespace dynahand::model {

/// World pose of each body frame, indexed like model.bodies().
struct ModelPose {
  std::vector<Pose> bodies;  ///< world pose per body, by body index
};

/// The root body's world pose and, per joint (indexed like model.joints()), the angles
/// (flexion, abduction, twist), rad. The child's orientation is
/// parent * joint.frame * jointRotation(angles); see jointRotation for the convention.
struct JointAngles {
  Pose root;                 ///< the root body's world pose
  std::vector<Vec3> angles;  ///< (flexion, abduction, twist) per joint, rad
};

/// All angles zero (which may lie outside the limits), root at the identity.
JointAngles zeroAngles(const ArticulatedModel& model);
/// Each angle clamped into its joint's [min, max].
void clampToLimits(const ArticulatedModel& model, JointAngles& angles);
/// Whether every angle is within its limits (+ tolerance, rad).
bool withinLimits(const ArticulatedModel& model, const JointAngles& angles,
                  float tolerance = 1e-5f);

/// The joint rotation of (flexion, abduction, twist), rad, and its inverse (|abduction| < pi/2).
/// Swing-twist in the model's joint axes (+z along the child bone, +x the flexion axis, +y
/// dorsal): the bone direction is
///   d = (sin(abduction), -cos(abduction) sin(flexion), cos(abduction) cos(flexion)),
/// the rotation is the shortest swing z -> d followed by the twist about z. Pure flexion is a
/// rotation about +x (the bone turns toward -y, the palm); pure abduction one about +y (the
/// bone turns toward +x: the thumb side of a right hand); pure twist one about +z. This is the
/// physics convention (physics_angles.h) with angles (f, -a, t) in the joint frame whose
/// physics axes X, Y, Z are the model's z, -y, x.
Quat jointRotation(const Vec3& angles);
/// The inverse of jointRotation: (flexion, abduction, twist) of a joint rotation, rad.
Vec3 jointRotationAngles(const Quat& rotation);

/// Every body's world pose from the root pose and the joint angles (parents first; each child
/// placed so that its joint anchors meet).
ModelPose forwardKinematics(const ArticulatedModel& model, const JointAngles& angles);
/// forwardKinematics into a caller-owned buffer.
void forwardKinematicsInto(const ArticulatedModel& model, const JointAngles& angles,
                           ModelPose& out);

/// Angles recovered from body orientations (positions are not used; the root pose is the root
/// body's pose).
JointAngles jointAngles(const ArticulatedModel& model, const ModelPose& pose);
/// jointAngles into a caller-owned buffer.
void jointAnglesInto(const ArticulatedModel& model, const ModelPose& pose, JointAngles& out);

/// Linear in the angles, slerp of the root; t in [0, 1]. Joint-consistent at every t.
JointAngles interpolate(const JointAngles& a, const JointAngles& b, float t);
/// Poses interpolated through their joint angles (so joints stay attached).
ModelPose interpolate(const ArticulatedModel& model, const ModelPose& a, const ModelPose& b,
                      float t);

/// Angles of the mirror image (see mirrorModel): (f, a, t) -> (f, -a, -t), root mirrored
/// through the x = 0 plane of the world.
JointAngles mirrorAngles(const JointAngles& angles);

/// World position of every keypoint of the model (indexed like model.keypoints()).
void keypointPositionsInto(const ArticulatedModel& model, const ModelPose& pose,
                           std::vector<Vec3>& out);

/// 21 hand keypoints in MediaPipe order: 0 wrist; 1-4 thumb CMC, MCP, IP, TIP; 5-8 index MCP,
/// PIP, DIP, TIP; 9-12 middle; 13-16 ring; 17-20 pinky. Requires model.hasKeypoints21().
std::array<Vec3, 21> keypoints21(const ArticulatedModel& model, const ModelPose& pose);

/// The hand's length (m) from its 21 keypoints: the middle finger's chain wrist -> MCP -> PIP
/// -> DIP -> tip straightened out, as ModelMetadata::referenceLength measures it.
float handLength(const std::array<Vec3, 21>& keypoints);

/// The MediaPipe names, in order ("wrist", "thumb_cmc", ..., "pinky_tip").
const std::array<const char*, 21>& keypoint21Names();

/// One XR_EXT_hand_tracking joint: pose (+z toward the wrist along the bone, +y out of the
/// back of the hand, x = y cross z) and radius (m).
struct XrJoint {
  Pose pose;            ///< world pose of the joint frame
  float radius = 0.0f;  ///< distance from the joint to the skin, m
};

/// The 26 joints in XrHandJointEXT order: 0 palm, 1 wrist, 2-5 thumb metacarpal, proximal,
/// distal, tip, 6-10 index metacarpal, proximal, intermediate, distal, tip, 11-15 middle,
/// 16-20 ring, 21-25 little. Requires model.hasOpenXrJoints().
std::array<XrJoint, 26> openxr26(const ArticulatedModel& model, const ModelPose& pose);
/// The OpenXR joint names, in order ("palm", "wrist", "thumb_metacarpal", ...).
const std::array<const char*, 26>& openXrJointNames();

// ---- Pose sequences: JSON lines (docs/formats/pose.md) ----

/// The version savePoseSequence writes and loadPoseSequence reads.
inline constexpr int kPoseFormatVersion = 1;

/// Model poses over time, with the names of the model's bodies.
struct PoseSequence {
  std::vector<std::string> bodyNames;  ///< the model's body names, in order
  std::vector<ModelPose> frames;       ///< one pose per frame, poses in bodyNames order
};

/// Reads a pose JSON lines file; errors name the file, line and problem.
Result<PoseSequence> loadPoseSequence(const std::filesystem::path& path);
/// Writes a pose JSON lines file; every frame must have one pose per body name.
Status savePoseSequence(const PoseSequence& sequence, const std::filesystem::path& path);
/// Checks that the sequence's bodies are the model's (names and order).
Status checkPoseSequence(const PoseSequence& sequence, const ArticulatedModel& model);

}  // namespace dynahand::model
