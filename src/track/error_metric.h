// The paper's 3D error metric ("Error Metric", eqs. 1-4), used only to pick the best
// simulation, never to move the model:
//   P_i      = sample points whose nearest hand surface point lies on body i
//   errFit_i = max over P_i of the distance to body i's surface
//   errOcc_i = r_i (largest inscribed sphere about the centroid) when body i's centroid
//              projects onto a pixel showing background farther than it, or no data
//   total    = sum errFit_i + sum errOcc_i
// A centroid projecting outside the image adds nothing: there is no evidence there.
#pragma once

#include <functional>
#include <span>
#include <vector>

#include "dynahand/depth_frame.h"
#include "track/posed_bodies.h"

namespace dynahand::track {

struct ErrorBreakdown {
  std::vector<float> fit;            // (bodies) errFit_i, m
  std::vector<float> occlusion;      // (bodies) errOcc_i, m
  std::vector<int> pointCount;       // (bodies) |P_i|
  std::vector<float> pointDistance;  // (points) distance to the nearest body's surface, m
                                     // (infinity when no body exists)
  float fitTotal = 0.0f;             // m
  float occlusionTotal = 0.0f;       // m
  float total = 0.0f;                // m
};

// isFree(p): whether the camera saw the space at p (camera frame) to be empty, e.g.
// CloudFrame::isFree or inFreeSpace below.
using FreeSpaceTest = std::function<bool(const Vec3&)>;
// nearestHints: optional, per point a body likely nearest (e.g. the simulation's last
// mapping); it only speeds the queries up, the result is the same without it. Not for
// concurrent calls on one PosedBodies (its bulk queries keep scratch buffers).
void computeError(const PosedBodies& bodies, std::span<const Vec3> points,
                  const FreeSpaceTest& isFree, ErrorBreakdown& out,
                  std::span<const int> nearestHints = {});

// computeError that gives up as soon as the total is sure to exceed `abortAbove` (m): the
// per-body maxima only grow, so the sum so far is a lower bound. Returns true with exactly
// computeError's result (same bits) when the total stays at or below abortAbove; false
// otherwise, with `out.total` a lower bound above abortAbove (the rest of `out` partial).
// order: optional, the point indices in the order to visit (points likely to be far from
// the model first make a losing candidate give up sooner); the result does not depend on it.
// settleBelowM > 0: a point whose distance to its hinted body is at most settleBelowM and at
// most the errFit so far of every body that could be as near is not matched further (it
// cannot raise any errFit): errFit, errOcc, the totals and the give-up points are the same
// bits, but such a point's pointDistance is that hinted distance (an upper bound, at most
// settleBelowM: any "within settleBelowM" count of pointDistance stays exact) and it is in
// no pointCount. On the wave clip 70 % of the points settle; that spares their other bodies'
// queries, not the first body's, which costs most (-0.5 % of the tracker, docs/tracker.md).
bool computeErrorBounded(const PosedBodies& bodies, std::span<const Vec3> points,
                         const FreeSpaceTest& isFree, float abortAbove, ErrorBreakdown& out,
                         std::span<const int> nearestHints = {}, std::span<const int> order = {},
                         float settleBelowM = 0.0f);

// True when the pixel under `point` shows background farther than it or no data,
// i.e. the point sits in space the camera saw to be empty. False outside the image.
bool inFreeSpace(const Vec3& point, const DepthFrame& depth, const Intrinsics& intrinsics);

}  // namespace dynahand::track
