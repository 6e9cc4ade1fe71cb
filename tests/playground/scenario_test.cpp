// Playground scenarios with the tracker in the loop: synthetic tof frames of a clip seen by
// the desk-facing camera (the lever and the box grasp also by the head-mounted one) -> tracker
// (ground-truth first frame) -> powered ragdoll hand in a scene. Thresholds are the issue's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "dynahand/model.h"
#include "scenario.h"

namespace dynahand::playground {
namespace {

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;
constexpr float kFps = 30.0f;

// headClip: the scene camera is remapped for this clip seen by the head-mounted camera
// (test::headMountedCamera); empty: the scene's own (desk) mapping.
std::unique_ptr<Playground> build(const std::string& sceneName, const std::string& headClip = "") {
  auto scene = loadScene(test::sceneFile(sceneName));
  EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.message());
  if (!scene) return nullptr;
  if (!headClip.empty()) scene->camera = test::headMountedCamera(scene->camera, headClip);
  auto pg = Playground::create(*scene, model::makeDefaultHand());
  EXPECT_TRUE(pg.ok()) << (pg.ok() ? "" : pg.message());
  return pg.ok() ? std::move(*pg) : nullptr;
}

void expectTrackedMostly(const test::ScenarioStats& stats) {
  if (std::getenv("DYNAHAND_PLAYGROUND_TRUTH")) return;
  EXPECT_GE(stats.trackedFrames, stats.frames - 2);
  std::printf("tracked %d/%d frames, mean keypoint error %.1f mm\n", stats.trackedFrames,
              stats.frames, 1000.0 * static_cast<double>(stats.meanKeypointErrorM));
}

// Printing helpers (printf takes doubles).
double cm(float m) {
  return 100.0 * static_cast<double>(m);
}
double mm(float m) {
  return 1000.0 * static_cast<double>(m);
}
double degrees(float rad) {
  return static_cast<double>(rad / kDeg);
}
double seconds(int frames) {
  return frames / static_cast<double>(kFps);
}

// Longest run of consecutive frames for which `ok` held.
struct RunCounter {
  int current = 0, longest = 0;
  void add(bool ok) {
    current = ok ? current + 1 : 0;
    longest = std::max(longest, current);
  }
};

// The box scenario's measures: how high the box went and its longest stay >= 10 cm up.
struct GraspOutcome {
  float highest = 0.0f;  // m above its start
  int heldFrames = 0;    // longest run of frames >= 10 cm up
  bool liftedAndHeld() const {
    return highest >= 0.10f && heldFrames >= static_cast<int>(2.0f * kFps);
  }
};

GraspOutcome graspLiftAndHold(Playground& pg, synth::CameraPlacement placement,
                              std::optional<std::uint64_t> seed = std::nullopt) {
  const int box = pg.bodyIndex("box");
  const float startY = pg.bodyPose(box).p.y();
  GraspOutcome out;
  RunCounter held;
  const auto stats = test::runScenario(
      pg, "reach-grasp-lift", 132,
      [&](int, const Playground& p) {
        const float lift = p.bodyPose(box).p.y() - startY;
        out.highest = std::max(out.highest, lift);
        held.add(lift >= 0.10f);
      },
      placement, seed);
  expectTrackedMostly(stats);
  out.heldFrames = held.longest;
  std::printf("box lifted up to %.1f cm, held >= 10 cm for %.2f s\n", cm(out.highest),
              seconds(out.heldFrames));
  return out;
}

// The power grasp closes fingers and thumb around the box from above; the joint drives are
// springs, so the digits squeeze it to a force balance (docs/playground.md).
TEST(Scenario, GraspLiftAndHoldABox) {
  auto pg = build("grasp");
  ASSERT_NE(pg, nullptr);
  const GraspOutcome g = graspLiftAndHold(*pg, synth::CameraPlacement::DeskFacing);
  EXPECT_GE(g.highest, 0.10f);
  EXPECT_GE(g.heldFrames, static_cast<int>(2.0f * kFps)) << "held 2 s without dropping";
}

// The same grasp seen by the head-mounted camera. Knife-edge: from about frame 30 the forearm
// hides the thumb, which the tracker then tucks part of the way toward the index, and whether
// the box stays in the hand for 2 s turns on the sensor's noise. So the scenario runs on 16
// noise seeds and asks for the box lifted and held on at least 5 (7 with the shipped tracker;
// docs/playground.md).
TEST(Scenario, GraspLiftAndHoldABoxSeenFromTheHead) {
  int held = 0;
  for (std::uint64_t seed = 1; seed <= 16; ++seed) {
    auto pg = build("grasp", "reach-grasp-lift");
    ASSERT_NE(pg, nullptr);
    std::printf("noise seed %d: ", static_cast<int>(seed));
    if (graspLiftAndHold(*pg, synth::CameraPlacement::HeadMounted, seed).liftedAndHeld()) ++held;
  }
  std::printf("lifted and held 2 s on %d of 16 noise seeds\n", held);
  EXPECT_GE(held, 5);
}

// The same clip grasps the barbell's bar between the end caps.
TEST(Scenario, BarbellPickedUpByTheBarDoesNotSlipSideways) {
  auto pg = build("barbell");
  ASSERT_NE(pg, nullptr);
  const int bar = pg->bodyIndex("barbell/bar");
  const int palm = pg->bodyIndex("hand/palm");
  const float startY = pg->bodyPose(bar).p.y();
  float highest = 0.0f;
  RunCounter held;
  // Sideways = along the bar's axis, measured from the palm while the bar is up.
  float minAlong = 1.0f, maxAlong = -1.0f;
  const auto stats = test::runScenario(*pg, "reach-grasp-lift", 132, [&](int, const Playground& p) {
    const Pose barPose = p.bodyPose(bar);
    const float lift = barPose.p.y() - startY;
    highest = std::max(highest, lift);
    held.add(lift >= 0.10f);
    if (lift >= 0.10f) {
      const float along = (p.bodyPose(palm).p - barPose.p).dot(barPose.rotate(Vec3::UnitX()));
      minAlong = std::min(minAlong, along);
      maxAlong = std::max(maxAlong, along);
    }
  });
  expectTrackedMostly(stats);
  std::printf("bar lifted up to %.1f cm, held for %.2f s, slid %.1f mm along its axis\n",
              cm(highest), seconds(held.longest), mm(maxAlong - minAlong));
  EXPECT_GE(highest, 0.10f);
  EXPECT_GE(held.longest, static_cast<int>(2.0f * kFps));
  EXPECT_LT(maxAlong - minAlong, 0.02f) << "the bar slides less than 2 cm in the hand";
}

// The lever scenario with the clip seen by the head-mounted camera (back of the hand toward it),
// the scene's camera remapped so that the same motion lands on the same scene poses.
TEST(Scenario, LeverPushedFromOneEndStopToTheOtherSeenFromTheHead) {
  auto pg = build("lever", "push-forward");
  ASSERT_NE(pg, nullptr);
  const float start = *pg->hingeAngle("switch");
  const auto stats = test::runScenario(
      *pg, "push-forward", 72, [](int, const Playground&) {}, synth::CameraPlacement::HeadMounted);
  expectTrackedMostly(stats);
  const float end = *pg->hingeAngle("switch");
  std::printf("head-mounted: lever from %.1f to %.1f degrees\n", degrees(start), degrees(end));
  EXPECT_NEAR(start, 35.0f * kDeg, 1.0f * kDeg);
  EXPECT_NEAR(end, -35.0f * kDeg, 2.0f * kDeg);
}

TEST(Scenario, LeverPushedFromOneEndStopToTheOther) {
  auto pg = build("lever");
  ASSERT_NE(pg, nullptr);
  const float start = *pg->hingeAngle("switch");
  const auto stats = test::runScenario(*pg, "push-forward", 72, [](int, const Playground&) {});
  expectTrackedMostly(stats);
  const float end = *pg->hingeAngle("switch");
  std::printf("lever from %.1f to %.1f degrees\n", degrees(start), degrees(end));
  EXPECT_NEAR(start, 35.0f * kDeg, 1.0f * kDeg);
  EXPECT_NEAR(end, -35.0f * kDeg, 2.0f * kDeg);
}

// The key grip pinches the dial's fin between the thumb and the index; the forearm rolls
// 110 degrees about the pinch, which is on the dial's axis.
TEST(Scenario, DialTurnedAtLeast90Degrees) {
  auto pg = build("dial");
  ASSERT_NE(pg, nullptr);
  const float start = *pg->hingeAngle("dial");
  float farthest = 0.0f;
  const auto stats = test::runScenario(*pg, "turn-key", 72, [&](int, const Playground& p) {
    farthest = std::max(farthest, std::abs(*p.hingeAngle("dial") - start));
  });
  expectTrackedMostly(stats);
  std::printf("dial turned up to %.1f degrees\n", degrees(farthest));
  EXPECT_GE(farthest, 90.0f * kDeg);
}

// Deepest point of any hand body's hull inside a static box body (m, >= 0).
float deepestInside(const physics::World& world, physics::BodyId box, const model::ModelPose& hand,
                    const model::ArticulatedModel& model) {
  const Pose boxPose = world.pose(box);
  const physics::ConvexShape& shape = world.bodyShape(box);
  float deepest = 0.0f;
  for (std::size_t b = 1; b < hand.bodies.size(); ++b)
    for (const Vec3& v : model.bodies()[b].shape.vertices())
      deepest = std::max(
          deepest, -shape.signedDistance(boxPose.inverseTransform(hand.bodies[b].transform(v))));
  return deepest;
}

// A fist pushed sideways (little finger first, `push-sideways`) 6 cm into a wall at its side;
// the tracker follows it (3.5 mm mean keypoint error) and its tracked hand gets 6 cm in.
TEST(Scenario, HandStaysOutsideAWallTheTrackedHandGoesThrough) {
  auto pg = build("wall");
  ASSERT_NE(pg, nullptr);
  const model::ArticulatedModel model = model::makeDefaultHand();
  const physics::BodyId wall = pg->bodies()[static_cast<std::size_t>(pg->bodyIndex("wall"))].id;
  float trackedDepth = 0.0f, virtualDepth = 0.0f, contactDepth = 0.0f;
  const auto stats = test::runScenario(*pg, "push-sideways", 72, [&](int, const Playground& p) {
    trackedDepth = std::max(trackedDepth, deepestInside(p.world(), wall, p.handTarget(), model));
    virtualDepth = std::max(virtualDepth, deepestInside(p.world(), wall, p.handPose(), model));
    contactDepth = std::max(contactDepth, handPenetration(p, wall));
  });
  expectTrackedMostly(stats);
  std::printf("tracked hand %.1f cm inside the wall, virtual hand %.2f mm (contacts %.2f mm)\n",
              cm(trackedDepth), mm(virtualDepth), mm(contactDepth));
  EXPECT_GE(trackedDepth, 0.05f) << "the tracked hand goes through the wall";
  EXPECT_LT(virtualDepth, 0.005f);
  EXPECT_LT(contactDepth, 0.005f);
}

}  // namespace
}  // namespace dynahand::playground
