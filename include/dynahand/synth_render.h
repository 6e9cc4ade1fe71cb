/// @file
/// The synthetic hand's render surface and the CPU depth renderer.
///
/// The surface is deliberately NOT the tracker's convex bodies (rendering those would
/// flatter the tracker, the "inverse crime"): it is a union of round cones (the convex hull
/// of two spheres: a sphere at each joint blended into a tapered capsule along the bone),
/// a palm slab swept from a row of such cones, fingertip pads and a forearm, with its own
/// per-segment radii. It is built from the 21 keypoints (MediaPipe order) plus an elbow
/// point, so any skeleton source can drive it.
///
/// The renderer ray-casts each primitive analytically, only over its projected bounding
/// box, against an exact pinhole camera (u = fx x / z + cx, pixel centres at integers) into
/// a float z-buffer. Depth is the z coordinate (not the ray length), as depth cameras report.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "dynahand/core.h"
#include "dynahand/depth_frame.h"
#include "dynahand/model.h"

namespace dynahand::synth {

/// 21 hand keypoints, metres, camera frame, MediaPipe order: 0 wrist, 1-4 thumb (CMC, MCP,
/// IP, tip), 5-8 index (MCP, PIP, DIP, tip), 9-12 middle, 13-16 ring, 17-20 pinky.
using HandKeypoints = std::array<Vec3, 21>;

/// All 21 keypoints at the origin (Eigen vectors are not zeroed by default construction).
inline HandKeypoints zeroKeypoints() {
  HandKeypoints k;
  k.fill(Vec3::Zero());
  return k;
}

/// The convex hull of a sphere at `a` (radius ra) and a sphere at `b` (radius rb): a
/// sphere when a == b, a capsule when ra == rb. Metres, camera frame.
struct RoundCone {
  Vec3 a = Vec3::Zero();  ///< centre of the first sphere, m
  Vec3 b = Vec3::Zero();  ///< centre of the second sphere, m
  float ra = 0.0f;        ///< m
  float rb = 0.0f;        ///< m
};

/// A solid box: centre, orientation (columns: its unit axes) and half extents along them.
/// Metres, camera frame.
struct OrientedBox {
  Vec3 centre = Vec3::Zero();       ///< m
  Mat3 axes = Mat3::Identity();     ///< columns: the box's axes, unit length, orthogonal
  Vec3 halfExtents = Vec3::Zero();  ///< m, half the box's size along each axis
};

/// First intersection of the ray t * dir (t > 0, from the camera centre) with the solid
/// round cone; returns the ray parameter t (so the hit is t * dir) or a negative value for
/// a miss. `dir` need not be unit length. Exposed for tests and other analytic users.
float intersectRoundCone(const RoundCone& cone, const Vec3& dir);

/// Per-segment radii of the render surface, metres, for a hand of the reference size
/// (length 0.19 m, width 0.085 m); buildHandSurface scales them with the hand.
struct SurfaceRadii {
  /// [finger][joint]: finger 0 thumb .. 4 pinky; joint 0 base (thumb CMC, finger MCP),
  /// 1, 2 the next joints, 3 the tip.
  std::array<std::array<float, 4>, 5> finger = {{{0.0125f, 0.0110f, 0.0095f, 0.0085f},
                                                 {0.0100f, 0.0088f, 0.0078f, 0.0070f},
                                                 {0.0102f, 0.0090f, 0.0080f, 0.0072f},
                                                 {0.0096f, 0.0084f, 0.0076f, 0.0068f},
                                                 {0.0086f, 0.0075f, 0.0068f, 0.0062f}}};
  float palmHalfThickness = 0.0125f;  ///< m, half the dorsal-palmar thickness of the palm slab
  float wrist = 0.0240f;              ///< m, forearm radius at the wrist
  float elbow = 0.0330f;              ///< m, forearm radius at the elbow end
  float padOffset = 0.0020f;          ///< m, how far fingertip pads bulge palmar of the bone
};

/// Per-hand shape factors of the rendered hand relative to the tracking model (1 = same):
/// the ground truth and the render surface take them, the tracker's model does not, so a
/// benchmark can measure how much a hand shaped unlike the model costs. The same factors as
/// model::HandShape, which builds a default hand shaped so (model::makeDefaultHand).
using HandProportions = model::HandShape;

/// Each factor uniform in [1-spread, 1+spread], deterministic from seed (portable: the same
/// numbers on every platform). spread 0 gives all ones.
HandProportions randomProportions(std::uint64_t seed, float spread);

/// Stretches each bone of the 21-keypoint skeleton (MediaPipe order) about its parent
/// keypoint, moving the children along; the wrist stays fixed. All ones leaves the
/// keypoints untouched (bit for bit).
void applyProportions(const HandProportions& p, HandKeypoints& keypoints);

/// Finger radii times fingerThickness, palm half-thickness times palmThickness.
SurfaceRadii scaledRadii(const SurfaceRadii& radii, const HandProportions& p);

/// One hand's skeleton as the renderer needs it.
struct HandSkeleton {
  HandKeypoints keypoints = zeroKeypoints();  ///< m, camera frame
  Vec3 elbow = Vec3::Zero();                  ///< m, camera frame: far end of the forearm
  /// m, camera frame: where an upper arm from the elbow ends (none when empty). A camera that
  /// sees the elbow sees the arm go on to the body, not end in mid-air.
  std::optional<Vec3> shoulder;
  bool leftHand = false;  ///< mirrors the palm normal used for the fingertip pads
  float scale = 1.0f;     ///< radii multiplier (hand size / reference size)
};

/// Maximum primitives one hand produces (fingers, palm, pads, forearm).
inline constexpr int kMaxHandPrimitives = 48;

/// Appends the hand's primitives to `out` (no allocation once `out` has capacity).
void buildHandSurface(const HandSkeleton& hand, const SurfaceRadii& radii,
                      std::vector<RoundCone>& out);

/// What each rendered pixel shows (HeldObject: an object held in the first hand).
enum class PixelLabel : std::uint8_t {
  Empty = 0,
  Background = 1,
  Hand0 = 2,
  Hand1 = 3,
  HeldObject = 4
};

/// An infinite plane n . x = offset in the camera frame (n unit length), e.g. a wall or
/// a table top.
struct Plane {
  Vec3 normal = Vec3::UnitZ();  ///< n, unit length
  float offset = 1.0f;          ///< m
};

/// A z-buffered analytic depth renderer for one image size. Reuses its buffers: no
/// allocation per frame.
class DepthRenderer {
 public:
  /// A renderer for images of this camera, with no background.
  explicit DepthRenderer(const Intrinsics& intrinsics);

  const Intrinsics& intrinsics() const { return intrinsics_; }  ///< the camera rendered for

  /// Static background (planes and primitives) rendered once and restored by clear().
  void setBackground(std::span<const Plane> planes, std::span<const RoundCone> solids);
  /// Resets depth to the background (or to empty: depth 0, label Empty).
  void clear();
  /// Draws primitives with the given label, keeping the nearest surface per pixel.
  void draw(std::span<const RoundCone> primitives, PixelLabel label);
  /// Draws a box with the given label, keeping the nearest surface per pixel; a box reaching
  /// nearer than 5 cm to the camera plane is not drawn.
  void draw(const OrientedBox& box, PixelLabel label);

  /// (height x width) depth in metres, 0 where nothing was hit.
  std::span<const float> depth() const { return depth_; }
  /// (height x width) label of the nearest surface per pixel.
  std::span<const PixelLabel> labels() const { return labels_; }
  /// Pixel count the last draw() call ray-tested (for benchmarks and tuning).
  std::int64_t testedPixels() const { return testedPixels_; }

 private:
  void drawOne(const RoundCone& cone, PixelLabel label, std::vector<float>& depth,
               std::vector<PixelLabel>& labels);

  Intrinsics intrinsics_;
  std::vector<float> rayX_;                            ///< (width) (u - cx) / fx
  std::vector<float> rayY_;                            ///< (height) (v - cy) / fy
  std::vector<float> depth_, backgroundDepth_;         ///< (height x width), m
  std::vector<PixelLabel> labels_, backgroundLabels_;  ///< (height x width)
  std::int64_t testedPixels_ = 0;
};

}  // namespace dynahand::synth
