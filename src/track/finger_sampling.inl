// The finger detector's scanline sampling, eight samples at a time: a kernel file of the SIMD
// layer (core/simd/for_each_level.inl compiles it once per level inside finger_detector.cpp's
// anonymous namespace, after ScanlineSampler). No include guard, no includes.

// roundToPixel of eight coordinates, all below 2^22 in magnitude: truncation, then the
// fraction's test, as roundToPixel does one at a time.
DYNAHAND_SIMD_INLINE IntW roundToPixels(FloatW x) {
  const IntW whole = truncate(x);
  const FloatW fraction = x - toFloat(whole);
  const IntW one = splat(std::int32_t{1});
  const IntW up = select(fraction >= splat(0.5f), whole + one, whole);
  return select(fraction <= splat(-0.5f), up - one, up);
}

// ScanlineSampler::row over samples [0, columns): the same sums and products per sample, and
// the same rounding, so the same pixels. Lanes outside the box read pixel 0 and ignore it.
inline void sampleRow(const ScanlineSampler& sampler, const Vec2& rowBase, const Vec2& across,
                      float tMin, int columns, std::uint64_t* on) {
  const FloatW baseX = splat(rowBase.x()), baseY = splat(rowBase.y());
  const FloatW acrossX = splat(across.x()), acrossY = splat(across.y());
  const FloatW first = splat(tMin);
  const FloatW limit = splat(kExactRounding);
  const IntW x0 = splat(sampler.box.x0 - 1), x1 = splat(sampler.box.x1);
  const IntW y0 = splat(sampler.box.y0 - 1), y1 = splat(sampler.box.y1);
  const IntW stride = splat(sampler.width);
  const IntW zero = splat(std::int32_t{0});
  for (int col = 0; col < columns; col += kLanes) {
    const FloatW t = first + toFloat(splat(col) + iota());
    const FloatW px = baseX + acrossX * t;
    const FloatW py = baseY + acrossY * t;
    const int count = std::min(kLanes, columns - col);
    if (!all((abs(px) < limit) & (abs(py) < limit))) {  // far outside any image: one by one
      sampler.row(rowBase, across, tMin, col, col + count, on);
      continue;
    }
    const IntW u = roundToPixels(px), v = roundToPixels(py);
    const MaskW inside = (u > x0) & (x1 > u) & (v > y0) & (y1 > v);
    alignas(32) std::int32_t pixel[kLanes];
    store(pixel, select(inside, mulLow(v, stride) + u, zero));
    unsigned sampled = 0;
    for (int k = 0; k < kLanes; ++k)
      sampled |= static_cast<unsigned>(sampler.mask[static_cast<std::size_t>(pixel[k])] != 0) << k;
    sampled &= bits(inside) & ((1u << count) - 1u);
    on[col / 64] |= static_cast<std::uint64_t>(sampled) << (col % 64);
  }
}
