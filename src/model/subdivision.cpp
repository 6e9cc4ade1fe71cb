// Catmull-Clark subdivision (Catmull & Clark 1978) for polygon meshes. Boundary edges (one
// adjacent face) use their midpoint; the cages of the authors' model are closed.
#include <cassert>
#include <map>
#include <utility>

#include "dynahand/model_intel.h"

namespace dynahand::model {

PolygonMesh catmullClark(const PolygonMesh& mesh) {
  const size_t vertexCount = mesh.vertices.size();
  struct Edge {
    int index = -1;  // new vertex index of the edge point
    std::vector<int> faces;
  };
  std::map<std::pair<int, int>, Edge> edges;  // ordered: deterministic numbering
  auto key = [](int a, int b) { return a < b ? std::make_pair(a, b) : std::make_pair(b, a); };

  std::vector<Vec3> facePoints(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    assert(face.size() >= 3);
    Vec3 sum = Vec3::Zero();
    for (size_t i = 0; i < face.size(); ++i) {
      sum += mesh.vertices[static_cast<size_t>(face[i])];
      edges[key(face[i], face[(i + 1) % face.size()])].faces.push_back(static_cast<int>(f));
    }
    facePoints[f] = sum / static_cast<float>(face.size());
  }

  PolygonMesh out;
  out.vertices.resize(vertexCount);  // moved originals first, then face points, then edge points
  const int faceBase = static_cast<int>(vertexCount);
  for (const Vec3& p : facePoints) out.vertices.push_back(p);
  std::vector<Vec3> faceSum(vertexCount, Vec3::Zero());
  std::vector<Vec3> midSum(vertexCount, Vec3::Zero());
  std::vector<int> faceCount(vertexCount, 0);
  std::vector<int> edgeCount(vertexCount, 0);
  for (auto& [ends, edge] : edges) {
    const Vec3& a = mesh.vertices[static_cast<size_t>(ends.first)];
    const Vec3& b = mesh.vertices[static_cast<size_t>(ends.second)];
    Vec3 point = 0.5f * (a + b);
    if (edge.faces.size() == 2) {
      point = 0.25f * (a + b + facePoints[static_cast<size_t>(edge.faces[0])] +
                       facePoints[static_cast<size_t>(edge.faces[1])]);
    }
    edge.index = static_cast<int>(out.vertices.size());
    out.vertices.push_back(point);
    for (const int v : {ends.first, ends.second}) {
      midSum[static_cast<size_t>(v)] += 0.5f * (a + b);
      ++edgeCount[static_cast<size_t>(v)];
    }
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (const int v : mesh.faces[f]) {
      faceSum[static_cast<size_t>(v)] += facePoints[f];
      ++faceCount[static_cast<size_t>(v)];
    }
  }
  for (size_t v = 0; v < vertexCount; ++v) {
    const Vec3& p = mesh.vertices[v];
    if (faceCount[v] == 0) {
      out.vertices[v] = p;  // unused vertex
      continue;
    }
    const float n = static_cast<float>(edgeCount[v]);
    const Vec3 f = faceSum[v] / static_cast<float>(faceCount[v]);
    const Vec3 r = midSum[v] / n;
    out.vertices[v] = (f + 2.0f * r + (n - 3.0f) * p) / n;
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    const size_t k = face.size();
    for (size_t i = 0; i < k; ++i) {
      const int prev = face[(i + k - 1) % k];
      const int next = face[(i + 1) % k];
      out.faces.push_back({face[i], edges.at(key(face[i], next)).index,
                           faceBase + static_cast<int>(f), edges.at(key(prev, face[i])).index});
    }
  }
  return out;
}

}  // namespace dynahand::model
