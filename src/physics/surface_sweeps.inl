// The surface rows' sweeps, eight rows (one batch) at a time: a kernel file of the SIMD layer
// (core/simd/for_each_level.inl compiles it once per level inside surface_batches.cpp's
// anonymous namespace, after SurfaceSweeps, its access to SurfaceBatches). Each lane does the
// arithmetic of SurfaceBatches::solveFallback, operation for operation, so the same bits.
// No include guard, no includes.

// SurfaceBatches::fillBatch with two 8 x 8 transposes: a row's fourteen floats (normal ...
// upper, bytes 4-60) are read as floats 0-7 and 6-13. The same operations per value.
inline void fillBatchLanes(SurfaceSweeps::Batch& b, const PreparedSurfaceRow* const* rows,
                           const float* copies) {
  static_assert(sizeof(PreparedSurfaceRow) == 60, "slot, then fourteen floats");
  FloatW first[kLanes], second[kLanes];
  for (int k = 0; k < kLanes; ++k) {
    const float* f = reinterpret_cast<const float*>(rows[k]) + 1;
    first[k] = load(f);
    second[k] = load(f + 6);
  }
  transpose8(first);
  transpose8(second);
  const FloatW c = load(copies);
  store(b.nx, first[0]);
  store(b.ny, first[1]);
  store(b.nz, first[2]);
  store(b.ax, first[3]);
  store(b.ay, first[4]);
  store(b.az, first[5]);
  store(b.ix, second[0] * c);
  store(b.iy, second[1] * c);
  store(b.iz, second[2] * c);
  store(b.effMass, second[3] / c);
  store(b.bias, second[4]);
  store(b.relaxBias, second[5]);
  store(b.lower, second[6]);
  store(b.upper, second[7]);
  store(b.impulse, splat(0.0f));
}

// The bodies of a sweep's eight lanes, their velocities in registers. A lane changes body
// only where its column moves to the next slot (about one lane every sixth batch, rarely
// several at once), so lanes are written back and loaded one by one.
struct EightBodies {
  FloatW vx, vy, vz, wx, wy, wz;
  FloatW pull;  // the body's inverse mass x the lane's massScale_ (the normal's factor)

  // Lanes in `lanes` (a bit mask) write their velocities back to their bodies p[k].
  DYNAHAND_SIMD_INLINE void writeBack(unsigned lanes, SolverBody* const p[kLanes]) const {
    alignas(32) float t[6][kLanes];
    store(t[0], vx);
    store(t[1], vy);
    store(t[2], vz);
    store(t[3], wx);
    store(t[4], wy);
    store(t[5], wz);
    for (; lanes != 0; lanes &= lanes - 1) {
      const int k = __builtin_ctz(lanes);
      SolverBody& body = *p[k];
      body.v = Vec3(t[0][k], t[1][k], t[2][k]);
      body.w = Vec3(t[3][k], t[4][k], t[5][k]);
    }
  }
  // Lane k takes `body`, whose rows pull with `scale` times its inverse mass.
  DYNAHAND_SIMD_INLINE void loadLane(int k, const SolverBody& body, float scale) {
    const MaskW m = laneMask(k);
    vx = select(m, splat(body.v.x()), vx);
    vy = select(m, splat(body.v.y()), vy);
    vz = select(m, splat(body.v.z()), vz);
    wx = select(m, splat(body.w.x()), wx);
    wy = select(m, splat(body.w.y()), wy);
    wz = select(m, splat(body.w.z()), wz);
    pull = select(m, splat(body.invMass * scale), pull);
  }
};

// One batch's rows. The chain through a body's velocity is the row arithmetic alone; the
// clamp's target is formed off that chain.
DYNAHAND_SIMD_INLINE void solveBatch(SurfaceSweeps::Batch& b, EightBodies& lane, bool useBias) {
  const FloatW effMass = load(b.effMass);
  const FloatW old = load(b.impulse);
  const FloatW base = old - effMass * load(useBias ? b.bias : b.relaxBias);
  const FloatW jv = ((load(b.nx) * lane.vx + load(b.ny) * lane.vy) + load(b.nz) * lane.vz) +
                    ((load(b.ax) * lane.wx + load(b.ay) * lane.wy) + load(b.az) * lane.wz);
  const FloatW clamped = min(max(base - effMass * jv, load(b.lower)), load(b.upper));
  store(b.impulse, clamped);
  const FloatW d = clamped - old;
  lane.vx = lane.vx + d * (load(b.nx) * lane.pull);
  lane.vy = lane.vy + d * (load(b.ny) * lane.pull);
  lane.vz = lane.vz + d * (load(b.nz) * lane.pull);
  lane.wx = lane.wx + d * load(b.ix);
  lane.wy = lane.wy + d * load(b.iy);
  lane.wz = lane.wz + d * load(b.iz);
}

// Lanes `lanes` (a bit mask) of batch i take their bodies (p: where they are).
DYNAHAND_SIMD_INLINE void loadLanes(SurfaceBatches& sweep, std::vector<SolverBody>& bodies,
                                    std::size_t i, unsigned lanes, SolverBody* p[kLanes],
                                    EightBodies& lane) {
  for (; lanes != 0; lanes &= lanes - 1) {
    const int k = __builtin_ctz(lanes);
    const int slot = SurfaceSweeps::lanes(sweep)[i].slot[k];
    p[k] = SurfaceSweeps::laneBody(sweep, bodies, slot);
    lane.loadLane(k, *p[k], SurfaceSweeps::massScale(sweep)[static_cast<std::size_t>(slot)]);
  }
}

// Batches [from, to) of the first M sweeps (each has them). Each lane runs down its column,
// mostly on one slot for many batches in a row: its body stays in registers until the lane
// moves to another slot, and until `to`.
template <int M>
DYNAHAND_SIMD_INLINE void sweepPhase(SurfaceBatches* const* sweeps,
                                     std::vector<SolverBody>* const* bodies, std::size_t from,
                                     std::size_t to, bool useBias) {
  constexpr unsigned kAll = (1u << kLanes) - 1;
  SolverBody* p[M][kLanes];
  EightBodies lane[M];
#pragma GCC unroll 4
  for (int w = 0; w < M; ++w) {
    lane[w].vx = lane[w].vy = lane[w].vz = lane[w].wx = lane[w].wy = lane[w].wz = lane[w].pull =
        splat(0.0f);
    loadLanes(*sweeps[w], *bodies[w], from, kAll, p[w], lane[w]);
  }
  for (std::size_t i = from; i < to; ++i) {
#pragma GCC unroll 4
    for (int w = 0; w < M; ++w) {
      const unsigned changed = SurfaceSweeps::changed(*sweeps[w])[i];
      if (i == from || changed == 0) continue;
      // Every leaving body is written back before any arriving one is read: a slot can
      // leave one lane and enter another at the same batch.
      lane[w].writeBack(changed, p[w]);
      loadLanes(*sweeps[w], *bodies[w], i, changed, p[w], lane[w]);
    }
#pragma GCC unroll 4
    for (int w = 0; w < M; ++w) solveBatch(SurfaceSweeps::batches(*sweeps[w])[i], lane[w], useBias);
  }
#pragma GCC unroll 4
  for (int w = 0; w < M; ++w) lane[w].writeBack(kAll, p[w]);
}

// Every batch of the given sweeps (count of them, 1-4, none empty): all of them side by side
// while each has batches left, then the longer ones on.
inline void sweepSideBySide(SurfaceBatches* const* given,
                            std::vector<SolverBody>* const* givenBodies, std::size_t count,
                            bool useBias) {
  SurfaceBatches* sweeps[4];
  std::vector<SolverBody>* bodies[4];
  for (std::size_t w = 0; w < count; ++w) {  // by decreasing batch count (insertion sort)
    std::size_t j = w;
    for (; j > 0 && SurfaceSweeps::batches(*sweeps[j - 1]).size() <
                        SurfaceSweeps::batches(*given[w]).size();
         --j) {
      sweeps[j] = sweeps[j - 1];
      bodies[j] = bodies[j - 1];
    }
    sweeps[j] = given[w];
    bodies[j] = givenBodies[w];
  }
  for (std::size_t w = 0; w < count; ++w) SurfaceSweeps::beginCopies(*sweeps[w], *bodies[w]);
  std::size_t from = 0;
  for (std::size_t m = count; m > 0; --m) {  // the m longest sweeps still have batches
    const std::size_t to = SurfaceSweeps::batches(*sweeps[m - 1]).size();
    if (from < to) {
      switch (m) {
        case 4:
          sweepPhase<4>(sweeps, bodies, from, to, useBias);
          break;
        case 3:
          sweepPhase<3>(sweeps, bodies, from, to, useBias);
          break;
        case 2:
          sweepPhase<2>(sweeps, bodies, from, to, useBias);
          break;
        default:
          sweepPhase<1>(sweeps, bodies, from, to, useBias);
          break;
      }
      from = to;
    }
  }
  for (std::size_t w = 0; w < count; ++w) SurfaceSweeps::endCopies(*sweeps[w], *bodies[w]);
}
