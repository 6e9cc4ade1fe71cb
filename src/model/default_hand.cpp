// The default hand, generated from anthropometric proportions of hand length L (wrist crease
// to middle fingertip) and palm width W (across the four knuckles). Segment lengths follow
// the ratios of Buchholz, Armstrong & Goldstein (1992, "Anthropometric data for describing
// the kinematics of the human hand"), rescaled so the middle finger chain sums to L; radii
// are fractions of W. Body frames: origin at the joint with the parent, +z distal along the
// bone, +y dorsal (out of the back of the hand), +x radial (toward the thumb) for a right
// hand. Joint angles (model_pose.h): flexion about +x bends toward the palm, abduction is
// positive toward +x (the thumb side of a right hand), twist is about the bone. Finger bones are
// convex hulls of two spheres (tapered capsules) centred on their joints, so neighbours share a
// ball around every joint and never show a gap.
#include <array>
#include <cassert>
#include <cmath>
#include <numbers>
#include <string>

#include "dynahand/model.h"

namespace dynahand::model {
namespace {

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;
constexpr float kPi = std::numbers::pi_v<float>;

// Sample coordinates below 0.1 um are rounding residue of cos(pi / 2): written as 0.
Vec3 snap(const Vec3& v) {
  return v.unaryExpr([](float c) { return std::abs(c) < 1e-7f ? 0.0f : c; });
}

// Points on an axis-aligned ellipsoid: poles plus `rings` latitude rings of `segments`.
void addEllipsoid(std::vector<Vec3>& out, const Vec3& centre, const Vec3& radii, int rings,
                  int segments) {
  out.push_back(centre + Vec3(0, 0, radii.z()));
  out.push_back(centre - Vec3(0, 0, radii.z()));
  for (int r = 0; r < rings; ++r) {
    const float lat = -kPi / 2 + kPi * static_cast<float>(r + 1) / static_cast<float>(rings + 1);
    // Alternate rings are rotated half a step so the hull has no long vertical edges.
    const float phase = (r % 2) * kPi / static_cast<float>(segments);
    for (int s = 0; s < segments; ++s) {
      const float lon = phase + 2 * kPi * static_cast<float>(s) / static_cast<float>(segments);
      out.push_back(snap(centre + Vec3(radii.x() * std::cos(lat) * std::cos(lon),
                                       radii.y() * std::cos(lat) * std::sin(lon),
                                       radii.z() * std::sin(lat))));
    }
  }
}

// An elliptical ring in a plane z = const.
void addRing(std::vector<Vec3>& out, const Vec3& centre, float halfWidth, float halfThickness,
             int segments) {
  for (int s = 0; s < segments; ++s) {
    const float lon = 2 * kPi * static_cast<float>(s) / static_cast<float>(segments);
    out.push_back(
        snap(centre + Vec3(halfWidth * std::cos(lon), halfThickness * std::sin(lon), 0.0f)));
  }
}

// A tapered capsule along +z: spheres of radius r0 at z = 0 and r1 at z = length.
std::vector<Vec3> capsule(float r0, float r1, float length) {
  std::vector<Vec3> points;
  addEllipsoid(points, Vec3::Zero(), Vec3::Constant(r0), 3, 6);
  addEllipsoid(points, Vec3(0, 0, length), Vec3::Constant(r1), 3, 6);
  return points;
}

Vec3 degrees(float x, float y, float z) {
  return Vec3(x, y, z) * kDeg;
}

struct FingerShape {
  const char* name;
  float mcpX;        // knuckle position across the palm, fraction of W (+ radial)
  float mcpY;        // dorsal offset of the knuckle, fraction of W (palm arch)
  float mcpZ;        // knuckle distance from the wrist, fraction of L
  float splayDeg;    // rest spread about the palm's y axis, degrees (+ radial)
  float lengths[3];  // proximal, middle, distal (to the tip) phalanx, fraction of L
  float radius;      // proximal phalanx base radius, fraction of W
  float minAbductionDeg, maxAbductionDeg;  // spread range, degrees, + radial
};

// Middle finger: palm 0.47 L + phalanges 0.245 + 0.155 + 0.13 = L. Other digits scale the
// middle finger's phalanges by Buchholz's ratios (index 0.96/0.84/0.90, ring 0.94/0.97/0.99,
// pinky 0.74/0.69/0.86).
constexpr std::array<FingerShape, 4> kFingers = {{
    {"index", 0.385f, -0.02f, 0.455f, 4.0f, {0.2345f, 0.130f, 0.117f}, 0.112f, -15.0f, 20.0f},
    {"middle", 0.125f, 0.0f, 0.470f, 0.0f, {0.245f, 0.155f, 0.130f}, 0.115f, -15.0f, 15.0f},
    {"ring", -0.125f, -0.01f, 0.450f, -4.0f, {0.229f, 0.150f, 0.129f}, 0.108f, -20.0f, 12.0f},
    {"pinky", -0.39f, -0.04f, 0.415f, -9.0f, {0.182f, 0.107f, 0.112f}, 0.095f, -30.0f, 12.0f},
}};

// Radius along a finger, as a fraction of its base radius, at joints 0..3 (MCP, PIP, DIP, tip).
constexpr std::array<float, 4> kTaper = {1.0f, 0.88f, 0.80f, 0.72f};

const char* const kPhalanx[3] = {"proximal", "middle", "distal"};
const char* const kJointName[4] = {"mcp", "pip", "dip", "tip"};

}  // namespace

namespace {

// Appends to a model spec (the default hand's builders below).
struct SpecBuilder {
  ModelSpec& spec;
  void body(const std::string& name, std::vector<Vec3> points) {
    spec.bodies.push_back(BodySpec{name, std::move(points), std::nullopt, std::nullopt});
  }
  void joint(const std::string& parent, const std::string& child, const Vec3& anchor,
             const Quat& frame, const Vec3& minAngle, const Vec3& maxAngle) {
    spec.joints.push_back(
        JointSpec{parent, child, anchor, Vec3::Zero(), frame, minAngle, maxAngle});
  }
  void keypoint(const std::string& name, const std::string& body, const Vec3& point, float radius) {
    spec.keypoints.push_back(KeypointSpec{name, body, point, radius});
  }
};

// 0 forearm: origin at the wrist joint centre, reaching 0.5 L back toward the elbow.
void addForearm(SpecBuilder& b, float L, float W) {
  std::vector<Vec3> points;
  // The rounded distal end reaches past the wrist joint centre into the palm.
  addRing(points, Vec3(0, 0, 0.12f * W), 0.24f * W, 0.12f * W, 16);
  addRing(points, Vec3(0, 0, 0.0f), 0.34f * W, 0.19f * W, 16);
  addRing(points, Vec3(0, 0, -0.5f * L), 0.40f * W, 0.25f * W, 16);
  b.body("forearm", std::move(points));
}

// 1 palm: wrist section, mid-palm section and a flattened ball around each knuckle (mcp);
// the wrist joint and the wrist and palm keypoints (MediaPipe wrist = the wrist joint centre).
void addPalm(SpecBuilder& b, const std::array<Vec3, 4>& mcp, float L, float W,
             const HandShape& shape) {
  std::vector<Vec3> points;
  const float t = shape.palmThickness;
  addRing(points, Vec3(0, 0, -0.1f * W), 0.26f * W, 0.13f * W * t, 16);  // heel of the palm
  addRing(points, Vec3(0, 0, 0), 0.34f * W, 0.19f * W * t, 16);
  addRing(points, Vec3(0, -0.02f * W, 0.22f * L), 0.46f * W, 0.18f * W * t, 16);
  for (size_t f = 0; f < 4; ++f) {
    const float r = kFingers[f].radius * W * shape.fingerThickness[f + 1];
    addEllipsoid(points, mcp[f], Vec3(r, 1.2f * r, r), 3, 8);
  }
  b.body("palm", std::move(points));
  b.joint("forearm", "palm", Vec3::Zero(), Quat::Identity(), degrees(-70, -35, 0),
          degrees(80, 20, 0));
  b.keypoint("wrist", "palm", Vec3::Zero(), 0.19f * W);
  b.keypoint("palm_center", "palm", Vec3(0.5f * mcp[1].x(), -0.01f * W, 0.5f * mcp[1].z()),
             0.18f * W);
}

// 2-4 thumb. The carpometacarpal joint sits radial and volar near the wrist; at rest the thumb
// points distally, radially and slightly volar, its nail turned toward the radial side, so
// flexion (about its x) sweeps it across the palm.
void addThumb(SpecBuilder& b, float L, float W, const HandShape& shape) {
  const Vec3 cmc = Vec3(0.25f * W, -0.08f * W, 0.11f * L) * shape.boneLength[0][0];
  const Vec3 z = Vec3(0.52f, -0.22f, 0.82f).normalized();
  const Vec3 y = (Vec3(0.8f, 0.6f, 0.0f) - z * z.dot(Vec3(0.8f, 0.6f, 0.0f))).normalized();
  Mat3 axes;
  axes.col(0) = y.cross(z);
  axes.col(1) = y;
  axes.col(2) = z;
  const Quat restFrame(axes);
  const auto& stretch = shape.boneLength[0];
  const std::array<float, 3> lengths = {0.251f * L * stretch[1], 0.196f * L * stretch[2],
                                        0.158f * L * stretch[3]};
  const float t = shape.fingerThickness[0];
  const std::array<float, 4> radii = {0.17f * W * t, 0.13f * W * t, 0.115f * W * t, 0.10f * W * t};
  const char* names[3] = {"thumb_metacarpal", "thumb_proximal", "thumb_distal"};
  const char* keys[4] = {"thumb_cmc", "thumb_mcp", "thumb_ip", "thumb_tip"};
  for (size_t i = 0; i < 3; ++i) {
    // The distal bone's end sphere is centred one radius short of the tip.
    const float length = i == 2 ? lengths[i] - radii[i + 1] : lengths[i];
    b.body(names[i], capsule(radii[i], radii[i + 1], length));
    b.keypoint(keys[i], names[i], Vec3::Zero(), radii[i]);
  }
  b.keypoint(keys[3], names[2], Vec3(0, 0, lengths[2]), radii[3]);
  b.joint("palm", names[0], cmc, restFrame, degrees(-20, -30, -20), degrees(55, 40, 30));
  b.joint(names[0], names[1], Vec3(0, 0, lengths[0]), Quat::Identity(), degrees(-10, -10, -5),
          degrees(60, 15, 5));
  b.joint(names[1], names[2], Vec3(0, 0, lengths[1]), Quat::Identity(), degrees(-15, 0, 0),
          degrees(85, 0, 0));
}

// 5-16 fingers: proximal, middle, distal phalanx each, from the knuckle at mcp.
// `digit` 1-4 indexes `shape` (0 is the thumb).
void addFinger(SpecBuilder& b, const FingerShape& finger, const Vec3& mcp, float L, float W,
               const HandShape& shape, size_t digit) {
  const std::string n = finger.name;
  const float base = finger.radius * W * shape.fingerThickness[digit];
  const auto& stretch = shape.boneLength[digit];
  const std::array<float, 3> lengths = {finger.lengths[0] * L * stretch[1],
                                        finger.lengths[1] * L * stretch[2],
                                        finger.lengths[2] * L * stretch[3]};
  for (size_t i = 0; i < 3; ++i) {
    const float r0 = kTaper[i] * base;
    const float r1 = kTaper[i + 1] * base;
    const float length = lengths[i];
    b.body(n + "_" + kPhalanx[i], capsule(r0, r1, i == 2 ? length - r1 : length));
    b.keypoint(n + "_" + kJointName[i], n + "_" + kPhalanx[i], Vec3::Zero(), r0);
  }
  b.keypoint(n + "_tip", n + "_distal", Vec3(0, 0, lengths[2]), kTaper[3] * base);
  // Metacarpal bases converge toward the wrist (OpenXR metacarpal joints).
  b.keypoint(n + "_cmc", "palm", Vec3(0.6f * mcp.x(), mcp.y(), 0.2f * mcp.z()), 0.8f * base);
  const Quat splay(Eigen::AngleAxisf(finger.splayDeg * kDeg, Vec3::UnitY()));
  b.joint("palm", n + "_proximal", mcp, splay, degrees(-25, finger.minAbductionDeg, -5),
          degrees(95, finger.maxAbductionDeg, 5));
  b.joint(n + "_proximal", n + "_middle", Vec3(0, 0, lengths[0]), Quat::Identity(),
          degrees(-5, 0, 0), degrees(110, 0, 0));
  b.joint(n + "_middle", n + "_distal", Vec3(0, 0, lengths[1]), Quat::Identity(),
          degrees(-10, 0, 0), degrees(85, 0, 0));
}

}  // namespace

bool HandShape::identity() const {
  for (const auto& digit : boneLength)
    for (float f : digit)
      if (f != 1.0f) return false;
  for (float f : fingerThickness)
    if (f != 1.0f) return false;
  return palmThickness == 1.0f;
}

ArticulatedModel makeDefaultHand(const HandDimensions& dimensions, Side side,
                                 const HandShape& shape) {
  const float L = dimensions.length;
  const float W = dimensions.width;
  assert(L > 0.0f && W > 0.0f && "hand dimensions must be positive");

  ModelSpec spec;
  spec.metadata.name = "dynahand default hand";
  spec.metadata.handedness = Handedness::Right;
  spec.metadata.referenceLength = L;
  spec.collision.ignoreJointNeighbours = true;
  // The thenar base sits on the wrist: the thumb metacarpal and the forearm always touch.
  spec.collision.ignoredPairs.emplace_back("forearm", "thumb_metacarpal");
  SpecBuilder builder{spec};
  std::array<Vec3, 4> mcp;
  for (size_t f = 0; f < 4; ++f)
    mcp[f] = Vec3(kFingers[f].mcpX * W, kFingers[f].mcpY * W, kFingers[f].mcpZ * L) *
             shape.boneLength[f + 1][0];
  addForearm(builder, L, W);
  addPalm(builder, mcp, L, W, shape);
  addThumb(builder, L, W, shape);
  for (size_t f = 0; f < 4; ++f) addFinger(builder, kFingers[f], mcp[f], L, W, shape, f + 1);

  // Joint order must match the body order (joint j has child j + 1): thumb joints were added
  // before the finger joints, as the bodies were.
  Result<ArticulatedModel> right = buildModel(spec);
  assert(right.ok() && "the default hand is a valid model");
  if (side == Side::Right) return std::move(right).value();
  return mirrorModel(right.value());
}

}  // namespace dynahand::model
