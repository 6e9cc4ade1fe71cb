#include "physics/face_cells.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

#include "dynahand/convex_shape.h"

namespace dynahand::physics {
namespace {

// Sets the bits of the faces (near[f]) whose plane distance at (x, y, z) is within reach of
// the largest; the planes as SoA, padded to a multiple of four (the padding never within
// reach). Four planes per SSE instruction where there is SSE.
void markCandidates(const std::vector<float>& nx, const std::vector<float>& ny,
                    const std::vector<float>& nz, const std::vector<float>& offset,
                    const std::vector<int>& near, float x, float y, float z, float reach,
                    std::vector<float>& distance, std::uint64_t* mask) {
  const std::size_t n = nx.size();
  distance.resize(n);
  float* d = distance.data();
#if defined(__SSE2__)
  const __m128 px = _mm_set1_ps(x), py = _mm_set1_ps(y), pz = _mm_set1_ps(z);
  __m128 top4 = _mm_set1_ps(-std::numeric_limits<float>::infinity());
  for (std::size_t f = 0; f < n; f += 4) {
    const __m128 v = _mm_sub_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_loadu_ps(nx.data() + f), px),
                                                      _mm_mul_ps(_mm_loadu_ps(ny.data() + f), py)),
                                           _mm_mul_ps(_mm_loadu_ps(nz.data() + f), pz)),
                                _mm_loadu_ps(offset.data() + f));
    _mm_storeu_ps(d + f, v);
    top4 = _mm_max_ps(top4, v);
  }
  top4 = _mm_max_ps(top4, _mm_shuffle_ps(top4, top4, _MM_SHUFFLE(2, 3, 0, 1)));
  top4 = _mm_max_ps(top4, _mm_shuffle_ps(top4, top4, _MM_SHUFFLE(1, 0, 3, 2)));
  const float top = _mm_cvtss_f32(top4);
#else
  float top = -std::numeric_limits<float>::infinity();
  for (std::size_t f = 0; f < n; ++f) {
    d[f] = nx[f] * x + ny[f] * y + nz[f] * z - offset[f];
    top = std::max(top, d[f]);
  }
#endif
  const float keep = top - reach;
  for (std::size_t f = 0; f < near.size(); ++f) {
    if (d[f] < keep) continue;
    const auto face = static_cast<std::size_t>(near[f]);
    mask[face / 64] |= std::uint64_t{1} << (face % 64);
  }
}

}  // namespace

FaceCells::FaceCells(const ConvexShape& shape) {
  const auto& faces = shape.faces();
  words_ = std::max(1, static_cast<int>((faces.size() + 63) / 64));
  Vec3 lo = Vec3::Constant(std::numeric_limits<float>::infinity());
  Vec3 hi = -lo;
  for (const Vec3& v : shape.vertices()) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  if (faces.empty() || !lo.allFinite() || !hi.allFinite()) return;  // no grid: every face
  lo.array() -= kMargin;
  hi.array() += kMargin;
  const auto count = [](float extent) {
    return static_cast<std::size_t>(std::ceil(extent / kCellSize));
  };
  const std::size_t nx = count(hi.x() - lo.x()), ny = count(hi.y() - lo.y()),
                    nz = count(hi.z() - lo.z());
  // Cell indices are computed in float by the lookups: exact below 2^24.
  if (nx * ny * nz >= (std::size_t{1} << 24)) return;
  grid_ = Grid{lo.x(),
               lo.y(),
               lo.z(),
               1.0f / kCellSize,
               static_cast<float>(nx),
               static_cast<float>(ny),
               static_cast<float>(nz)};
  masks_.assign(nx * ny * nz * static_cast<std::size_t>(words_), 0);

  // A point q of a cell is within h (half the cell's diagonal) of its centre c, so every
  // plane distance at q is within h of the one at c (unit normals): the largest at q belongs
  // to a face within 2h of the largest at c. kSlack covers the float rounding of the scans'
  // arithmetic, of finding q's cell and of the distances here (all ~1e-8 m), so a face left
  // out is strictly below the largest in the scans' float arithmetic as well.
  constexpr double kSlack = 1e-5;  // m
  const double cell = kCellSize;
  const auto cellReach = static_cast<float>(std::sqrt(3.0) * cell + kSlack);
  // Blocks of kBlock^3 cells first: a cell centre is within r of its block's centre, so its
  // candidates are among the faces within 2r + 2h of the largest distance there.
  constexpr std::size_t kBlock = 4;
  const double r = std::sqrt(3.0) * 0.5 * static_cast<double>(kBlock - 1) * cell;
  const auto blockReach = static_cast<float>(2.0 * r + std::sqrt(3.0) * cell + kSlack);
  const std::size_t n = faces.size();
  std::vector<float> distance(n);
  // A block's faces within reach, padded to a multiple of four with planes that never come
  // near (normal 0, offset 1e30), as SoA for four-wide distances.
  std::vector<int> near;
  std::vector<float> cellDistance;
  std::vector<float> nearX, nearY, nearZ, nearO;
  const auto centre = [&](double index, float origin) {
    return static_cast<float>(static_cast<double>(origin) + (index + 0.5) * cell);
  };
  const double half = 0.5 * static_cast<double>(kBlock - 1);
  for (std::size_t bk = 0; bk < nz; bk += kBlock) {
    for (std::size_t bj = 0; bj < ny; bj += kBlock) {
      for (std::size_t bi = 0; bi < nx; bi += kBlock) {
        const Vec3 c(centre(static_cast<double>(bi) + half, lo.x()),
                     centre(static_cast<double>(bj) + half, lo.y()),
                     centre(static_cast<double>(bk) + half, lo.z()));
        float largest = -std::numeric_limits<float>::infinity();
        for (std::size_t f = 0; f < n; ++f) {
          distance[f] = faces[f].normal.dot(c) - faces[f].offset;
          largest = std::max(largest, distance[f]);
        }
        near.clear();
        nearX.clear();
        nearY.clear();
        nearZ.clear();
        nearO.clear();
        for (std::size_t f = 0; f < n; ++f) {
          if (distance[f] < largest - blockReach) continue;
          near.push_back(static_cast<int>(f));
          nearX.push_back(faces[f].normal.x());
          nearY.push_back(faces[f].normal.y());
          nearZ.push_back(faces[f].normal.z());
          nearO.push_back(faces[f].offset);
        }
        while (nearX.size() % 4 != 0) {
          nearX.push_back(0.0f);
          nearY.push_back(0.0f);
          nearZ.push_back(0.0f);
          nearO.push_back(1e30f);
        }
        for (std::size_t k = bk; k < std::min(bk + kBlock, nz); ++k) {
          const float z = centre(static_cast<double>(k), lo.z());
          for (std::size_t j = bj; j < std::min(bj + kBlock, ny); ++j) {
            const float y = centre(static_cast<double>(j), lo.y());
            for (std::size_t i = bi; i < std::min(bi + kBlock, nx); ++i) {
              const float x = centre(static_cast<double>(i), lo.x());
              markCandidates(nearX, nearY, nearZ, nearO, near, x, y, z, cellReach, cellDistance,
                             masks_.data() + ((k * ny + j) * nx + i) * words_);
            }
          }
        }
      }
    }
  }
}

}  // namespace dynahand::physics
