// ConvexShape's per-vertex and per-edge scans, eight at a time: a kernel file of the SIMD layer
// (core/simd/for_each_level.inl compiles it once per level inside convex_shape.cpp's anonymous
// namespace). Dot products sum as Eigen's 3-vector dot does, x + (y + z), each product
// rounded. No include guard, no includes.

// out[i] = direction . vertex i for i in [0, n rounded down to 8); `done` = that count.
inline void vertexHeightLanes(const float* x, const float* y, const float* z, std::size_t n,
                              const Vec3& direction, float* out, std::size_t* done) {
  const FloatW dx = splat(direction.x()), dy = splat(direction.y()), dz = splat(direction.z());
  std::size_t i = 0;
  for (; i + kLanes <= n; i += kLanes)
    store(out + i, dx * load(x + i) + (dy * load(y + i) + dz * load(z + i)));
  *done = i;
}

// The squared distance from p to each edge's closest point, each lane keeping its first
// minimum over edges lane, lane + 8, ... (n a multiple of 8): best[lane], index[lane].
inline void nearestEdgeLanes(const float* ax, const float* ay, const float* az, const float* ddx,
                             const float* ddy, const float* ddz, const float* invLen2,
                             std::size_t n, const Vec3& p, float* best, std::int32_t* index) {
  const FloatW px = splat(p.x()), py = splat(p.y()), pz = splat(p.z());
  const FloatW zero = splat(0.0f), one = splat(1.0f);
  FloatW bestV = splat(std::numeric_limits<float>::infinity());
  IntW indexV = splat(std::int32_t{0});
  IntW lane = iota();
  const IntW step = splat(std::int32_t{kLanes});
  for (std::size_t e = 0; e < n; e += kLanes) {
    const FloatW wx = px - load(ax + e), wy = py - load(ay + e), wz = pz - load(az + e);
    const FloatW dx = load(ddx + e), dy = load(ddy + e), dz = load(ddz + e);
    const FloatW along = (wx * dx + wy * dy) + wz * dz;
    const FloatW s = min(max(along * load(invLen2 + e), zero), one);
    const FloatW ex = wx - s * dx, ey = wy - s * dy, ez = wz - s * dz;
    const FloatW d2 = (ex * ex + ey * ey) + ez * ez;
    const MaskW closer = d2 < bestV;
    bestV = min(d2, bestV);
    indexV = select(closer, lane, indexV);
    lane = lane + step;
  }
  store(best, bestV);
  store(index, indexV);
}

// direction . vertex over vertices [0, n rounded down to 8), each lane keeping its first
// largest (starting from `start`): value[lane], index[lane]; `done` = the vertices scanned.
inline void supportLanes(const float* x, const float* y, const float* z, std::size_t n,
                         const Vec3& direction, float start, float* value, std::int32_t* index,
                         std::size_t* done) {
  const FloatW dx = splat(direction.x()), dy = splat(direction.y()), dz = splat(direction.z());
  FloatW bestV = splat(start);
  IntW indexV = splat(std::int32_t{0});
  IntW lane = iota();
  const IntW step = splat(std::int32_t{kLanes});
  std::size_t i = 0;
  for (; i + kLanes <= n; i += kLanes) {
    const FloatW h = load(x + i) * dx + (load(y + i) * dy + load(z + i) * dz);
    const MaskW larger = h > bestV;
    bestV = select(larger, h, bestV);
    indexV = select(larger, lane, indexV);
    lane = lane + step;
  }
  store(value, bestV);
  store(index, indexV);
  *done = i;
}
