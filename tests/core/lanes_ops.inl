// The operations of core/simd/lanes.h applied to arrays of eight lanes, compiled once per SIMD
// level (core/simd/for_each_level.inl) by simd_lanes_test.cpp. No include guard, no includes.

// out[op][lane] for float inputs a, b and int inputs i, j (see kOpNames in the test).
inline void applyOps(const float* a, const float* b, const std::int32_t* i, const std::int32_t* j,
                     std::uint32_t (*out)[8]) {
  const FloatW fa = load(a), fb = load(b);
  const IntW ia = load(i), ib = load(j);
  float f[8];
  std::int32_t n[8];
  int op = 0;
  auto putFloat = [&](FloatW x) {
    store(f, x);
    for (int lane = 0; lane < kLanes; ++lane) out[op][lane] = std::bit_cast<std::uint32_t>(f[lane]);
    ++op;
  };
  auto putInt = [&](IntW x) {
    store(n, x);
    for (int lane = 0; lane < kLanes; ++lane) out[op][lane] = static_cast<std::uint32_t>(n[lane]);
    ++op;
  };
  auto putMask = [&](MaskW m) {
    const unsigned mask = bits(m);
    for (int lane = 0; lane < kLanes; ++lane) out[op][lane] = (mask >> lane) & 1u;
    ++op;
  };
  putFloat(fa + fb);
  putFloat(fa - fb);
  putFloat(fa * fb);
  putFloat(fa / fb);
  putFloat(abs(fa));
  putFloat(min(fa, fb));
  putFloat(max(fa, fb));
  putFloat(sqrt(abs(fa)));
  putFloat(toFloat(ia));
  putInt(truncate(fa));
  putInt(ia + ib);
  putInt(ia - ib);
  putInt(mulLow(ia, ib));
  putMask(fa < fb);
  putMask(fa <= fb);
  putMask(fa > fb);
  putMask(fa >= fb);
  putMask(fa == fb);
  putMask(ia > ib);
  putMask((fa < fb) & (ia > ib));
  putInt(select(fa < fb, ia, ib));
  putFloat(select(fa > fb, fa, fb));
  putInt(iota());
  putFloat(splat(a[3]));
  for (int lane = 0; lane < kLanes; ++lane) out[op][lane] = all(fa <= fa) ? 1u : 0u;
  ++op;
  putMask(ia == ib);
  putMask(ia == ia);
  putMask(laneMask(i[0] & 7));
}

// rows[k][f] -> out[f][k] through transpose8.
inline void transposeRows(const float (*rows)[8], float (*out)[8]) {
  FloatW r[kLanes];
  for (int k = 0; k < kLanes; ++k) r[k] = load(rows[k]);
  transpose8(r);
  for (int f = 0; f < kLanes; ++f) store(out[f], r[f]);
}
