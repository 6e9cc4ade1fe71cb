// Surface rows of one body prepared eight at a time: a kernel file of the SIMD layer
// (core/simd/for_each_level.inl compiles it once per level inside surface_prepare.cpp's
// anonymous namespace, after SurfaceBodyConstants). The same arithmetic, operation for
// operation (no fused or reordered operations), as prepareSurfaceRow, so the same bits.
// No include guard, no includes.

// Rows index[0, count) (1 <= count <= 8, all on the body `b` describes) into m.surfaceRows;
// the lanes past count compute the last row again and are not written.
inline void prepareRowsOfBody(World::Impl& m, const SurfaceRows& rows,
                              const SurfaceBodyConstants& b, const int* index, int count,
                              float erp, float invH) {
  float in[15][kLanes];  // anchor, normal, target (x, y, z each), lower, upper
  for (int lane = 0; lane < kLanes; ++lane) {
    const auto i = static_cast<std::size_t>(index[lane < count ? lane : count - 1]);
    const Vec3* vectors[3] = {&rows.anchor[i], &rows.normal[i], &rows.target[i]};
    for (int v = 0; v < 3; ++v)
      for (int axis = 0; axis < 3; ++axis) in[3 * v + axis][lane] = (*vectors[v])[axis];
    in[9][lane] = rows.lower[i];
    in[10][lane] = rows.upper[i];
  }
  const FloatW ax = load(in[0]), ay = load(in[1]), az = load(in[2]);
  const FloatW nx = load(in[3]), ny = load(in[4]), nz = load(in[5]);
  const FloatW tx = load(in[6]), ty = load(in[7]), tz = load(in[8]);
  const FloatW lower = load(in[9]), upper = load(in[10]);
  const FloatW qx = splat(b.q.x()), qy = splat(b.q.y()), qz = splat(b.q.z()), qw = splat(b.q.w());
  // comLocal = anchor - centroid; world = position + q * comLocal (Eigen's
  // _transformVector: uv = q.vec x v, uv += uv, v + w uv + q.vec x uv).
  const FloatW lx = ax - splat(b.centroid.x()), ly = ay - splat(b.centroid.y()),
               lz = az - splat(b.centroid.z());
  FloatW ux = qy * lz - qz * ly, uy = qz * lx - qx * lz, uz = qx * ly - qy * lx;
  ux = ux + ux, uy = uy + uy, uz = uz + uz;
  const FloatW rx = (lx + qw * ux) + (qy * uz - qz * uy);
  const FloatW ry = (ly + qw * uy) + (qz * ux - qx * uz);
  const FloatW rz = (lz + qw * uz) + (qx * uy - qy * ux);
  const FloatW wx = splat(b.position.x()) + rx, wy = splat(b.position.y()) + ry,
               wz = splat(b.position.z()) + rz;
  const FloatW armX = wx - splat(b.slotPosition.x()), armY = wy - splat(b.slotPosition.y()),
               armZ = wz - splat(b.slotPosition.z());
  // ang = arm x normal; invIAng = the inverse inertia times ang.
  const FloatW gx = armY * nz - armZ * ny;
  const FloatW gy = armZ * nx - armX * nz;
  const FloatW gz = armX * ny - armY * nx;
  const FloatW ixx = splat(b.ixx), iyy = splat(b.iyy), izz = splat(b.izz);
  const FloatW ixy = splat(b.ixy), ixz = splat(b.ixz), iyz = splat(b.iyz);
  const FloatW jx = (ixx * gx + ixy * gy) + ixz * gz;
  const FloatW jy = (ixy * gx + iyy * gy) + iyz * gz;
  const FloatW jz = (ixz * gx + iyz * gy) + izz * gz;
  // Eigen's dot and squaredNorm of 3-vectors sum as x + (y + z).
  const FloatW k = splat(b.invMass) * (nx * nx + (ny * ny + nz * nz)) + (gx * jx + (gy * jy + gz * jz));
  const FloatW zero = splat(0.0f);
  const FloatW effMass = select(k > zero, splat(1.0f) / k, zero);
  const FloatW c = nx * (wx - tx) + (ny * (wy - ty) + nz * (wz - tz));
  // Bias (rows.h): one-sided rows (lower >= 0) ahead of the surface keep c / h in both
  // sweeps; otherwise erp c / h, and no relax bias.
  const MaskW ahead = (lower >= zero) & (c > zero);
  const FloatW speculative = c * splat(invH);
  const FloatW closing = (splat(erp) * c) * splat(invH);
  const FloatW solve = select(ahead, speculative, closing);
  const FloatW relax = select(ahead, speculative, zero);
  float out[14][kLanes];
  const FloatW fields[14] = {nx, ny, nz, gx, gy, gz, jx, jy, jz, effMass, solve, relax, lower, upper};
  for (int f = 0; f < 14; ++f) store(out[f], fields[f]);
  for (int lane = 0; lane < count; ++lane) {
    PreparedSurfaceRow& row = m.surfaceRows[static_cast<std::size_t>(index[lane])];
    row.slot = b.slot;
    row.normal = Vec3(out[0][lane], out[1][lane], out[2][lane]);
    row.ang = Vec3(out[3][lane], out[4][lane], out[5][lane]);
    row.invIAng = Vec3(out[6][lane], out[7][lane], out[8][lane]);
    row.effMass = out[9][lane];
    row.bias = out[10][lane];
    row.relaxBias = out[11][lane];
    row.lower = out[12][lane];
    row.upper = out[13][lane];
  }
}
