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

std::uint64_t packKey(std::int32_t ix, std::int32_t iy, std::int32_t iz) {
  constexpr std::int32_t kOffset = VoxelGrid::kMaxAbsCoordinate + 1;
  const auto field = [](std::int32_t c) { return static_cast<std::uint64_t>(c + kOffset); };
  return field(ix) | (field(iy) << 21) | (field(iz) << 42);
}

}  // namespace

VoxelGrid::VoxelGrid(float voxelSizeM, int maxVoxels)
    : voxelSize_(voxelSizeM), inverseVoxelSize_(1.0f / voxelSizeM), maxVoxels_(maxVoxels) {
  assert(voxelSizeM > 0.0f && std::isfinite(voxelSizeM) && "voxel size must be positive");
  assert(maxVoxels > 0 && "maxVoxels must be positive");
  // Load factor at most 1/2 keeps probe sequences short.
  const std::uint32_t slotCount = std::bit_ceil(static_cast<std::uint32_t>(maxVoxels) * 2u);
  slotMask_ = slotCount - 1u;
  slotKey_.assign(slotCount, 0);
  slotStamp_.assign(slotCount, 0);
  slotVoxel_.assign(slotCount, 0);
  const auto n = static_cast<std::size_t>(maxVoxels);
  sum_.assign(n, Vec3::Zero());
  corner_.assign(n, Vec3::Zero());
  count_.assign(n, 0);
  firstTag_.assign(n, -1);
}

void VoxelGrid::clear() {
  voxelCount_ = 0;
  droppedPoints_ = 0;
  ++stamp_;
  if (stamp_ == 0) {  // wrapped after 2^32 frames: stale stamps could alias, so wipe once
    std::fill(slotStamp_.begin(), slotStamp_.end(), 0u);
    stamp_ = 1;
  }
}

bool VoxelGrid::add(const Vec3& point, std::int32_t tag) {
  const float fx = std::floor(point.x() * inverseVoxelSize_);
  const float fy = std::floor(point.y() * inverseVoxelSize_);
  const float fz = std::floor(point.z() * inverseVoxelSize_);
  constexpr auto kLimit = static_cast<float>(kMaxAbsCoordinate);
  // The negated comparison also rejects NaN.
  if (!(std::fabs(fx) <= kLimit && std::fabs(fy) <= kLimit && std::fabs(fz) <= kLimit)) {
    ++droppedPoints_;
    return false;
  }
  const auto ix = static_cast<std::int32_t>(fx);
  const auto iy = static_cast<std::int32_t>(fy);
  const auto iz = static_cast<std::int32_t>(fz);
  const std::uint64_t key = packKey(ix, iy, iz);
  std::uint32_t slot = static_cast<std::uint32_t>(mixKey(key)) & slotMask_;
  for (;;) {
    if (slotStamp_[slot] != stamp_) break;  // empty this frame: a new voxel
    if (slotKey_[slot] == key) {
      const auto v = static_cast<std::size_t>(slotVoxel_[slot]);
      sum_[v] += point - corner_[v];
      ++count_[v];
      return true;
    }
    slot = (slot + 1u) & slotMask_;
  }
  if (voxelCount_ == maxVoxels_) {
    ++droppedPoints_;
    return false;
  }
  const auto v = static_cast<std::size_t>(voxelCount_++);
  slotStamp_[slot] = stamp_;
  slotKey_[slot] = key;
  slotVoxel_[slot] = static_cast<std::int32_t>(v);
  corner_[v] = Vec3(fx, fy, fz) * voxelSize_;
  sum_[v] = point - corner_[v];
  count_[v] = 1;
  firstTag_[v] = tag;
  return true;
}

Vec3 VoxelGrid::centroid(int i) const {
  assert(i >= 0 && i < voxelCount_);
  const auto v = static_cast<std::size_t>(i);
  return corner_[v] + sum_[v] / static_cast<float>(count_[v]);
}

}  // namespace dynahand
