// The largest plane distance of one point over a body's plane table, eight planes at a time:
// a kernel file of the SIMD layer (core/simd/for_each_level.inl compiles it once per level
// inside posed_bodies.cpp's anonymous namespace). No include guard, no includes.

// Lane k keeps the largest of the distances ((nx qx + ny qy) + nz qz) - o of planes k, k + 8,
// ... (n a multiple of 8) and the first plane holding it: best[k], index[k]. Stops after the
// eight planes where any distance exceeds stopAbove (the caller then only needs to know that).
inline void maxPlaneDistanceLanes(const float* nx, const float* ny, const float* nz,
                                  const float* o, std::size_t n, const Vec3& q, float stopAbove,
                                  float* best, std::int32_t* index) {
  const FloatW qx = splat(q.x()), qy = splat(q.y()), qz = splat(q.z());
  const FloatW stop = splat(stopAbove);
  FloatW bestV = splat(-1e30f);
  IntW indexV = splat(std::int32_t{0});
  IntW plane = iota();
  const IntW step = splat(std::int32_t{kLanes});
  for (std::size_t f = 0; f < n; f += kLanes) {
    const FloatW d = ((load(nx + f) * qx + load(ny + f) * qy) + load(nz + f) * qz) - load(o + f);
    const MaskW better = d > bestV;
    bestV = max(d, bestV);  // == better ? d : bestV (no NaNs here)
    indexV = select(better, plane, indexV);
    plane = plane + step;
    if (bits(d > stop) != 0) break;
  }
  store(best, bestV);
  store(index, indexV);
}
