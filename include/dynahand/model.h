/// @file
/// Articulated convex models: rigid convex bodies joined by ball joints with per-axis angle
/// limits, a collision filter and named keypoints. The model is data (docs/formats/model.md);
/// the default hand is one such model generated from anthropometric proportions. Conventions
/// (body frames, joint angles, keypoint layouts) are in docs/model.md.
///
/// Units: metres, kilograms, radians. A model is immutable once built and cheap to share by
/// const reference (like MuJoCo's mjModel); per-frame state lives in ModelPose / JointAngles
/// (model_pose.h).
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "dynahand/convex_shape.h"
#include "dynahand/core.h"

namespace dynahand::model {

/// Which hand makeDefaultHand builds.
enum class Side { Right, Left };
/// Which hand a model is; None: not a hand.
enum class Handedness { None, Right, Left };

/// Hand size: length from the wrist crease to the middle fingertip and palm width across the
/// four finger knuckles (MCP joints), m.
struct HandDimensions {
  float length = 0.19f;  ///< wrist crease to middle fingertip, m
  float width = 0.085f;  ///< palm width across the four finger knuckles, m
};

/// Per-bone departures of a hand from the default proportions (all 1: the default hand).
/// Bone 0 of a digit runs from the wrist to its base (thumb CMC, finger MCP), so its factor
/// moves that base along the line from the wrist; bones 1-3 are the next segments out to the
/// tip (thumb metacarpal, proximal, distal; finger proximal, middle, distal phalanx).
struct HandShape {
  /// [digit 0 thumb..4 pinky][bone 0 = wrist->base, 1..3 out to the tip]: length factors
  std::array<std::array<float, 4>, 5> boneLength = {{{1.0f, 1.0f, 1.0f, 1.0f},
                                                     {1.0f, 1.0f, 1.0f, 1.0f},
                                                     {1.0f, 1.0f, 1.0f, 1.0f},
                                                     {1.0f, 1.0f, 1.0f, 1.0f},
                                                     {1.0f, 1.0f, 1.0f, 1.0f}}};
  /// factor on each digit's radii, 1 by default
  std::array<float, 5> fingerThickness = {1.0f, 1.0f, 1.0f, 1.0f, 1.0f};
  /// factor on the palm's dorsal-palmar thickness, 1 by default
  float palmThickness = 1.0f;

  /// Every factor exactly 1.
  bool identity() const;
};

/// The file format version written by saveModel (docs/formats/model.md).
inline constexpr int kModelFormatVersion = 1;

// ---- Plain description (what a model file holds); buildModel validates and compiles it ----

/// One body of a ModelSpec: its name, hull vertices and mass or density.
struct BodySpec {
  std::string name;              ///< unique body name
  std::vector<Vec3> vertices;    ///< body frame, m; the body's shape is their convex hull
  std::optional<float> mass;     ///< kg; at most one of mass / density
  std::optional<float> density;  ///< kg/m^3; neither given: kDefaultDensity
};

/// One ball joint of a ModelSpec between two bodies given by name.
struct JointSpec {
  std::string parent;                ///< parent body name
  std::string child;                 ///< child body name
  Vec3 anchorParent = Vec3::Zero();  ///< joint centre in the parent's body frame, m
  Vec3 anchorChild = Vec3::Zero();   ///< joint centre in the child's body frame, m
  Quat frame = Quat::Identity();     ///< joint frame in the parent's body frame (unit)
  Vec3 minAngle = Vec3::Zero();      ///< rad, per axis (flexion x, abduction y, twist z)
  Vec3 maxAngle = Vec3::Zero();      ///< rad; min == max locks the axis
};

/// One named keypoint of a ModelSpec, fixed on a body.
struct KeypointSpec {
  std::string name;           ///< unique keypoint name
  std::string body;           ///< name of the body it is fixed on
  Vec3 point = Vec3::Zero();  ///< body frame, m
  float radius = 0.0f;        ///< distance from the point to the skin, m (OpenXR joint radius)
};

/// The collision filter of a ModelSpec: which body pairs never collide.
struct CollisionSpec {
  bool ignoreJointNeighbours = true;  ///< bodies joined by a joint never collide
  std::vector<std::pair<std::string, std::string>> ignoredPairs;  ///< body names
};

/// A model's name, handedness and reference length.
struct ModelMetadata {
  std::string name;                          ///< model name
  Handedness handedness = Handedness::None;  ///< which hand, if any
  float referenceLength = 0.0f;              ///< m; hands: wrist crease to middle fingertip
};

/// A model's plain description (what a model file holds); buildModel validates and compiles it.
struct ModelSpec {
  ModelMetadata metadata;               ///< name, handedness, reference length
  std::vector<BodySpec> bodies;         ///< the root is the one body that is no joint's child
  std::vector<JointSpec> joints;        ///< ball joints; each body is the child of at most one
  CollisionSpec collision;              ///< collision filter
  std::vector<KeypointSpec> keypoints;  ///< named points on the bodies
};

inline constexpr float kDefaultDensity = 1100.0f;  ///< kg/m^3, soft tissue and bone

// ---- Compiled model ----

/// A compiled body of an ArticulatedModel.
struct Body {
  std::string name;            ///< unique body name
  std::vector<Vec3> vertices;  ///< as given, body frame, m (kept for exact file round trips)
  physics::ConvexShape shape;  ///< their hull
  float mass = 0.0f;           ///< kg
  int parent = -1;             ///< body index, -1 for the root
  int joint = -1;              ///< index of the joint to the parent, -1 for the root
};

/// A compiled joint of an ArticulatedModel; bodies by index.
struct Joint {
  int parent = -1;                   ///< parent body index
  int child = -1;                    ///< child body index
  Vec3 anchorParent = Vec3::Zero();  ///< m, parent body frame
  Vec3 anchorChild = Vec3::Zero();   ///< m, child body frame
  Quat frame = Quat::Identity();     ///< joint frame in the parent body frame
  Vec3 minAngle = Vec3::Zero();      ///< rad (flexion, abduction, twist)
  Vec3 maxAngle = Vec3::Zero();      ///< rad
};

/// A compiled keypoint of an ArticulatedModel; body by index.
struct Keypoint {
  std::string name;           ///< unique keypoint name
  int body = -1;              ///< index of the body it is fixed on
  Vec3 point = Vec3::Zero();  ///< body frame, m
  float radius = 0.0f;        ///< m
};

/// One OpenXR joint as a frame fixed on a body (see docs/model.md for the axes).
struct BodyFrame {
  int body = -1;        ///< index of the body it is fixed on
  Pose local;           ///< in the body frame
  float radius = 0.0f;  ///< m
};

/// A validated, compiled articulated model, built by buildModel; immutable.
class ArticulatedModel {
 public:
  const ModelMetadata& metadata() const { return metadata_; }            ///< name, handedness, size
  const std::vector<Body>& bodies() const { return bodies_; }            ///< bodies by index
  const std::vector<Joint>& joints() const { return joints_; }           ///< joints by index
  const std::vector<Keypoint>& keypoints() const { return keypoints_; }  ///< keypoints by index
  int bodyCount() const { return static_cast<int>(bodies_.size()); }     ///< number of bodies
  int jointCount() const { return static_cast<int>(joints_.size()); }    ///< number of joints
  int root() const { return root_; }  ///< index of the root body (no joint's child)
  /// Body indices with every parent before its children (root first).
  const std::vector<int>& kinematicOrder() const { return order_; }
  /// Index of the named body, -1 when absent.
  int bodyIndex(const std::string& name) const;
  /// Index of the named keypoint, -1 when absent.
  int keypointIndex(const std::string& name) const;
  /// Whether bodies a and b may collide (the collision filter).
  bool collides(int a, int b) const {
    return collides_[static_cast<size_t>(a * bodyCount() + b)] != 0;
  }
  /// Whether `ancestor` is `body` or on its path to the root.
  bool isAncestorOrSelf(int ancestor, int body) const {
    return ancestorOrSelf_[static_cast<size_t>(body * bodyCount() + ancestor)] != 0;
  }

  /// Hand layouts: present when the model names all 21 MediaPipe keypoints (docs/model.md);
  /// the OpenXR frames additionally need palm_center and the four finger *_cmc keypoints.
  bool hasKeypoints21() const { return hasKeypoints21_; }
  /// Indices into keypoints() of the 21 MediaPipe keypoints, in MediaPipe order.
  const std::array<int, 21>& keypoints21Indices() const { return keypoints21_; }
  /// Whether openXrFrames() is filled (see hasKeypoints21).
  bool hasOpenXrJoints() const { return hasOpenXr_; }
  /// The 26 OpenXR hand joints as frames on the bodies, in OpenXR order.
  const std::array<BodyFrame, 26>& openXrFrames() const { return openXr_; }

  /// Back to a plain description (the exact inverse of buildModel up to mass/density:
  /// bodies carry their mass).
  ModelSpec spec() const;

 private:
  friend Result<ArticulatedModel> buildModel(const ModelSpec& spec);
  ArticulatedModel() = default;

  ModelMetadata metadata_;
  std::vector<Body> bodies_;
  std::vector<Joint> joints_;
  std::vector<Keypoint> keypoints_;
  CollisionSpec collision_;
  int root_ = 0;
  std::vector<int> order_;
  std::vector<unsigned char> collides_;        ///< (bodyCount x bodyCount), symmetric
  std::vector<unsigned char> ancestorOrSelf_;  ///< (bodyCount x bodyCount), [body][ancestor]
  bool hasKeypoints21_ = false;
  std::array<int, 21> keypoints21_{};
  bool hasOpenXr_ = false;
  std::array<BodyFrame, 26> openXr_{};
};

/// Validates a description and compiles it. Errors carry the JSON path of the first problem,
/// e.g. "bodies[5].vertices: fewer than 4 non-coplanar points".
Result<ArticulatedModel> buildModel(const ModelSpec& spec);

/// Model files (JSON, docs/formats/model.md). Errors name the file and the JSON path.
Result<ArticulatedModel> loadModel(const std::filesystem::path& path);
/// Parses model JSON text; errors start with sourceName (a file name or similar).
Result<ArticulatedModel> parseModel(const std::string& jsonText, const std::string& sourceName);
/// Writes modelToJson(model) to path.
Status saveModel(const ArticulatedModel& model, const std::filesystem::path& path);
std::string modelToJson(const ArticulatedModel& model);  ///< the exact text saveModel writes

/// The default hand: 17 bodies (0 forearm, 1 palm, 2-4 thumb metacarpal/proximal/distal,
/// 5-7 index proximal/middle/distal, 8-10 middle, 11-13 ring, 14-16 pinky) and 16 joints
/// (joint j has child body j + 1), generated from anthropometric proportions.
/// `shape` stretches single bones and thickens single digits; the default shape is the default
/// hand bit for bit.
ArticulatedModel makeDefaultHand(const HandDimensions& dimensions = {}, Side side = Side::Right,
                                 const HandShape& shape = {});

/// Uniform scaling about each body frame origin: every length times `factor`, masses times
/// factor^3. factor > 0.
ArticulatedModel scaleModel(const ArticulatedModel& model, float factor);

/// The mirror image through each body's x = 0 plane (right hand <-> left hand). Frames stay
/// right-handed; a pose with angles (f, a, t) mirrors to (f, -a, -t) (mirrorAngles).
ArticulatedModel mirrorModel(const ArticulatedModel& model);

}  // namespace dynahand::model
