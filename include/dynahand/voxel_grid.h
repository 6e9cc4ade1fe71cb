/// @file
/// Voxel-grid subsampling (paper: "Sampling from a Depth Sensor"): one point per
/// occupied voxel, at the centroid of the points that fell into it.
///
/// Linear time: a fixed-capacity open-addressing hash table keyed by the integer
/// voxel coordinates (voxels are aligned to the camera origin); the slot is a hash of
/// (y, z) plus x, so voxels met one after another along an image row share cache lines. Slots carry
/// a generation stamp, so clearing between frames is O(1) and nothing is allocated after
/// construction. Output order is the order in which voxels were first hit, so a fixed input order
/// gives a fixed output order (deterministic).
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "dynahand/core.h"

namespace dynahand {

/// Voxel-grid subsampling with a fixed capacity (see the file comment).
class VoxelGrid {
 public:
  /// voxelSizeM > 0: voxel edge, m. 0 < maxVoxels <= 65535: occupied voxels per frame; a point
  /// that would open voxel maxVoxels + 1 is dropped and counted in droppedPoints().
  VoxelGrid(float voxelSizeM, int maxVoxels);

  /// Forgets all voxels (O(1)).
  void clear();

  /// Adds one point (m). tag is carried along for the first point of each voxel (the
  /// pipeline passes the source pixel index). Returns false when dropped: voxel table
  /// full, non-finite point, or a coordinate beyond +-kMaxAbsCoordinate voxels.
  bool add(const Vec3& point, std::int32_t tag = -1) {
    Run run = beginRun(keyOf(point), tag);
    addToRun(run, point);
    endRun(run);
    return run.voxel >= 0;
  }

  /// The voxel holding a point, as packed integer coordinates; kInvalidKey for a point that
  /// add() drops (non-finite, or a coordinate beyond +-kMaxAbsCoordinate voxels).
  using Key = std::uint64_t;
  static constexpr Key kInvalidKey = ~Key{0};  ///< the key of no voxel
  Key keyOf(const Vec3& point) const;          ///< the key of the voxel holding point
  /// keyOf() of the n points (xPerZ[i] * z[i], yPerZ * z[i], z[i]) (an image row: x / z per
  /// column, y / z of the row, depth in m), without branches so that it vectorises. Every
  /// coordinate must be finite and within +-kMaxAbsCoordinate voxels (inRange()).
  void keysOfRow(const float* xPerZ, float yPerZ, const float* z, int n, Key* keys) const;
  /// True when every coordinate up to maxAbsM (m) is in the key range.
  bool inRange(float maxAbsM) const {
    return maxAbsM * inverseVoxelSize_ < static_cast<float>(kMaxAbsCoordinate);
  }
  /// Points of one voxel met one after another (along an image row): the voxel is looked up
  /// once, beginRun(); addToRun() per point sums in registers; endRun() stores. The same
  /// result as add() per point, bit for bit (same sums in the same order). tag as for add();
  /// `hint` is a voxel index that may hold key (e.g. the voxel of the pixel above), checked
  /// before the table. Nothing else may add to the grid between beginRun and endRun.
  struct Run {
    int voxel = -1;              ///< -1: the run's points are dropped (table full, or kInvalidKey)
    Key key = kInvalidKey;       ///< the voxel's key
    Vec3 corner = Vec3::Zero();  ///< the voxel's lower corner, m
    Vec3 sum = Vec3::Zero();     ///< the voxel's coordinate sum relative to corner, m
    int count = 0;               ///< the voxel's points so far
    int added = 0;               ///< points added by this run
  };
  /// Starts a run on the voxel of key, opening it (with tag) if new since clear().
  Run beginRun(Key key, std::int32_t tag = -1, int hint = -1);
  /// Adds one point (m) of the run's voxel to the run.
  static void addToRun(Run& run, const Vec3& point) {
    run.sum += point - run.corner;
    ++run.count;
    ++run.added;
  }
  /// Stores the run's sums in its voxel, or counts its points as dropped.
  void endRun(const Run& run);

  int voxelCount() const { return voxelCount_; }        ///< occupied voxels since clear()
  int droppedPoints() const { return droppedPoints_; }  ///< points dropped since clear()
  int maxVoxels() const { return maxVoxels_; }          ///< voxel capacity per frame

  /// Centroid (m) of voxel i in first-hit order, 0 <= i < voxelCount().
  Vec3 centroid(int i) const;
  /// Number of points that fell into voxel i.
  int count(int i) const { return count_[static_cast<std::size_t>(i)]; }
  /// Tag of the first point of voxel i.
  std::int32_t firstTag(int i) const { return firstTag_[static_cast<std::size_t>(i)]; }

  /// Voxel coordinates are kept within +-2^20 so a key packs into 63 bits.
  static constexpr std::int32_t kMaxAbsCoordinate = (1 << 20) - 1;
  static constexpr int kKeyFieldBits = 21;  ///< per coordinate, offset by kMaxAbsCoordinate + 1

 private:
  float voxelSize_;
  float inverseVoxelSize_;
  int maxVoxels_;
  std::uint32_t slotMask_;
  int voxelCount_ = 0;
  int droppedPoints_ = 0;
  /// Hash table (slotCount): 4 bytes per slot (16-bit clear() generation, 16-bit voxel
  /// index), so the table stays cache-resident (64 KB at the default capacity); the full
  /// keys live in the dense per-voxel array key_.
  std::vector<std::uint32_t> slots_;
  std::uint16_t stamp16_ = 1;
  /// The last voxel hit: neighbouring pixels usually share a voxel, so most points skip
  /// the table lookup.
  std::uint64_t lastKey_ = 0;
  std::int32_t lastVoxel_ = -1;
  /// Per voxel, (maxVoxels): coordinate sums relative to the voxel's lower corner (m),
  /// kept small so float sums stay accurate; the corner; point count; first tag.
  std::vector<std::uint64_t> key_;  ///< packed voxel coordinates
  std::vector<Vec3> sum_;
  std::vector<Vec3> corner_;
  std::vector<int> count_;
  std::vector<std::int32_t> firstTag_;
};

inline VoxelGrid::Key VoxelGrid::keyOf(const Vec3& point) const {
  const float sx = point.x() * inverseVoxelSize_;
  const float sy = point.y() * inverseVoxelSize_;
  const float sz = point.z() * inverseVoxelSize_;
  constexpr auto kLimit = static_cast<float>(kMaxAbsCoordinate);
  // The negated comparison also rejects NaN.
  if (!(std::fabs(sx) <= kLimit && std::fabs(sy) <= kLimit && std::fabs(sz) <= kLimit)) {
    return kInvalidKey;
  }
  // floor() for |x| < 2^21 without a libm call (baseline x86-64 has no roundss).
  const auto field = [](float x) {
    const auto i = static_cast<std::int32_t>(x);  // truncates toward zero
    const std::int32_t floor = static_cast<float>(i) > x ? i - 1 : i;
    return static_cast<Key>(floor + kMaxAbsCoordinate + 1);
  };
  return field(sx) | (field(sy) << kKeyFieldBits) | (field(sz) << (2 * kKeyFieldBits));
}

}  // namespace dynahand
