/// @file
/// Free-space boundary planes (paper: "Boundary Planes"): planes through the camera
/// centre that tightly contain a point cloud. The space between the camera and the
/// observed surface is empty, so the tracked model may be kept inside the cone over
/// the convex hull of the cloud's image projection.
///
/// Construction: project the points to the normalised image plane (x/z, y/z), take
/// their convex hull, and for each of `planeCount` evenly spaced directions d keep the
/// supporting line d . q = s of the hull (s = max over hull vertices of d . q). Each
/// line lifts to the plane (d.x, d.y, -s) . p = 0 through the camera centre. Every
/// input point satisfies signedDistance(p) <= 0, and each plane touches the hull, so the
/// cone is tight up to the polygon's corners (a fixed count keeps the solver's row
/// count fixed; 16 directions lose at most 1 - cos(11.25 deg) = 2% of the hull's width).
#pragma once

#include <limits>
#include <span>
#include <vector>

#include "dynahand/core.h"

namespace dynahand {

/// A plane through the camera centre: points p with normal . p <= 0 are inside.
struct BoundaryPlane {
  Vec3 normal = Vec3::UnitX();          ///< unit, pointing out of the contained cone
  Vec2 imageDirection = Vec2::UnitX();  ///< unit outward direction in the normalised image plane

  /// Signed distance (m) of p from the plane; > 0 outside the cone.
  float signedDistance(const Vec3& p) const { return normal.dot(p); }
};

/// Settings of BoundaryPlaneBuilder.
struct BoundaryPlaneConfig {
  int planeCount = 16;  ///< supporting directions, >= 3
  /// Outward slack added to every plane, in normalised image units (1 pixel = 1 / fx).
  /// The pipeline sets it from `marginPixels` so the planes clear the pixel footprint.
  float margin = 0.0f;
  /// Planes whose outward image direction lies within this half-angle (rad) of the arm
  /// direction are left out (the wrist and forearm continue that way). <= 0 omits none.
  float omitHalfAngle = 0.6f;
};

/// Where the image ends, in the normalised image plane (x/z, y/z): the hull's vertices on an
/// edge are where the camera's view ends, not where the hand does, so the planes that rest on
/// them (outward direction toward that edge) are left out and the hand may go on out of view.
/// The default (infinite) bounds leave out nothing.
struct ViewBounds {
  Vec2 min = Vec2::Constant(-std::numeric_limits<float>::infinity());  ///< left, top edge
  Vec2 max = Vec2::Constant(std::numeric_limits<float>::infinity());   ///< right, bottom edge
  /// A hull vertex within this of an edge lies on it (normalised image units: the sample
  /// spacing and pixel footprint, 1 pixel = 1 / f).
  float margin = 0.0f;
};

/// Reusable builder: scratch buffers grow to the largest input seen, then no allocation.
class BoundaryPlaneBuilder {
 public:
  /// Planes for points given in the normalised image plane (x/z, y/z). armDirection is
  /// a direction in that plane (zero = none: keep all planes). `view`: planes resting on the
  /// image's edges are left out (ViewBounds). Replaces `out`.
  void build(std::span<const Vec2> normalisedPoints, const BoundaryPlaneConfig& config,
             const Vec2& armDirection, std::vector<BoundaryPlane>& out,
             const ViewBounds& view = {});
  /// Same for 3D points (m, camera frame, z > 0; others are skipped).
  void buildFromPoints(std::span<const Vec3> points, const BoundaryPlaneConfig& config,
                       const Vec2& armDirection, std::vector<BoundaryPlane>& out);

  /// Convex hull of the last build's points (normalised image plane), each turn with a
  /// positive cross product, first vertex not repeated.
  std::span<const Vec2> hull() const { return hull_; }

 private:
  bool restsOnViewEdge(const Vec2& d, float support, const ViewBounds& view) const;

  std::vector<Vec2> sorted_;
  std::vector<Vec2> hull_;
  std::vector<Vec2> projected_;
};

}  // namespace dynahand
