// ConvexShape: hull by Qhull (reentrant C API), mass properties by tetrahedral
// decomposition, exact queries over the merged polygonal faces.
#include "dynahand/convex_shape.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <utility>

#include "core/simd/lanes.h"

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace dynahand::physics {
namespace {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;

// Qhull writes its diagnostics to a FILE*; capture them into a string for the Error.
class CapturedStream {
 public:
  CapturedStream() : file_(open_memstream(&buffer_, &size_)) {}
  ~CapturedStream() {
    if (file_) std::fclose(file_);
    std::free(buffer_);
  }
  CapturedStream(const CapturedStream&) = delete;
  CapturedStream& operator=(const CapturedStream&) = delete;
  FILE* file() const { return file_; }
  std::string text() {
    if (file_) std::fflush(file_);
    std::string s = buffer_ ? std::string(buffer_, size_) : std::string();
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
    const std::size_t firstLine = s.find('\n');
    return firstLine == std::string::npos ? s : s.substr(0, firstLine);
  }

 private:
  char* buffer_ = nullptr;
  std::size_t size_ = 0;
  FILE* file_ = nullptr;
};

#define DYNAHAND_SIMD_KERNELS "physics/convex_shape.inl"
#include "core/simd/for_each_level.inl"

}  // namespace

Result<ConvexShape> ConvexShape::fromPoints(std::span<const Vec3> points) {
  if (points.size() < 4) {
    return Error{"convex shape: need at least 4 points, got " + std::to_string(points.size())};
  }
  std::vector<coordT> coords;
  coords.reserve(points.size() * 3);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      return Error{"convex shape: point " + std::to_string(i) + " has a non-finite coordinate"};
    }
    for (int k = 0; k < 3; ++k) coords.push_back(static_cast<coordT>(points[i][k]));
  }

  CapturedStream errors;
  qhT qhStorage;
  qhT* qh = &qhStorage;
  qh_zero(qh, errors.file());
  // Pre-merge facets whose centrums are within float round-off of each other's planes
  // (relative to the point cloud's extent), so coplanar triangles become one polygonal face.
  float extent = 0.0f;
  for (const Vec3& p : points) extent = std::max(extent, p.cwiseAbs().maxCoeff());
  char command[64];
  std::snprintf(command, sizeof command, "qhull C-%.3g", static_cast<double>(extent) * 1e-6);
  const int exitCode = qh_new_qhull(qh, 3, static_cast<int>(points.size()), coords.data(), False,
                                    command, nullptr, errors.file());
  ConvexShape shape;
  std::string failure;
  if (exitCode != 0) {
    failure =
        "convex shape: hull failed (points coplanar, collinear or degenerate): " + errors.text();
  } else {
    // Hull vertices, renumbered in Qhull's point order so the result is deterministic.
    std::vector<int> remap(points.size(), -1);
    vertexT* vertex;
    FORALLvertices {
      remap[static_cast<std::size_t>(qh_pointid(qh, vertex->point))] = 0;
    }
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (remap[i] == 0) {
        remap[i] = static_cast<int>(shape.vertices_.size());
        shape.vertices_.push_back(points[i]);
      }
    }
    facetT* facet;
    FORALLfacets {
      Face face;
      const Vec3d n(facet->normal[0], facet->normal[1], facet->normal[2]);
      face.normal = n.normalized().cast<float>();
      vertexT** vertexp;
      FOREACHvertex_(facet->vertices) {
        face.vertices.push_back(remap[static_cast<std::size_t>(qh_pointid(qh, vertex->point))]);
      }
      shape.faces_.push_back(std::move(face));
    }
  }
  qh_freeqhull(qh, !qh_ALL);
  int curLong = 0, totLong = 0;
  qh_memfreeshort(qh, &curLong, &totLong);
  if (!failure.empty()) return Error{failure};

  // Order each face's vertices CCW about its outward normal, and make its plane a true
  // supporting plane of the hull (offset = max over vertices) so queries are conservative.
  for (Face& face : shape.faces_) {
    const Vec3d n = face.normal.cast<double>();
    Vec3d centre = Vec3d::Zero();
    for (int v : face.vertices)
      centre += shape.vertices_[static_cast<std::size_t>(v)].cast<double>();
    centre /= static_cast<double>(face.vertices.size());
    const Vec3d u = n.unitOrthogonal();
    const Vec3d w = n.cross(u);
    std::vector<std::pair<double, int>> byAngle;
    for (int v : face.vertices) {
      const Vec3d d = shape.vertices_[static_cast<std::size_t>(v)].cast<double>() - centre;
      byAngle.emplace_back(std::atan2(d.dot(w), d.dot(u)), v);
    }
    std::sort(byAngle.begin(), byAngle.end());
    for (std::size_t i = 0; i < byAngle.size(); ++i) face.vertices[i] = byAngle[i].second;
    float offset = -std::numeric_limits<float>::infinity();
    for (const Vec3& v : shape.vertices_) offset = std::max(offset, face.normal.dot(v));
    face.offset = offset;
  }
  // Lowest-vertex-first face order makes face indices independent of Qhull's list order.
  std::stable_sort(shape.faces_.begin(), shape.faces_.end(), [](const Face& a, const Face& b) {
    const int minA = *std::min_element(a.vertices.begin(), a.vertices.end());
    const int minB = *std::min_element(b.vertices.begin(), b.vertices.end());
    if (minA != minB) return minA < minB;
    return a.vertices < b.vertices;
  });

  shape.computeDerived();
  if (!(shape.volume_ > 0.0f) || !std::isfinite(shape.volume_)) {
    return Error{"convex shape: hull has zero volume"};
  }
  return shape;
}

ConvexShape ConvexShape::box(const Vec3& halfExtents) {
  assert(halfExtents.minCoeff() > 0.0f && "box half extents must be positive");
  std::vector<Vec3> corners;
  for (int i = 0; i < 8; ++i) {
    corners.emplace_back((i & 1) ? halfExtents.x() : -halfExtents.x(),
                         (i & 2) ? halfExtents.y() : -halfExtents.y(),
                         (i & 4) ? halfExtents.z() : -halfExtents.z());
  }
  Result<ConvexShape> shape = fromPoints(corners);
  assert(shape.ok());
  return std::move(shape).value();
}

void ConvexShape::buildEdges() {
  std::vector<std::pair<std::pair<int, int>, int>> halfEdges;  // (lower, upper vertex), face
  vertexLowestFace_.assign(vertices_.size(), std::numeric_limits<int>::max());
  for (std::size_t f = 0; f < faces_.size(); ++f) {
    const auto& loop = faces_[f].vertices;
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const int a = loop[i], b = loop[(i + 1) % loop.size()];
      halfEdges.push_back({{std::min(a, b), std::max(a, b)}, static_cast<int>(f)});
      int& lowest = vertexLowestFace_[static_cast<std::size_t>(a)];
      lowest = std::min(lowest, static_cast<int>(f));
    }
  }
  std::sort(halfEdges.begin(), halfEdges.end());  // an edge's two faces, lower one first
  edges_.clear();
  for (std::size_t i = 0; i < halfEdges.size(); ++i) {
    if (i > 0 && halfEdges[i].first == halfEdges[i - 1].first) continue;
    edges_.push_back({halfEdges[i].first.first, halfEdges[i].first.second, halfEdges[i].second});
  }
  vertexX_.resize(vertices_.size());
  vertexY_.resize(vertices_.size());
  vertexZ_.resize(vertices_.size());
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    vertexX_[i] = vertices_[i].x();
    vertexY_[i] = vertices_[i].y();
    vertexZ_[i] = vertices_[i].z();
  }
  const std::size_t padded = (edges_.size() + simd::kLanes - 1) / simd::kLanes * simd::kLanes;
  for (auto* v : {&edgeAx_, &edgeAy_, &edgeAz_}) v->assign(padded, 1e15f);
  for (auto* v : {&edgeDx_, &edgeDy_, &edgeDz_, &edgeInvLen2_}) v->assign(padded, 0.0f);
  for (std::size_t e = 0; e < edges_.size(); ++e) {
    const Vec3& a = vertices_[static_cast<std::size_t>(edges_[e].a)];
    const Vec3 d = vertices_[static_cast<std::size_t>(edges_[e].b)] - a;
    edgeAx_[e] = a.x();
    edgeAy_[e] = a.y();
    edgeAz_[e] = a.z();
    edgeDx_[e] = d.x();
    edgeDy_[e] = d.y();
    edgeDz_[e] = d.z();
    const float len2 = d.squaredNorm();
    edgeInvLen2_[e] = len2 > 0.0f ? 1.0f / len2 : 0.0f;  // a point edge: its start
  }
}

void ConvexShape::vertexHeights(const Vec3& direction, float* out) const {
  // Eigen's 3-vector dot: x + (y + z), each product rounded.
  const std::size_t n = vertices_.size();
  assert(vertexX_.size() == n);
  std::size_t i = 0;
  DYNAHAND_SIMD_DISPATCH(vertexHeightLanes, vertexX_.data(), vertexY_.data(), vertexZ_.data(), n,
                         direction, out, &i);
  for (; i < n; ++i) out[i] = direction.dot(vertices_[i]);
}

float ConvexShape::nearestEdge(const Vec3& p, int* edge, float* t) const {
  // Eight edges per step, each lane keeping its own first minimum; then the least of the
  // lanes, the lowest index among equal ones: the same edge as one by one.
  const std::size_t n = edgeAx_.size();
  float best[simd::kLanes];
  std::int32_t index[simd::kLanes];
  DYNAHAND_SIMD_DISPATCH(nearestEdgeLanes, edgeAx_.data(), edgeAy_.data(), edgeAz_.data(),
                         edgeDx_.data(), edgeDy_.data(), edgeDz_.data(), edgeInvLen2_.data(), n, p,
                         best, index);
  std::int32_t which = index[0];
  float result = best[0];
  simd::foldLeastLane(best, index, result, which);
  const auto i = static_cast<std::size_t>(which);
  const float wx = p.x() - edgeAx_[i], wy = p.y() - edgeAy_[i], wz = p.z() - edgeAz_[i];
  const float along = (wx * edgeDx_[i] + wy * edgeDy_[i]) + wz * edgeDz_[i];
  *t = std::min(std::max(along * edgeInvLen2_[i], 0.0f), 1.0f);
  *edge = which;
  return result;
}

void ConvexShape::computeDerived() {
  buildEdges();
  // Fan-triangulate every face and form tetrahedra with a reference point near the centre;
  // accumulate volume, first moment and the second-moment (covariance) tensor in double.
  Vec3d ref = Vec3d::Zero();
  for (const Vec3& v : vertices_) ref += v.cast<double>();
  ref /= static_cast<double>(vertices_.size());
  // Covariance of the canonical tetrahedron (0, e1, e2, e3), times 120.
  Mat3d canonical;
  canonical << 2, 1, 1, 1, 2, 1, 1, 1, 2;
  canonical /= 120.0;
  double volume = 0.0;
  Vec3d moment = Vec3d::Zero();
  Mat3d covariance = Mat3d::Zero();
  for (const Face& face : faces_) {
    const Vec3d a = vertices_[static_cast<std::size_t>(face.vertices[0])].cast<double>() - ref;
    for (std::size_t i = 1; i + 1 < face.vertices.size(); ++i) {
      const Vec3d b = vertices_[static_cast<std::size_t>(face.vertices[i])].cast<double>() - ref;
      const Vec3d c =
          vertices_[static_cast<std::size_t>(face.vertices[i + 1])].cast<double>() - ref;
      Mat3d edges;
      edges << a, b, c;
      const double det = edges.determinant();  // 6 x signed volume (CCW faces: positive)
      volume += det / 6.0;
      moment += det / 6.0 * (a + b + c) / 4.0;
      covariance += det * edges * canonical * edges.transpose();
    }
  }
  volume_ = static_cast<float>(volume);
  if (!(volume > 0.0)) return;
  const Vec3d centroidRel = moment / volume;
  // Move the covariance to the centroid (parallel axis), per unit mass.
  const Mat3d covCentroid = covariance / volume - centroidRel * centroidRel.transpose();
  const Mat3d inertia = Mat3d::Identity() * covCentroid.trace() - covCentroid;
  unitInertia_ = inertia.cast<float>();
  centroid_ = (centroidRel + ref).cast<float>();

  inscribedRadius_ = std::numeric_limits<float>::infinity();
  for (const Face& face : faces_) {
    inscribedRadius_ = std::min(inscribedRadius_, face.offset - face.normal.dot(centroid_));
  }
  boundingRadius_ = 0.0f;
  for (const Vec3& v : vertices_)
    boundingRadius_ = std::max(boundingRadius_, (v - centroid_).norm());
}

bool ConvexShape::onFacePolygon(const Face& face, const Vec3& projected) const {
  // Inside the polygon when on the inner side of every edge (CCW about the normal).
  const std::size_t count = face.vertices.size();
  if (count == 0) return true;
  const Vec3* a = &vertices_[static_cast<std::size_t>(face.vertices[count - 1])];
  for (std::size_t i = 0; i < count; ++i) {  // edges (last, 0), (0, 1), ...
    const Vec3& b = vertices_[static_cast<std::size_t>(face.vertices[i])];
    if ((b - *a).cross(projected - *a).dot(face.normal) < 0.0f) return false;
    a = &b;
  }
  return true;
}

float ConvexShape::query(const Vec3& p, Vec3* closest, int* face) const {
  // Largest plane distance: the answer for inside points, a lower bound outside.
  int maxFace = 0;
  float maxDist = -std::numeric_limits<float>::infinity();
  for (std::size_t f = 0; f < faces_.size(); ++f) {
    const float d = faces_[f].normal.dot(p) - faces_[f].offset;
    if (d > maxDist) {
      maxDist = d;
      maxFace = static_cast<int>(f);
    }
  }
  return queryFromPlane(p, maxDist, maxFace, closest, face);
}

float ConvexShape::queryFromPlane(const Vec3& p, float maxDist, int maxFace, Vec3* closest,
                                  int* face) const {
  if (maxDist <= 0.0f) {
    if (closest) *closest = p - maxDist * faces_[static_cast<std::size_t>(maxFace)].normal;
    if (face) *face = maxFace;
    return maxDist;
  }
  // Outside. When p's foot on the farthest plane lies on that face, it is the closest
  // point: no surface point can be nearer than the largest plane distance.
  {
    const Face& top = faces_[static_cast<std::size_t>(maxFace)];
    const Vec3 projected = p - maxDist * top.normal;
    if (onFacePolygon(top, projected)) {
      if (closest) *closest = projected;
      if (face) *face = maxFace;
      return maxDist;
    }
  }
  // Otherwise it lies on an edge: a point inside a face other than the farthest one would be
  // nearer than that face's plane distance, which is at most the largest. Every edge is on
  // the surface, so the nearest edge point is the closest surface point.
  int edge = 0;
  float t = 0.0f;
  const float d2 = nearestEdge(p, &edge, &t);
  const EdgeInfo& e = edges_[static_cast<std::size_t>(edge)];
  if (closest) {
    const auto i = static_cast<std::size_t>(edge);
    *closest =
        Vec3(edgeAx_[i], edgeAy_[i], edgeAz_[i]) + t * Vec3(edgeDx_[i], edgeDy_[i], edgeDz_[i]);
  }
  if (face) {
    // The faces holding the point: the edge's two, or all around a vertex end.
    *face = t <= 0.0f   ? vertexLowestFace_[static_cast<std::size_t>(e.a)]
            : t >= 1.0f ? vertexLowestFace_[static_cast<std::size_t>(e.b)]
                        : e.lowestFace;
  }
  return std::sqrt(d2);
}

float ConvexShape::signedDistance(const Vec3& p) const {
  return query(p, nullptr, nullptr);
}

Vec3 ConvexShape::closestPoint(const Vec3& p) const {
  Vec3 q;
  query(p, &q, nullptr);
  return q;
}

int ConvexShape::closestFace(const Vec3& p) const {
  int f = 0;
  query(p, nullptr, &f);
  return f;
}

Vec3 ConvexShape::support(const Vec3& direction) const {
  // The first vertex of the largest dot product (Eigen's dot: x + (y + z)). Eight vertices per
  // step, each lane keeping its own first largest; then the largest of the lanes, the earliest
  // among equal ones, and the rest one by one: the same vertex as one by one. (Below eight
  // vertices the lanes' reduction costs what it saves.)
  const std::size_t n = vertices_.size();
  std::size_t best = 0, i = 0;
  float bestDot = -std::numeric_limits<float>::infinity();
  if (n >= 8) {
    float value[simd::kLanes];
    std::int32_t index[simd::kLanes];
    DYNAHAND_SIMD_DISPATCH(supportLanes, vertexX_.data(), vertexY_.data(), vertexZ_.data(), n,
                           direction, bestDot, value, index, &i);
    std::int32_t which = 0;
    simd::foldLargestLane(value, index, bestDot, which);
    best = static_cast<std::size_t>(which);
  }
  for (; i < n; ++i) {
    const float d = vertices_[i].dot(direction);
    if (d > bestDot) {
      bestDot = d;
      best = i;
    }
  }
  return vertices_[best];
}

std::optional<float> ConvexShape::raycast(const Vec3& origin, const Vec3& dir, float maxT) const {
  // Clip the parameter interval [0, maxT] against every face half-space (Cyrus-Beck).
  float tEnter = 0.0f;
  float tExit = maxT;
  for (const Face& face : faces_) {
    const float dist = face.normal.dot(origin) - face.offset;  // > 0: outside this plane
    const float rate = face.normal.dot(dir);
    if (rate == 0.0f) {
      if (dist > 0.0f) return std::nullopt;  // parallel and outside
      continue;
    }
    const float t = -dist / rate;
    if (rate < 0.0f) {
      tEnter = std::max(tEnter, t);
    } else {
      tExit = std::min(tExit, t);
    }
    if (tEnter > tExit) return std::nullopt;
  }
  return tEnter;
}

}  // namespace dynahand::physics
