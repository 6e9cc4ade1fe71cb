/// @file
/// Two hands from one segmented cloud (paper: "Tracking of Multiple Hands"): k-means
/// with k = 2; the cluster on the user's left is the left hand; when the two clusters
/// are too close, one is too small, or they are one limb cut lengthwise (a hand and its
/// forearm) they are merged into one cluster, tracked as the right hand. A small stateful object:
/// while two hands stay visible, each cluster takes the label of the nearer of last frame's
/// hands, so hands keep their identity when they cross.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "dynahand/core.h"

namespace dynahand {

/// Which of the user's hands; indexes HandSplit::hands.
enum class Hand : std::uint8_t { kLeft = 0, kRight = 1 };

/// Which image side the user's left hand appears on when labelling fresh clusters.
enum class CameraPlacement : std::uint8_t {
  kFacingUser,  ///< camera looks at the user: their left hand has the larger camera x
  kBehindUser,  ///< camera looks along the user's view (or a mirrored image): smaller x
};

/// Settings of a HandSplitter.
struct HandSplitConfig {
  /// Clusters whose centroids are closer than this (m) are one hand: halves of one hand
  /// seen from the desk. Two hands touching side by side have centroids about 0.1-0.14 m
  /// apart, a hand and its own forearm cut apart by k-means 0.1-0.17 m.
  float mergeDistanceM = 0.09f;
  /// Clusters farther apart than this (m) are two hands whatever their shape.
  float apartDistanceM = 0.2f;
  /// Between the two distances, the clusters are two hands only when neither one's longest
  /// axis lies along the line between their centroids (|cosine| below this): one limb cut in
  /// two (a hand and its forearm) has both along that line, two hands side by side lie
  /// along their arms, across it.
  float maxAlongLimb = 0.6f;
  int minPointsPerHand = 30;  ///< a smaller cluster is noise or a fingertip: merge
  int maxIterations = 20;     ///< k-means (Lloyd) iterations; it stops earlier when stable
  CameraPlacement placement = CameraPlacement::kFacingUser;  ///< which side is the left hand
};

/// One hand's cluster of points.
struct HandCluster {
  bool present = false;          ///< the hand was found this frame
  Vec3 centroid = Vec3::Zero();  ///< m, camera frame
  int pointCount = 0;            ///< input points labelled with this hand
};

/// The result of HandSplitter::split for one frame.
struct HandSplit {
  int handCount = 0;                 ///< 0, 1 (merged: the right hand) or 2
  std::array<HandCluster, 2> hands;  ///< indexed by Hand: [kLeft], [kRight]
  std::vector<Hand> label;           ///< (pointCount): hand of each input point

  /// The cluster of hand h.
  const HandCluster& operator[](Hand h) const { return hands[static_cast<std::size_t>(h)]; }
};

/// Splits each frame's points into up to two hands, keeping their identity across frames.
class HandSplitter {
 public:
  /// A splitter with these settings that remembers no clusters yet.
  explicit HandSplitter(const HandSplitConfig& config = {});

  /// Splits `points` (m, camera frame; e.g. the voxel cloud) into hands. Replaces `out`.
  void split(std::span<const Vec3> points, HandSplit& out);
  /// Forgets last frame's clusters (next frame labels fresh clusters by side).
  void reset() { hadTwoHands_ = false; }

  const HandSplitConfig& config() const { return config_; }  ///< the settings

 private:
  // Lloyd's k-means from `centre` (updated): labels (kLeft = cluster 0) and counts.
  void cluster(std::span<const Vec3> points, std::array<Vec3, 2>& centre, std::vector<Hand>& label,
               std::array<int, 2>& count) const;
  bool oneLimb(std::span<const Vec3> points, std::span<const Hand> label,
               const std::array<Vec3, 2>& centre) const;
  HandSplitConfig config_;
  bool hadTwoHands_ = false;
  std::array<Vec3, 2> previousCentroid_ = {Vec3::Zero(), Vec3::Zero()};  ///< [left, right]
};

}  // namespace dynahand
