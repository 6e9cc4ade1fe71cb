// The bulk queries' kernels (PosedBodies::nearestMany, nearestPlanarMany, nearestManySettling
// and nearest()'s sphere bounds): eight points or eight bodies at a time, one per lane. A kernel
// file of the SIMD layer (core/simd/for_each_level.inl compiles it once per level inside
// posed_bodies.cpp's anonymous namespace, after kCompress). No include guard, no includes.

// |p - c| - r lane by lane: sphereGap's arithmetic (x^2 + (y^2 + z^2), Eigen's order for a
// 3-vector's squared norm), so the one-point queries give the same bits.
DYNAHAND_SIMD_INLINE FloatW sphereGapLanes(FloatW px, FloatW py, FloatW pz, FloatW cx, FloatW cy,
                                           FloatW cz, FloatW r) {
  const FloatW dx = px - cx, dy = py - cy, dz = pz - cz;
  return sqrt(dx * dx + (dy * dy + dz * dz)) - r;
}

// Bounding-sphere lower bounds max(|p - c_i| - r_i, 0) of bodies 0 .. count - 1 into bounds
// (sphere SoA padded past count to a multiple of eight; bounds has room for as many).
inline void sphereBoundsLanes(const Vec3& p, const float* cx, const float* cy, const float* cz,
                              const float* r, int count, float* bounds) {
  const FloatW px = splat(p.x()), py = splat(p.y()), pz = splat(p.z());
  const FloatW zero = splat(0.0f);
  for (int o = 0; o < count; o += kLanes)
    store(bounds + o,
          max(sphereGapLanes(px, py, pz, load(cx + o), load(cy + o), load(cz + o), load(r + o)),
              zero));
}

// Pose::inverseTransform of eight points (PosedBodies::toLocal's arithmetic, operation for
// operation: v + 2w (u x v) + u x 2(u x v) with u the conjugate's vector part).
DYNAHAND_SIMD_INLINE void toLocalLanes(const Quat& rotation, const Vec3& t, FloatW px, FloatW py,
                                       FloatW pz, FloatW& qx, FloatW& qy, FloatW& qz) {
  const FloatW w = splat(rotation.w());
  const FloatW ux = splat(-rotation.x()), uy = splat(-rotation.y()), uz = splat(-rotation.z());
  const FloatW dx = px - splat(t.x()), dy = py - splat(t.y()), dz = pz - splat(t.z());
  FloatW cx = uy * dz - uz * dy, cy = uz * dx - ux * dz, cz = ux * dy - uy * dx;
  cx = cx + cx;
  cy = cy + cy;
  cz = cz + cz;
  qx = (dx + w * cx) + (uy * cz - uz * cy);
  qy = (dy + w * cy) + (uz * cx - ux * cz);
  qz = (dz + w * cz) + (ux * cy - uy * cx);
}

// Eight points (wx, wy, wz) against one body (rotation, t; its plane table nx, ny, nz, o of
// `count` planes, a multiple of eight): the points in the body frame into (lx, ly, lz), each
// one's largest plane distance ((nx qx + ny qy) + nz qz) - o into largest and the first plane
// holding it into face (maxPlaneDistance's answer). Stops after the eight planes where every
// lane has passed its stop; such a lane then only has a distance above its stop.
inline void scanEightLanes(const Quat& rotation, const Vec3& t, const float* wx, const float* wy,
                           const float* wz, const float* nx, const float* ny, const float* nz,
                           const float* o, std::size_t count, const float* stop, float* lx,
                           float* ly, float* lz, float* largest, std::int32_t* face) {
  FloatW qx, qy, qz;
  toLocalLanes(rotation, t, load(wx), load(wy), load(wz), qx, qy, qz);
  store(lx, qx);
  store(ly, qy);
  store(lz, qz);
  FloatW best = splat(-1e30f);
  IntW index = splat(std::int32_t{0});
  IntW plane = splat(std::int32_t{0});  // f in every lane
  const IntW one = splat(std::int32_t{1});
  const FloatW stopAbove = load(stop);
  for (std::size_t group = 0; group < count; group += kLanes) {
#pragma GCC unroll 8
    for (std::size_t f = group; f < group + kLanes; ++f) {
      const FloatW d = ((splat(nx[f]) * qx + splat(ny[f]) * qy) + splat(nz[f]) * qz) - splat(o[f]);
      const MaskW better = d > best;
      best = max(d, best);  // == better ? d : best (no NaNs here)
      index = select(better, plane, index);
      plane = plane + one;
    }
    if (all(best > stopAbove)) break;
  }
  store(largest, best);
  store(face, index);
}

// scanEightLanes over the listed points list[0 .. count) (indices into the point SoA px, py,
// pz, with their stop distances in best), eight at a time, the last eight padded with the last
// point: each listed point's stop, body-frame point, largest distance and face at its position
// in stop, lx, ly, lz, largest and face (room for count rounded up to eight).
inline void scanListedLanes(const Quat& rotation, const Vec3& t, const float* px, const float* py,
                            const float* pz, const float* best, const int* list, std::size_t count,
                            const float* nx, const float* ny, const float* nz, const float* o,
                            std::size_t planes, float* stop, float* lx, float* ly, float* lz,
                            float* largest, std::int32_t* face) {
  alignas(32) float wx[kLanes], wy[kLanes], wz[kLanes];
  for (std::size_t start = 0; start < count; start += kLanes) {
    for (std::size_t k = 0; k < kLanes; ++k) {
      const auto i = static_cast<std::size_t>(list[std::min(start + k, count - 1)]);
      wx[k] = px[i];
      wy[k] = py[i];
      wz[k] = pz[i];
      stop[start + k] = best[i];
    }
    scanEightLanes(rotation, t, wx, wy, wz, nx, ny, nz, o, planes, stop + start, lx + start,
                   ly + start, lz + start, largest + start, face + start);
  }
}

// The points (of `padded`, the last eight holding the real ones of lastLanes) that body b
// (centre c, radius r) could still beat or tie, i.e. not sphereGap > best, and that were not
// tested against it first (`first`, bodies as floats): their indices, in order, into `list`
// (room for seven more past the count: the appends write eight at a time), their count into
// *listed.
inline void reachablePointsLanes(const float* px, const float* py, const float* pz,
                                 const float* best, const float* first, std::size_t padded,
                                 unsigned lastLanes, float b, float cx, float cy, float cz, float r,
                                 int* list, int* listed) {
  const FloatW vcx = splat(cx), vcy = splat(cy), vcz = splat(cz), vr = splat(r), vb = splat(b);
  int count = 0;
  for (std::size_t start = 0; start < padded; start += kLanes) {
    const FloatW gap =
        sphereGapLanes(load(px + start), load(py + start), load(pz + start), vcx, vcy, vcz, vr);
    unsigned mask = bits(gap <= load(best + start)) & ~bits(load(first + start) == vb) & 0xffu;
    if (start + kLanes == padded) mask &= lastLanes;
    // Branch-free append (the reachable lanes are unpredictable): the eight lane offsets of
    // the mask's set bits, compressed by a table, written whole.
    store(list + count, splat(static_cast<std::int32_t>(start)) + load(kCompress.lanes[mask]));
    count += std::popcount(mask);
  }
  *listed = count;
}

// Settling (nearestManySettling): clears settled[i] for every point i that body b could still
// hold at its best distance (its sphere bound does not exceed it, or b is its first body)
// while that distance is above settle (b's running errFit). Points as in reachablePointsLanes.
inline void unsettleByBodyLanes(const float* px, const float* py, const float* pz,
                                const float* best, const float* first, std::size_t padded,
                                unsigned lastLanes, float b, float cx, float cy, float cz, float r,
                                float settle, std::uint8_t* settled) {
  const FloatW vcx = splat(cx), vcy = splat(cy), vcz = splat(cz), vr = splat(r), vb = splat(b);
  const FloatW vs = splat(settle);
  for (std::size_t start = 0; start < padded; start += kLanes) {
    const FloatW d = load(best + start);
    const FloatW gap =
        sphereGapLanes(load(px + start), load(py + start), load(pz + start), vcx, vcy, vcz, vr);
    unsigned mask = (bits(gap <= d) | bits(load(first + start) == vb)) & bits(vs < d);
    if (start + kLanes == padded) mask &= lastLanes;
    if (mask == 0) continue;
    for (int k = 0; k < kLanes; ++k)
      if (mask >> k & 1u) settled[start + static_cast<std::size_t>(k)] = 0;
  }
}
