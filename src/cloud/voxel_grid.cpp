#include "dynahand/voxel_grid.h"

#include <bit>
#include <cassert>
#include <cmath>

namespace dynahand {
namespace {

// SplitMix64 finaliser: a fixed, platform-independent mix (std::hash is not).
std::uint64_t mixKey(std::uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  x ^= x >> 31;
  return x;
}

// floor() for |x| < 2^21 without a libm call (baseline x86-64 has no roundss).
std::int32_t floorToInt(float x) {
  const auto i = static_cast<std::int32_t>(x);  // truncates toward zero
  return static_cast<float>(i) > x ? i - 1 : i;
}

std::uint64_t packKey(std::int32_t ix, std::int32_t iy, std::int32_t iz) {
  constexpr std::int32_t kOffset = VoxelGrid::kMaxAbsCoordinate + 1;
  const auto field = [](std::int32_t c) { return static_cast<std::uint64_t>(c + kOffset); };
  return field(ix) | (field(iy) << 21) | (field(iz) << 42);
}

}  // namespace

VoxelGrid::VoxelGrid(float voxelSizeM, int maxVoxels)
    : voxelSize_(voxelSizeM), inverseVoxelSize_(1.0f / voxelSizeM), maxVoxels_(maxVoxels) {
  assert(voxelSizeM > 0.0f && std::isfinite(voxelSizeM) && "voxel size must be positive");
  assert(maxVoxels > 0 && maxVoxels <= 65535 && "maxVoxels must be in [1, 65535]");
  // Load factor at most 1/2 keeps probe sequences short.
  const std::uint32_t slotCount = std::bit_ceil(static_cast<std::uint32_t>(maxVoxels) * 2u);
  slotMask_ = slotCount - 1u;
  slots_.assign(slotCount, 0u);
  const auto n = static_cast<std::size_t>(maxVoxels);
  key_.assign(n, 0);
  sum_.assign(n, Vec3::Zero());
  corner_.assign(n, Vec3::Zero());
  count_.assign(n, 0);
  firstTag_.assign(n, -1);
}

void VoxelGrid::clear() {
  voxelCount_ = 0;
  droppedPoints_ = 0;
  lastVoxel_ = -1;
  ++stamp16_;
  if (stamp16_ == 0) {  // wrapped after 65535 frames: stale stamps could alias, so wipe once
    std::fill(slots_.begin(), slots_.end(), 0u);
    stamp16_ = 1;
  }
}

bool VoxelGrid::add(const Vec3& point, std::int32_t tag) {
  const float sx = point.x() * inverseVoxelSize_;
  const float sy = point.y() * inverseVoxelSize_;
  const float sz = point.z() * inverseVoxelSize_;
  constexpr auto kLimit = static_cast<float>(kMaxAbsCoordinate);
  // The negated comparison also rejects NaN.
  if (!(std::fabs(sx) <= kLimit && std::fabs(sy) <= kLimit && std::fabs(sz) <= kLimit)) {
    ++droppedPoints_;
    return false;
  }
  const std::int32_t ix = floorToInt(sx);
  const std::int32_t iy = floorToInt(sy);
  const std::int32_t iz = floorToInt(sz);
  const std::uint64_t key = packKey(ix, iy, iz);
  if (lastVoxel_ >= 0 && key == lastKey_) {
    const auto v = static_cast<std::size_t>(lastVoxel_);
    sum_[v] += point - corner_[v];
    ++count_[v];
    return true;
  }
  // x-neighbouring voxels get neighbouring slots: a row-major pixel scan then walks the
  // table along cache lines instead of missing on every new voxel.
  const std::uint64_t yz = packKey(0, iy, iz);
  std::uint32_t index =
      (static_cast<std::uint32_t>(mixKey(yz)) + static_cast<std::uint32_t>(ix)) & slotMask_;
  const std::uint32_t stampBits = static_cast<std::uint32_t>(stamp16_) << 16;
  for (;;) {
    const std::uint32_t slot = slots_[index];
    if ((slot & 0xffff0000u) != stampBits) break;  // empty this frame: a new voxel
    const auto v = static_cast<std::size_t>(slot & 0xffffu);
    if (key_[v] == key) {
      sum_[v] += point - corner_[v];
      ++count_[v];
      lastKey_ = key;
      lastVoxel_ = static_cast<std::int32_t>(v);
      return true;
    }
    index = (index + 1u) & slotMask_;
  }
  if (voxelCount_ == maxVoxels_) {
    ++droppedPoints_;
    return false;
  }
  const auto v = static_cast<std::size_t>(voxelCount_++);
  slots_[index] = stampBits | static_cast<std::uint32_t>(v);
  key_[v] = key;
  corner_[v] =
      Vec3(static_cast<float>(ix), static_cast<float>(iy), static_cast<float>(iz)) * voxelSize_;
  sum_[v] = point - corner_[v];
  count_[v] = 1;
  firstTag_[v] = tag;
  lastKey_ = key;
  lastVoxel_ = static_cast<std::int32_t>(v);
  return true;
}

Vec3 VoxelGrid::centroid(int i) const {
  assert(i >= 0 && i < voxelCount_);
  const auto v = static_cast<std::size_t>(i);
  return corner_[v] + sum_[v] / static_cast<float>(count_[v]);
}

}  // namespace dynahand
