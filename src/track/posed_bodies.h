// The tracked model's convex bodies at one pose, in the camera (world) frame, ready
// for point queries: which body surface is nearest to a sample point, where, and
// through which face. Shared by the surface constraints and the error metric.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "dynahand/convex_shape.h"
#include "dynahand/core.h"

namespace dynahand::track {

using BodyMask = std::uint32_t;  // bit i = body i may be matched (at most 32 bodies)
inline constexpr BodyMask kAllBodies = ~BodyMask{0};

struct SurfaceHit {
  int body = -1;                   // nearest body, -1 if none allowed
  int face = -1;                   // face of that body holding the closest point
  float distance = 0.0f;           // unsigned distance to that body's surface, m
  float signedDistance = 0.0f;     // negative when the point is inside the body, m
  Vec3 localPoint = Vec3::Zero();  // closest surface point, body frame, m
};

class PosedBodies {
 public:
  // shapes[i] is body i's shape in its body frame; poses[i] its world pose.
  // The shapes must outlive this object.
  void set(std::span<const physics::ConvexShape* const> shapes, std::span<const Pose> poses);
  void setPose(int body, const Pose& pose);

  int size() const { return static_cast<int>(shapes_.size()); }
  const physics::ConvexShape& shape(int body) const {
    return *shapes_[static_cast<std::size_t>(body)];
  }
  const Pose& pose(int body) const { return poses_[static_cast<std::size_t>(body)]; }
  Vec3 worldCentroid(int body) const {
    const auto i = static_cast<std::size_t>(body);
    return {sphereX_[i], sphereY_[i], sphereZ_[i]};
  }

  // The body whose surface is nearest to p (world), among the bodies in mask. Exact:
  // the body with the smallest bounding-sphere lower bound is tried first, then every
  // other body whose sphere and face-plane bounds do not exceed the best distance found. Ties go to
  // the lower body index. hint: a body likely to be the answer, tried first (-1: none); the
  // result does not depend on it.
  SurfaceHit nearest(const Vec3& p, BodyMask mask = kAllBodies, int hint = -1) const;

  // The fast variant the surface constraints use: the distance to a body is its largest
  // face-plane distance (exact inside a body and wherever the foot of the perpendicular
  // lies on that face, a lower bound elsewhere; outside, at least the bounding-sphere
  // bound), the face is that plane's, and
  // localPoint is p's projection onto it (a point of the face plane: all a point-to-plane
  // row needs). About ten times cheaper than nearest(). hint: a body likely to be the
  // answer (e.g. last pass's), tried first to cull the others; -1 for none. The result
  // does not depend on the hint except on exact ties.
  SurfaceHit nearestPlanar(const Vec3& p, BodyMask mask = kAllBodies, int hint = -1) const;
  // nearestPlanar(points[i], kAllBodies, hints[i]) for every point, with the same bits, into
  // hits[i]; hints[i] becomes hits[i].body. Body by body over many points at once (eight
  // points per step of the SIMD layer, bulk_queries.inl): the mapping's bulk path. Not for
  // concurrent calls on one object (it keeps scratch buffers).
  void nearestPlanarMany(std::span<const Vec3> points, std::span<int> hints,
                         std::span<SurfaceHit> hits) const;
  // nearest(points[i], kAllBodies, hints[i]) for every point, with the same bits, the same way
  // (the error metric's bulk path).
  void nearestMany(std::span<const Vec3> points, std::span<const int> hints,
                   std::span<SurfaceHit> hits) const;
  // nearestMany for the error metric, which only needs each body's largest distance: a
  // point whose distance d to its first body (its hint, else the nearest sphere) is at most
  // settle[j] for that body and every body j whose bounding sphere comes within d is
  // "settled": it is tested against no other body, hits[i] is the first body's exact hit (d
  // is an upper bound on its nearest distance) and settled[i] = 1. With settle[j] at most
  // body j's errFit so far, such a point cannot raise any errFit. Other points get nearest()'s
  // answer and settled[i] = 0. The same points settle on every SIMD level; with the bulk
  // queries switched off (useBulkQueries) none does.
  void nearestManySettling(std::span<const Vec3> points, std::span<const int> hints,
                           std::span<const float> settle, std::span<SurfaceHit> hits,
                           std::span<std::uint8_t> settled) const;

  // One point's face-plane scan runs eight planes at a time (plane_scan.inl); the bulk queries
  // (nearestMany, nearestPlanarMany, nearestManySettling) run body by body over eight points at
  // a time (bulk_queries.inl); both on the SIMD layer's level, with the same bits on every
  // level. false (a test switch) makes the bulk queries answer point by point with the
  // one-point queries, which give the same hits; returns `enabled`.
  static bool useBulkQueries(bool enabled);

 private:
  // Face planes of one shape as SoA, padded to a multiple of 8 with planes that never win.
  struct PlaneTable {
    std::vector<float> nx, ny, nz, offset;
  };
  // Largest plane distance of local point q and its face; returns early with some
  // distance > stopAbove (not the largest) once one plane is farther than that.
  static float maxPlaneDistance(const PlaneTable& t, const Vec3& q, int* face,
                                float stopAbove = std::numeric_limits<float>::infinity());

  // p in body i's frame (Pose::inverseTransform, written out so that the eight-wide path can
  // give the same bits).
  Vec3 toLocal(std::size_t body, const Vec3& p) const;
  // |p - c_i| - r_i: a lower bound on p's planar distance to body i (inside the sphere too).
  float sphereGap(std::size_t body, const Vec3& p) const;
  // A body-frame point's planar answer for body i: SurfaceHit with d = -sd inside, else
  // max(sd, sphereGap); `face` and `sd` from the plane scan.
  SurfaceHit planarHit(std::size_t body, const Vec3& p, const Vec3& local, int face,
                       float sd) const;
  // The exact answer for body i from its largest plane distance and that plane's face.
  SurfaceHit exactHit(std::size_t body, const Vec3& local, float planeDist, int planeFace) const;

  std::vector<const physics::ConvexShape*> shapes_;
  std::vector<const physics::ConvexShape*> tableShapes_;  // shapes the tables were built for
  std::vector<PlaneTable> planes_;
  std::vector<Pose> poses_;
  static constexpr std::size_t kMaxBodies = 32;  // BodyMask bits
  void setCentroid(std::size_t body, const Vec3& centroid);

  // Each body's bounding sphere: world centroid and radius about it, as SoA for eight-wide
  // bounds, padded past the last body with far spheres.
  std::array<float, kMaxBodies> sphereX_{}, sphereY_{}, sphereZ_{}, sphereR_{};

  void nearestMany(std::span<const Vec3> points, std::span<const int> hints,
                   std::span<SurfaceHit> hits, bool exact, const float* settle = nullptr,
                   std::uint8_t* settled = nullptr) const;
  // nearestMany's wide path, stage by stage: the points into the SoA scratch (returns their
  // count padded to eight), each point listed under its first body, the listed points tested
  // eight at a time, settling, then each point listed under every other body that could
  // still beat its best.
  std::size_t loadPoints(std::span<const Vec3> points) const;
  void listFirstBodies(std::span<const Vec3> points, std::span<const int> hints,
                       std::size_t padded) const;
  void testListed(std::span<const Vec3> points, std::size_t padded, bool exact,
                  std::span<SurfaceHit> hits) const;
  void settleFirstHits(std::size_t n, std::size_t padded, const float* settle,
                       std::uint8_t* settled) const;
  void listReachablePoints(std::size_t n, std::size_t padded) const;
  // The bulk queries' scratch: the points as SoA, each point's first body (as a float, for
  // eight-wide compares; -1 for none), per body the points to test (a row of tests_ each) and
  // their count, each point's best so far.
  mutable std::vector<float> px_, py_, pz_;
  mutable std::vector<float> first_;
  mutable std::vector<int> tests_;
  mutable std::vector<int> testCount_;
  mutable std::vector<float> bestDistance_;
};

}  // namespace dynahand::track
