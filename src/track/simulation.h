// One tracking simulation step sequence, shared by every strategy: each substep maps
// the sample points onto the model (nearest face of the nearest body, re-mapped every
// substep), turns them into impulse-capped surface rows (line-of-sight rows for points
// that land on a back face), adds the free-space boundary planes, and steps the
// physics world (joints, limits, collisions and prior motion are the world's own).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "dynahand/cloud.h"
#include "track/hand_rig.h"
#include "track/posed_bodies.h"

namespace dynahand::track {

struct SimulationSettings {
  int substeps = 3;          // physics steps per depth frame
  float stepDt = 1.0f / 60;  // s per physics step
  // Total pull of all surface rows together (N); each row's impulse cap is
  // pullForce * stepDt / pointCount, so the total does not depend on the point count or
  // the voxel size (the paper's "impulse cap").
  float pullForce = 600.0f;
  float boundaryForce = 200.0f;  // cap per boundary row (N), times stepDt
  float boundaryMargin = 0.02f;  // planes farther than this from a body add no row (m)
  // Of a body's hull vertices within the margin, only those within this band of its deepest
  // one get a row (m; see World::addBoundary): a finger lying along a plane keeps its near
  // edge, not its far side too.
  float boundaryBand = 0.005f;
  // Points farther than this from every body make no row: they belong to something else.
  float maxAttachDistance = 0.06f;
  // Each substep maps and pulls on one of this many interleaved subsets of the sample
  // points (point i is in subset i mod pointSubsets), in turn, so a run of substeps still
  // sees every point; the pull is split over the subset (the total stays pullForce).
  int pointSubsets = 2;
  // Fingertips over empty space are pushed towards the nearest segmented pixel
  // (track/silhouette.h) with at most this force (N); 0 = off.
  float silhouetteForce = 100.0f;
};

// A sample point bound to a set of bodies ("this point is on some fingertip").
struct LabelledPoint {
  Vec3 point = Vec3::Zero();  // m, camera frame
  BodyMask bodies = kAllBodies;
  float capScale = 1.0f;  // times the ordinary surface-row cap
};

// A one-dimensional hold of a body point at a target along a fixed world axis.
struct AxisHold {
  int body = 0;
  Vec3 localPoint = Vec3::Zero();  // body frame, m
  Vec3 target = Vec3::Zero();      // world, m
  Vec3 axis = Vec3::UnitZ();       // world, unit
  float force = 0.0f;              // cap, N
};

// Everything one simulation needs for the current frame.
struct FrameInput {
  std::span<const Vec3> points;  // voxel cloud of this hand, m
  std::span<const BoundaryPlane> planes;
  std::span<const LabelledPoint> labelled;
  const CloudFrame* cloud = nullptr;  // for free-space queries
  const AxisHold* hold = nullptr;     // optional
  // Per point, its share of the pull relative to the others (empty: 1 each), e.g. a point
  // standing for several thinned ones.
  std::span<const float> weights;
};

class Simulator {
 public:
  explicit Simulator(const SimulationSettings& settings) : settings_(settings) {}
  const SimulationSettings& settings() const { return settings_; }

  // A new frame: forgets the first mapping kept for the frame's simulations (the first
  // mapping after this call is kept and reused by any later substep starting from the same
  // poses on the same points). With `shared`, that simulator's kept mapping is used
  // instead (it must outlive the frame's runs and not change during them).
  void beginFrame(const Simulator* shared = nullptr);
  // Computes and keeps the mapping of the frame's points at the rig's current poses, for
  // the simulators that share it.
  void mapFrameStart(const HandRig& rig, const FrameInput& input);
  // After mapFrameStart: the simulations sharing the mapping run on the points `kept` only
  // (increasing indices into mapFrameStart's points; keptPoints: those points, contiguous,
  // valid for the frame). The mapping and hints are gathered to them.
  void keepPoints(std::span<const int> kept, std::span<const Vec3> keptPoints);
  // After mapFrameStart (and keepPoints): the rows of a first physics step on `input` at the
  // rig's current state, kept for the simulations sharing the mapping. A simulation's first
  // step on the same input object from the same body positions and orientations copies them
  // instead of building its own (most strategies change only joints or welds before it).
  void prepareFrameStartRows(HandRig& rig, const FrameInput& input);
  // Runs `substeps` physics steps of the rig on the frame's data: each is prepareStep, then
  // the world's step.
  void run(HandRig& rig, const FrameInput& input, int substeps);
  // Everything of a physics step but the step itself: maps the points (one subset, in turn)
  // and fills the world's surface, line-of-sight, silhouette, hold and boundary rows.
  void prepareStep(HandRig& rig, const FrameInput& input) { addRows(rig, input); }
  // Refreshes `bodies` from the rig's current poses.
  void pose(const HandRig& rig, PosedBodies& bodies);
  // Per point of the last mapping pass, its nearest body by the planar query (-1: none):
  // a good first guess for exact nearest-body queries at a nearby pose.
  std::span<const int> lastNearestBodies() const { return hints_; }

 private:
  // Where a sample point attaches: a body (-1: none), the face point and its world normal.
  struct Attachment {
    int body = -1;
    Vec3 localPoint = Vec3::Zero();
    Vec3 normal = Vec3::Zero();
  };
  void addRows(HandRig& rig, const FrameInput& input);
  Attachment map(const HandRig& rig, const Vec3& p, BodyMask mask, bool anyDistance,
                 int* hint) const;
  // The attachment of a planar query's answer (none when too far, or on the forearm's cut).
  Attachment attachment(const HandRig& rig, const SurfaceHit& hit, bool anyDistance) const;
  // Maps subset `subset` of the points (see pointSubsets) into attachments_.
  void mapPoints(const HandRig& rig, const FrameInput& input, int subset);

  SimulationSettings settings_;
  PosedBodies bodies_;
  std::vector<const physics::ConvexShape*> shapes_;
  std::vector<Pose> poses_;
  std::vector<int> hints_;  // (points) body each point attached to last pass
  // mapPoints' scratch: the subset's points, hints and planar answers, contiguous.
  std::vector<Vec3> subsetPoints_;
  std::vector<int> subsetHints_;
  std::vector<SurfaceHit> subsetHits_;
  std::vector<Attachment> attachments_;
  std::vector<Attachment> frameStart_;  // the frame's first mapping (see beginFrame)
  int frameStartSubset_ = 0;            // the subset frameStart_ holds
  std::vector<Pose> frameStartPoses_;
  const Vec3* frameStartPoints_ = nullptr;
  const Simulator* shared_ = nullptr;  // whose frame-start mapping to use (see beginFrame)
  // prepareFrameStartRows' rows, the input they are for (nullptr: none this frame) and the
  // body positions and orientations they were built at.
  physics::SurfaceRows frameStartRows_;
  const FrameInput* frameStartRowsInput_ = nullptr;
  std::vector<Vec3> frameStartRowsPositions_;
  std::vector<Quat> frameStartRowsOrientations_;
  // The frame-start mapping's nearest bodies on a coarse pixel grid (kLabelColumns across the
  // image, -1: none), the next frame's first guesses (mapFrameStart).
  static constexpr int kLabelColumns = 80;
  int labelCell(const Intrinsics& k, const Vec3& p) const;  // -1 outside the grid
  std::vector<std::int8_t> labels_;
  std::vector<int> pointCells_;  // (points) each point's cell this frame, -1: none
  int labelRows_ = 0;
  float labelScale_ = 0.0f;  // grid cells per pixel
  int pass_ = 0;             // substeps since beginFrame: picks the point subset
};

}  // namespace dynahand::track
