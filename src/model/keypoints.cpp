// Hand keypoint layouts: 21 MediaPipe keypoints and 26 OpenXR joints from named keypoints.
#include <cassert>
#include <cmath>
#include <string>

#include "dynahand/model_pose.h"
#include "model/hand_layout.h"

namespace dynahand::model {
namespace {

const char* const kFingerNames[4] = {"index", "middle", "ring", "pinky"};

// An OpenXR joint: placed at `at`, +z from `to` back toward `from` (the bone direction).
struct XrJointRule {
  std::string at, from, to;
};

std::array<XrJointRule, 26> xrRules() {
  std::array<XrJointRule, 26> rules;
  rules[0] = {"palm_center", "wrist", "middle_mcp"};
  rules[1] = {"wrist", "wrist", "middle_mcp"};
  rules[2] = {"thumb_cmc", "thumb_cmc", "thumb_mcp"};
  rules[3] = {"thumb_mcp", "thumb_mcp", "thumb_ip"};
  rules[4] = {"thumb_ip", "thumb_ip", "thumb_tip"};
  rules[5] = {"thumb_tip", "thumb_ip", "thumb_tip"};
  for (int f = 0; f < 4; ++f) {
    const std::string n = kFingerNames[f];
    const size_t base = 6 + 5 * static_cast<size_t>(f);
    rules[base + 0] = {n + "_cmc", n + "_cmc", n + "_mcp"};
    rules[base + 1] = {n + "_mcp", n + "_mcp", n + "_pip"};
    rules[base + 2] = {n + "_pip", n + "_pip", n + "_dip"};
    rules[base + 3] = {n + "_dip", n + "_dip", n + "_tip"};
    rules[base + 4] = {n + "_tip", n + "_dip", n + "_tip"};
  }
  return rules;
}

}  // namespace

const std::array<const char*, 21>& keypoint21Names() {
  static const std::array<const char*, 21> names = {
      "wrist",      "thumb_cmc", "thumb_mcp", "thumb_ip",   "thumb_tip",  "index_mcp",
      "index_pip",  "index_dip", "index_tip", "middle_mcp", "middle_pip", "middle_dip",
      "middle_tip", "ring_mcp",  "ring_pip",  "ring_dip",   "ring_tip",   "pinky_mcp",
      "pinky_pip",  "pinky_dip", "pinky_tip"};
  return names;
}

const std::array<const char*, 26>& openXrJointNames() {
  static const std::array<const char*, 26> names = {"palm",
                                                    "wrist",
                                                    "thumb_metacarpal",
                                                    "thumb_proximal",
                                                    "thumb_distal",
                                                    "thumb_tip",
                                                    "index_metacarpal",
                                                    "index_proximal",
                                                    "index_intermediate",
                                                    "index_distal",
                                                    "index_tip",
                                                    "middle_metacarpal",
                                                    "middle_proximal",
                                                    "middle_intermediate",
                                                    "middle_distal",
                                                    "middle_tip",
                                                    "ring_metacarpal",
                                                    "ring_proximal",
                                                    "ring_intermediate",
                                                    "ring_distal",
                                                    "ring_tip",
                                                    "little_metacarpal",
                                                    "little_proximal",
                                                    "little_intermediate",
                                                    "little_distal",
                                                    "little_tip"};
  return names;
}

namespace detail {

void resolveHandLayout(const std::vector<Keypoint>& keypoints, bool& has21,
                       std::array<int, 21>& indices21) {
  has21 = true;
  for (size_t i = 0; i < 21; ++i) {
    indices21[i] = -1;
    for (size_t k = 0; k < keypoints.size(); ++k) {
      if (keypoints[k].name == keypoint21Names()[i]) indices21[i] = static_cast<int>(k);
    }
    if (indices21[i] < 0) has21 = false;
  }
}

bool computeOpenXrFrames(const ArticulatedModel& model, std::array<BodyFrame, 26>& frames) {
  const std::array<XrJointRule, 26> rules = xrRules();
  const ModelPose rest = forwardKinematics(model, zeroAngles(model));
  std::vector<Vec3> world;
  keypointPositionsInto(model, rest, world);
  for (size_t i = 0; i < 26; ++i) {
    const int at = model.keypointIndex(rules[i].at);
    const int from = model.keypointIndex(rules[i].from);
    const int to = model.keypointIndex(rules[i].to);
    if (at < 0 || from < 0 || to < 0) return false;
    const Keypoint& kp = model.keypoints()[static_cast<size_t>(at)];
    const Pose& bodyPose = rest.bodies[static_cast<size_t>(kp.body)];
    const Vec3 boneWorld = world[static_cast<size_t>(to)] - world[static_cast<size_t>(from)];
    // A bone of no length, or one too long for float arithmetic (keypoints near the float
    // limit), has no direction.
    const float length = boneWorld.norm();
    if (!(length >= 1e-6f) || !std::isfinite(length)) return false;
    const Vec3 z = -(bodyPose.q.conjugate() * boneWorld).normalized();
    // +y out of the back of the hand: the body's y axis (dorsal by the model convention),
    // made perpendicular to the bone.
    Vec3 y = Vec3::UnitY() - z * z.y();
    if (y.norm() < 1e-3f) y = Vec3::UnitX() - z * z.x();
    y.normalize();
    Mat3 axes;
    axes.col(0) = y.cross(z);
    axes.col(1) = y;
    axes.col(2) = z;
    frames[i] = BodyFrame{kp.body, Pose{kp.point, Quat(axes).normalized()}, kp.radius};
  }
  return true;
}

}  // namespace detail

void keypointPositionsInto(const ArticulatedModel& model, const ModelPose& pose,
                           std::vector<Vec3>& out) {
  assert(pose.bodies.size() == model.bodies().size());
  out.resize(model.keypoints().size());
  for (size_t k = 0; k < out.size(); ++k) {
    const Keypoint& kp = model.keypoints()[k];
    out[k] = pose.bodies[static_cast<size_t>(kp.body)].transform(kp.point);
  }
}

float handLength(const std::array<Vec3, 21>& kp) {
  return (kp[9] - kp[0]).norm() + (kp[10] - kp[9]).norm() + (kp[11] - kp[10]).norm() +
         (kp[12] - kp[11]).norm();
}

std::array<Vec3, 21> keypoints21(const ArticulatedModel& model, const ModelPose& pose) {
  assert(model.hasKeypoints21() && "the model lacks the 21 MediaPipe keypoint names");
  assert(pose.bodies.size() == model.bodies().size());
  std::array<Vec3, 21> out;
  for (size_t i = 0; i < 21; ++i) {
    const Keypoint& kp = model.keypoints()[static_cast<size_t>(model.keypoints21Indices()[i])];
    out[i] = pose.bodies[static_cast<size_t>(kp.body)].transform(kp.point);
  }
  return out;
}

std::array<XrJoint, 26> openxr26(const ArticulatedModel& model, const ModelPose& pose) {
  assert(model.hasOpenXrJoints() && "the model lacks palm_center or the *_cmc keypoints");
  assert(pose.bodies.size() == model.bodies().size());
  std::array<XrJoint, 26> out;
  for (size_t i = 0; i < 26; ++i) {
    const BodyFrame& f = model.openXrFrames()[i];
    out[i] = XrJoint{pose.bodies[static_cast<size_t>(f.body)] * f.local, f.radius};
  }
  return out;
}

}  // namespace dynahand::model
