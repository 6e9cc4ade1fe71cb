// How well a fitted hand explains the depth data, in numbers a person can check (beyond
// the paper's error metric, which is a maximum per body): the share of the hand's samples
// lying on the model surface, and the share of the model's visible surface lying on the
// segmented hand.
#pragma once

#include <span>

#include "dynahand/cloud.h"
#include "dynahand/tracker.h"
#include "track/posed_bodies.h"

namespace dynahand::track {

// A sample point within this distance of the model's surface counts as on it
// (FitQuality::dataNearModel).
inline constexpr float kNearSurfaceM = 0.010f;

// Where the hand ends and the arm begins: the plane through the wrist keypoint across the line
// from the middle finger's knuckle to it. Sample points beyond it are the arm's.
struct WristPlane {
  Vec3 wrist = Vec3::Zero();         // m, camera frame
  Vec3 towardElbow = Vec3::UnitZ();  // unit
};

// bodies: the fitted model; pointDistances: each of the hand's sample points' distance to
// the model's surface (the error metric's ErrorBreakdown::pointDistance at the same pose,
// so the points are not queried twice; only whether each is within kNearSurfaceM matters,
// so the metric's settled points, measured to at most kNearSurfaceM, count right); points and
// wrist, when given (points the same size as pointDistances): the points beyond the wrist plane
// are left out of dataNearModel, since how much of the arm the segmentation keeps depends on
// the view (a camera the forearm comes toward sees much of it, and counted, the arm made a
// model with a longer forearm look a better fit); skipBody: a body left out of the model-side
// share (the forearm, cut by segmentation), -1 for none; tips: the five fingertip keypoints.
FitQuality measureFitQuality(const PosedBodies& bodies, std::span<const float> pointDistances,
                             std::span<const Vec3> points, const WristPlane* wrist,
                             const CloudFrame& cloud, int skipBody, std::span<const Vec3> tips);

}  // namespace dynahand::track
