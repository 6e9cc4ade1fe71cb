/// @file
/// A convex polyhedron in its body frame: hull, face planes, mass properties of the uniform
/// solid and exact point/ray queries. Built once (Qhull), then immutable and shared between
/// bodies. Units: metres, kilograms, body frame throughout.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include "dynahand/core.h"

namespace dynahand::physics {

/// One polygonal hull face. Coplanar triangles are merged into one face.
struct Face {
  Vec3 normal = Vec3::UnitZ();  ///< outward unit normal, body frame
  float offset = 0.0f;          ///< normal·x = offset on the face plane, m
  std::vector<int> vertices;    ///< indices into ConvexShape::vertices(), CCW seen from outside
};

/// A convex polyhedron (see the file comment); made by fromPoints or box.
class ConvexShape {
 public:
  /// Convex hull of the points (body frame, m). Fails with a reason for fewer than 4 points,
  /// non-finite coordinates, coplanar/collinear points or a zero-volume hull. Points inside
  /// the hull are dropped.
  static Result<ConvexShape> fromPoints(std::span<const Vec3> points);

  /// An axis-aligned box centred on the origin; halfExtents > 0 (m). Convenience for tests/scenes.
  static ConvexShape box(const Vec3& halfExtents);

  const std::vector<Vec3>& vertices() const { return vertices_; }  ///< hull vertices, m
  /// direction·v for every hull vertex v into out (vertices().size() floats), four at a time,
  /// with the same bits as Vec3::dot.
  void vertexHeights(const Vec3& direction, float* out) const;
  const std::vector<Face>& faces() const { return faces_; }  ///< hull faces

  float volume() const { return volume_; }     ///< m^3
  Vec3 centroid() const { return centroid_; }  ///< centre of mass of the uniform solid, m
  /// Inertia tensor about the centroid, body axes, for a uniform solid of this mass (kg m^2).
  Mat3 inertiaAboutCentroid(float mass) const { return unitInertia_ * mass; }
  /// Largest sphere about the centroid inside the hull (distance to the nearest face plane), m.
  float inscribedRadius() const { return inscribedRadius_; }
  /// Smallest sphere about the centroid containing the hull (farthest vertex), m.
  float boundingRadius() const { return boundingRadius_; }

  /// Exact Euclidean signed distance to the surface, m; negative inside.
  float signedDistance(const Vec3& p) const;
  /// Closest point on the surface (for an inside point: its projection on the nearest face).
  Vec3 closestPoint(const Vec3& p) const;
  /// Index into faces() of the face holding closestPoint(p) (lowest index on ties).
  int closestFace(const Vec3& p) const;
  /// The three queries at once: returns the signed distance, writes the point and face.
  float query(const Vec3& p, Vec3* closest, int* face) const;
  /// query() for a caller that already has p's largest face-plane distance and its face
  /// (lowest index on ties), e.g. from a vectorised scan of the planes: skips that scan.
  float queryFromPlane(const Vec3& p, float maxDist, int maxFace, Vec3* closest, int* face) const;
  /// A hull vertex maximising direction·v (lowest index on ties). direction need not be unit.
  Vec3 support(const Vec3& direction) const;
  /// Ray origin + t·dir (dir unit or not, t in units of |dir|): the smallest t in [0, maxT] at
  /// which the ray is inside or on the solid; 0 if the origin is inside; nullopt on a miss.
  std::optional<float> raycast(const Vec3& origin, const Vec3& dir, float maxT) const;

 private:
  ConvexShape() = default;
  void computeDerived();
  /// projected (a point of face's plane) lies within the face's polygon.
  bool onFacePolygon(const Face& face, const Vec3& projected) const;
  void buildEdges();
  /// Squared distance from p to the nearest hull edge; writes that edge and the parameter t
  /// in [0, 1] of its closest point (lowest edge index on ties).
  float nearestEdge(const Vec3& p, int* edge, float* t) const;

  std::vector<Vec3> vertices_;
  std::vector<float> vertexX_, vertexY_, vertexZ_;  ///< vertices_ as SoA
  std::vector<Face> faces_;
  /// Every hull edge once, as start point a, direction d = b - a and 1 / |d|^2, SoA padded to a
  /// multiple of eight with far zero-length edges: an outside point whose foot misses its
  /// farthest face is nearest to one of them.
  std::vector<float> edgeAx_, edgeAy_, edgeAz_, edgeDx_, edgeDy_, edgeDz_, edgeInvLen2_;
  struct EdgeInfo {
    int a, b;        ///< vertex indices
    int lowestFace;  ///< lower index of its two faces
  };
  std::vector<EdgeInfo> edges_;
  std::vector<int> vertexLowestFace_;  ///< (vertices) lowest index of the faces around it
  float volume_ = 0.0f;
  Vec3 centroid_ = Vec3::Zero();
  Mat3 unitInertia_ = Mat3::Zero();  ///< inertia about the centroid per kg, m^2
  float inscribedRadius_ = 0.0f;
  float boundingRadius_ = 0.0f;
};

}  // namespace dynahand::physics
