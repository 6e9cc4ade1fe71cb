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

constexpr std::int32_t kKeyOffset = VoxelGrid::kMaxAbsCoordinate + 1;
constexpr std::uint64_t kKeyFieldMask = (std::uint64_t{1} << VoxelGrid::kKeyFieldBits) - 1u;

// Voxel coordinate `field` (0 = x, 1 = y, 2 = z) of a key.
std::int32_t unpackKey(std::uint64_t key, int field) {
  return static_cast<std::int32_t>((key >> (field * VoxelGrid::kKeyFieldBits)) & kKeyFieldMask) -
         kKeyOffset;
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

VoxelGrid::Run VoxelGrid::beginRun(Key key, std::int32_t tag, int hint) {
  Run run;
  run.key = key;
  if (key == kInvalidKey) return run;
  // Sums are kept relative to the voxel's corner (small numbers: accurate float sums).
  const auto open = [&](std::size_t v) {
    run.voxel = static_cast<int>(v);
    run.corner = corner_[v];
    run.sum = sum_[v];
    run.count = count_[v];
    lastKey_ = key;
    lastVoxel_ = static_cast<std::int32_t>(v);
    return run;
  };
  if (hint >= 0 && hint < voxelCount_ && key_[static_cast<std::size_t>(hint)] == key) {
    return open(static_cast<std::size_t>(hint));
  }
  if (lastVoxel_ >= 0 && key == lastKey_) return open(static_cast<std::size_t>(lastVoxel_));
  // x-neighbouring voxels get neighbouring slots: a row-major pixel scan then walks the
  // table along cache lines instead of missing on every new voxel.
  const std::int32_t ix = unpackKey(key, 0);
  const std::uint64_t yz = (key & ~kKeyFieldMask) | static_cast<std::uint64_t>(kKeyOffset);
  std::uint32_t index =
      (static_cast<std::uint32_t>(mixKey(yz)) + static_cast<std::uint32_t>(ix)) & slotMask_;
  const std::uint32_t stampBits = static_cast<std::uint32_t>(stamp16_) << 16;
  for (;;) {
    const std::uint32_t slot = slots_[index];
    if ((slot & 0xffff0000u) != stampBits) break;  // empty this frame: a new voxel
    const auto v = static_cast<std::size_t>(slot & 0xffffu);
    if (key_[v] == key) return open(v);
    index = (index + 1u) & slotMask_;
  }
  if (voxelCount_ == maxVoxels_) return run;
  const auto v = static_cast<std::size_t>(voxelCount_++);
  slots_[index] = stampBits | static_cast<std::uint32_t>(v);
  key_[v] = key;
  corner_[v] = Vec3(static_cast<float>(ix), static_cast<float>(unpackKey(key, 1)),
                    static_cast<float>(unpackKey(key, 2))) *
               voxelSize_;
  sum_[v] = Vec3::Zero();
  count_[v] = 0;
  firstTag_[v] = tag;
  return open(v);
}

void VoxelGrid::endRun(const Run& run) {
  if (run.voxel < 0) {
    droppedPoints_ += run.added;
    return;
  }
  const auto v = static_cast<std::size_t>(run.voxel);
  sum_[v] = run.sum;
  count_[v] = run.count;
}

void VoxelGrid::keysOfRow(const float* xPerZ, float yPerZ, const float* z, int n, Key* keys) const {
  const auto field = [](float x) {
    const auto i = static_cast<std::int32_t>(x);  // truncates toward zero
    const std::int32_t floor = i - (static_cast<float>(i) > x ? 1 : 0);
    return static_cast<Key>(static_cast<std::uint32_t>(floor + kKeyOffset));
  };
  for (int i = 0; i < n; ++i) {
    // The same products as keyOf(point): point first, then scaled to voxels.
    const float x = xPerZ[i] * z[i];
    const float y = yPerZ * z[i];
    keys[i] = field(x * inverseVoxelSize_) | (field(y * inverseVoxelSize_) << kKeyFieldBits) |
              (field(z[i] * inverseVoxelSize_) << (2 * kKeyFieldBits));
  }
}

Vec3 VoxelGrid::centroid(int i) const {
  assert(i >= 0 && i < voxelCount_);
  const auto v = static_cast<std::size_t>(i);
  return corner_[v] + sum_[v] / static_cast<float>(count_[v]);
}

}  // namespace dynahand
