// Scene files, scene building, view navigation and the virtual hand's drives (no tracker).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "dynahand/model.h"
#include "dynahand/playground.h"
#include "dynahand/playground_io.h"
#include "scene_files.h"

namespace dynahand::playground {
namespace {

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;

SceneSpec loadExample(const std::string& name) {
  auto scene = loadScene(test::sceneFile(name));
  EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.message());
  return scene.ok() ? *scene : SceneSpec{};
}

std::unique_ptr<Playground> build(const SceneSpec& scene) {
  static const model::ArticulatedModel hand = model::makeDefaultHand();
  auto pg = Playground::create(scene, hand);
  EXPECT_TRUE(pg.ok()) << (pg.ok() ? "" : pg.message());
  return pg.ok() ? std::move(*pg) : nullptr;
}

// The hand's rest pose as the desk-facing synthetic camera sees it (palm towards the camera,
// fingers up, forearm tilted 15 degrees away; docs/synth.md), in the camera frame. The
// example scenes' camera maps it to a palm-down hand 15 cm above the table.
model::ModelPose restHandInCamera() {
  const model::ArticulatedModel hand = model::makeDefaultHand();
  model::JointAngles a = model::zeroAngles(hand);
  model::clampToLimits(hand, a);
  Mat3 axes;
  axes.col(0) = Vec3::UnitX();
  axes.col(1) = Vec3::UnitZ();
  axes.col(2) = -Vec3::UnitY();
  a.root =
      Pose{Vec3(0, 0.07f, 0.4f), Quat(Eigen::AngleAxisf(15.0f * kDeg, Vec3::UnitX())) * Quat(axes)};
  return model::forwardKinematics(hand, a);
}

// Only the examples' table and camera.
SceneSpec tableOnly() {
  auto scene = parseScene(
      R"({"format": "dynahand-scene", "version": 1, "name": "table",
          "camera": {"position": [0, -0.217, -0.054], "pitchDeg": -75, "yawDeg": 180},
          "objects": [{"name": "table", "kind": "box", "static": true, "size": [1.0, 0.04, 0.7],
                       "position": [0, -0.02, -0.05]}]})",
      "table");
  EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.message());
  return scene.ok() ? *scene : SceneSpec{};
}

TEST(SceneFile, ExampleScenesLoadAndBuild) {
  for (const char* name : {"grasp", "barbell", "wall", "lever", "dial", "playground"}) {
    SCOPED_TRACE(name);
    const SceneSpec scene = loadExample(name);
    EXPECT_EQ(scene.name, name);
    const auto pg = build(scene);
    ASSERT_NE(pg, nullptr);
    EXPECT_GE(pg->bodyIndex("hand/palm"), 0);
    EXPECT_GE(pg->bodyIndex("hand/pad_thenar"), 0);
    EXPECT_LT(pg->bodyIndex("hand/forearm"), 0) << "the forearm is not simulated";
  }
}

TEST(SceneFile, CompoundObjectsNameTheirParts) {
  const auto pg = build(loadExample("playground"));
  ASSERT_NE(pg, nullptr);
  for (const char* part : {"barbell/bar", "barbell/cap0", "barbell/cap1", "switch/arm",
                           "switch/base", "dial/knob", "dial/fin", "swing/seat"})
    EXPECT_GE(pg->bodyIndex(part), 0) << part;
  EXPECT_TRUE(pg->hingeAngle("switch").has_value());
  EXPECT_FALSE(pg->hingeAngle("table").has_value());
}

TEST(SceneFile, ErrorsNameThePath) {
  const std::string head =
      R"({"format": "dynahand-scene", "version": 1, "camera": {"position": [0, 0.4, 0.4], "pitchDeg": 35}, )";
  struct Case {
    std::string json, expected;
  };
  const Case cases[] = {
      {R"({"format": "x", "version": 1})", "format: expected \"dynahand-scene\""},
      {R"({"format": "dynahand-scene", "version": 2})", "version: version 2 is newer"},
      {head + R"("objects": [{"name": "a", "kind": "cone", "position": [0, 0, 0]}]})",
       "objects[0].kind: unknown kind 'cone'"},
      {head + R"("objects": [{"name": "a", "kind": "box", "position": [0, 0]}]})",
       "objects[0].position: expected [x, y, z]"},
      {head +
           R"("objects": [{"name": "a", "kind": "box", "size": [0, 1, 1], "position": [0, 0, 0]}]})",
       "objects[0].size: every component must be > 0"},
      {head +
           R"("objects": [{"name": "l", "kind": "lever", "position": [0, 0, 0], "limitsDeg": [10, -10]}]})",
       "objects[0].limitsDeg: need lower <= upper"},
      {head +
           R"("objects": [{"name": "l", "kind": "dial", "position": [0, 0, 0], "limitsDeg": [-10, 10], "startDeg": 20}]})",
       "objects[0].startDeg: outside limitsDeg"},
      {head +
           R"("objects": [{"name": "c", "kind": "convex", "position": [0, 0, 0], "points": [[0, 0, 0]]}]})",
       "objects[0].points: a convex object needs at least 4 points"},
      {head +
           R"("objects": [{"name": "a", "kind": "box", "position": [0, 0, 0]}, {"name": "a", "kind": "box", "position": [0, 0, 0]}]})",
       "objects[1].name: duplicate name 'a'"},
      {head + R"("objects": [], "colour": 1})", "colour: unknown field"},
      {"{", "not valid JSON"},
  };
  for (const Case& c : cases) {
    const auto scene = parseScene(c.json, "s.json");
    ASSERT_FALSE(scene.ok()) << c.json;
    EXPECT_NE(scene.message().find("s.json: "), std::string::npos) << scene.message();
    EXPECT_NE(scene.message().find(c.expected), std::string::npos)
        << scene.message() << " / expected " << c.expected;
  }
}

// Found by fuzz/fuzz_scene.cpp: a number too large for a double (JSON allows any exponent)
// made the JSON parser throw out_of_range, which parseScene did not catch (std::terminate).
TEST(SceneFile, OverflowingNumberIsAnErrorNotACrash) {
  const std::string found =
      R"({"format": "dynahand-scene", "version": 1, "camera": {"position": [0, -0.217, -0.054],)"
      R"( "pitchDeg": -75}, "objects": [{"name": "s", "kind": "swing", "size": [0.008, 0.08, 0.008],)"
      R"( "links": 3, "position": [0.4, 0.3335, -0.9999999999E999000000000000999999]}]})";
  for (const std::string& json :
       {found, std::string(R"({"format": "dynahand-scene", "version": 1e999})")}) {
    const auto scene = parseScene(json, "s.json");
    ASSERT_FALSE(scene.ok()) << json;
    EXPECT_EQ(scene.message().rfind("s.json: not valid JSON: ", 0), 0u) << scene.message();
  }
}

// Found by fuzz/fuzz_scene.cpp: sizes far from an object's (1e-30 or 1e30 m) made a hull
// that Qhull cannot build, and building the playground crashed; a huge stepHz made one input
// frame run billions of physics steps (a hang).
TEST(SceneFile, SizesAndStepRateOutsideTheirRangeAreErrors) {
  const std::string head =
      R"({"format": "dynahand-scene", "version": 1, "camera": {"position": [0, 0.4, 0.4], "pitchDeg": 35}, )";
  struct Case {
    std::string json, expected;
  };
  const Case cases[] = {
      {head +
           R"("objects": [{"name": "a", "kind": "sphere", "radius": 1e-30, "position": [0, 0, 0]}]})",
       "objects[0].radius: must be in [0.001, 100] m"},
      {head +
           R"("objects": [{"name": "a", "kind": "box", "size": [1e-30, 1, 1], "position": [0, 0, 0]}]})",
       "objects[0].size: every component must be in [0.001, 100] m"},
      {head +
           R"("objects": [{"name": "a", "kind": "box", "size": [1e30, 1e30, 1e30], "position": [0, 0, 0]}]})",
       "objects[0].size: every component must be in [0.001, 100] m"},
      {head +
           R"("objects": [{"name": "a", "kind": "cylinder", "radius": 1e30, "length": 0.1, "position": [0, 0, 0]}]})",
       "objects[0].radius: must be in [0.001, 100] m"},
      {head +
           R"("objects": [{"name": "a", "kind": "barbell", "capLength": 1e-9, "position": [0, 0, 0]}]})",
       "objects[0].capLength: must be in [0.001, 100] m"},
      {head + R"("stepHz": 1e7, "objects": []})", "stepHz: must be in [1, 1000]"},
      {head + R"("stepHz": 0.001, "objects": []})", "stepHz: must be in [1, 1000]"},
  };
  for (const Case& c : cases) {
    const auto scene = parseScene(c.json, "s.json");
    ASSERT_FALSE(scene.ok()) << c.json;
    EXPECT_NE(scene.message().find("s.json: " + c.expected), std::string::npos)
        << scene.message() << " / expected " << c.expected;
  }
  // The ends of the ranges still build.
  for (
      const char* object :
      {R"({"name": "a", "kind": "box", "size": [100, 0.001, 100], "position": [0, 0, 0]})",
       R"({"name": "a", "kind": "sphere", "radius": 0.001, "position": [0, 0, 0]})",
       R"({"name": "a", "kind": "cylinder", "radius": 100, "length": 0.001, "position": [0, 0, 0]})",
       R"({"name": "a", "kind": "barbell", "radius": 0.001, "length": 100, "capRadius": 100, "capLength": 0.001, "position": [0, 0, 0]})",
       R"({"name": "a", "kind": "dial", "radius": 100, "length": 0.001, "size": [100, 0.001, 100], "position": [0, 0, 0]})"}) {
    const auto scene =
        parseScene(head + R"("stepHz": 1000, "objects": [)" + object + "]}", "s.json");
    ASSERT_TRUE(scene.ok()) << scene.message();
    EXPECT_NE(build(*scene), nullptr) << object;
  }
}

// Found by fuzz/fuzz_scene.cpp: a hinge axis whose length overflows a float came out of
// normalize() as the zero vector.
TEST(SceneFile, HugeHingeAxisIsNormalised) {
  const auto scene = parseScene(
      R"({"format": "dynahand-scene", "version": 1, "camera": {"position": [0, 0.4, 0.4], "pitchDeg": 35},
          "objects": [{"name": "l", "kind": "lever", "position": [0, 0, 0], "axis": [3e38, 3e38, 3e38],
                       "limitsDeg": [-10, 10]}]})",
      "s.json");
  ASSERT_TRUE(scene.ok()) << scene.message();
  const Vec3 expected = Vec3::Ones().normalized();
  EXPECT_NEAR((scene->objects[0].axis - expected).norm(), 0.0f, 1e-6f);
}

TEST(SceneFile, CameraLookingDownMapsCameraDownToSceneDown) {
  const float pitch = 35.0f * kDeg;
  const Pose camera = cameraLookingDown(Vec3(0, 0.4f, 0.4f), pitch);
  // The synthetic head-mounted camera's world-down direction (docs/synth.md).
  const Vec3 downInCamera(0, std::cos(pitch), std::sin(pitch));
  EXPECT_LT((camera.rotate(downInCamera) - Vec3(0, -1, 0)).norm(), 1e-6f);
  EXPECT_LT((camera.rotate(Vec3::UnitX()) - Vec3::UnitX()).norm(), 1e-6f);
}

TEST(SceneFile, DeskCameraMapsThePalmDownFingersForward) {
  // The examples' camera (pitch -75, yaw 180): the desk-facing rest hand's dorsal direction
  // (away from the camera, tilted 15 degrees) points up, its fingers forward (-z).
  const Pose camera = cameraLookingDown(Vec3::Zero(), -75.0f * kDeg, 180.0f * kDeg);
  const Quat tilt(Eigen::AngleAxisf(15.0f * kDeg, Vec3::UnitX()));
  EXPECT_LT((camera.rotate(tilt * Vec3::UnitZ()) - Vec3::UnitY()).norm(), 1e-5f);
  EXPECT_LT((camera.rotate(tilt * -Vec3::UnitY()) - -Vec3::UnitZ()).norm(), 1e-5f);
  EXPECT_LT((camera.rotate(Vec3::UnitX()) - -Vec3::UnitX()).norm(), 1e-5f);
}

TEST(SceneBuild, ObjectsRestOnTheTableWithoutTheHand) {
  const auto pg = build(loadExample("grasp"));
  ASSERT_NE(pg, nullptr);
  std::vector<Pose> start;
  for (std::size_t i = 0; i < pg->bodies().size(); ++i)
    start.push_back(pg->bodyPose(static_cast<int>(i)));
  for (int i = 0; i < 60; ++i) pg->step(std::nullopt, 1.0f / 30.0f);
  EXPECT_NEAR(pg->time(), 2.0, 1e-3);
  for (std::size_t i = 0; i < pg->bodies().size(); ++i) {
    const SceneBody& b = pg->bodies()[i];
    if (b.isHand) continue;
    const float moved = (pg->bodyPose(static_cast<int>(i)).p - start[i].p).norm();
    EXPECT_LT(moved, 0.003f) << b.name << " drifted";
  }
}

TEST(SceneBuild, LeverFallsToItsStopAndTheSwingHangs) {
  SceneSpec scene = loadExample("playground");
  const auto pg = build(scene);
  ASSERT_NE(pg, nullptr);
  for (int i = 0; i < 90; ++i) pg->step(std::nullopt, 1.0f / 30.0f);
  // The switch starts leaning to +35 degrees, its upper stop: gravity keeps it there.
  EXPECT_NEAR(*pg->hingeAngle("switch"), 35.0f * kDeg, 1.0f * kDeg);
  const float dial = *pg->hingeAngle("dial");
  EXPECT_NEAR(dial, 0.0f, 2.0f * kDeg) << "a balanced dial does not turn by itself";
  const Pose seat = pg->bodyPose(pg->bodyIndex("swing/seat"));
  const Pose anchor = pg->bodyPose(pg->bodyIndex("swing/anchor"));
  EXPECT_LT(std::abs(seat.p.x() - anchor.p.x()), 0.005f);
  EXPECT_LT(seat.p.y(), anchor.p.y());
}

TEST(SceneBuild, BarbellCapsStayOnTheBar) {
  const auto pg = build(loadExample("barbell"));
  ASSERT_NE(pg, nullptr);
  const int bar = pg->bodyIndex("barbell/bar"), cap = pg->bodyIndex("barbell/cap1");
  const Pose rel0 = pg->bodyPose(bar).inverse() * pg->bodyPose(cap);
  for (int i = 0; i < 30; ++i) pg->step(std::nullopt, 1.0f / 30.0f);
  const Pose rel = pg->bodyPose(bar).inverse() * pg->bodyPose(cap);
  EXPECT_LT((rel.p - rel0.p).norm(), 1e-4f);
  EXPECT_NEAR(rel0.p.x(), 0.5f * (0.26f - 0.025f), 1e-5f);
}

TEST(VirtualHand, HoldsStillAtAStillTarget) {
  const SceneSpec scene = tableOnly();
  const auto pg = build(scene);
  ASSERT_NE(pg, nullptr);
  const model::ModelPose rest = restHandInCamera();
  pg->placeHand(rest);
  EXPECT_NEAR(pg->bodyPose(pg->bodyIndex("hand/palm")).p.y(), 0.151f, 0.002f) << "15 cm up";
  for (int i = 0; i < 60; ++i) pg->step(rest, 1.0f / 30.0f);
  const model::ModelPose now = pg->handPose();
  const model::ModelPose& target = pg->handTarget();
  float worst = 0.0f;
  for (std::size_t b = 1; b < now.bodies.size(); ++b)
    worst = std::max(worst, (now.bodies[b].p - target.bodies[b].p).norm());
  EXPECT_LT(worst, 0.01f) << "drives hold the hand against gravity";
  // The palm is where the camera pose puts the tracked palm.
  EXPECT_LT((target.bodies[1].p - pg->trackingToScene().transform(rest.bodies[1].p)).norm(), 1e-5f);
}

TEST(VirtualHand, PalmStaysOnTheTableWhenTheTargetSinksThroughIt) {
  // A target 30 cm below the table top: contacts stop the capped drive at the table.
  const SceneSpec scene = tableOnly();
  const auto pg = build(scene);
  ASSERT_NE(pg, nullptr);
  model::ModelPose rest = restHandInCamera();
  pg->placeHand(rest);
  model::ModelPose sunk = rest;
  const Vec3 down = pg->trackingToScene().q.conjugate() * Vec3(0, -0.3f, 0);
  for (Pose& p : sunk.bodies) p.p += down;
  float lowest = 1.0f;
  for (int i = 0; i < 45; ++i) {
    pg->step(sunk, 1.0f / 30.0f);
    lowest = std::min(lowest, pg->bodyPose(pg->bodyIndex("hand/palm")).p.y());
    EXPECT_LT(
        handPenetration(*pg, pg->bodies()[static_cast<std::size_t>(pg->bodyIndex("table"))].id),
        0.005f);
  }
  EXPECT_GT(lowest, 0.0f) << "the palm stays above the table top";
}

TEST(Navigation, OffsetMovesOnlyNearTheImageEdge) {
  Intrinsics camera{320, 240, 224.0f, 224.0f, 159.5f, 119.5f};
  NavigationSettings settings;
  ViewNavigator centre(settings, camera);
  for (int i = 0; i < 30; ++i) centre.update(Vec3(0, 0, 0.4f), 1.0f / 30.0f);
  EXPECT_EQ(centre.offset(), Vec3::Zero());

  ViewNavigator right(settings, camera);
  const Vec3 nearRight = camera.deproject(315.0f, 119.5f, 0.4f);  // 5 px from the border
  for (int i = 0; i < 30; ++i) right.update(nearRight, 1.0f / 30.0f);
  EXPECT_GT(right.offset().x(), 0.5f * settings.speed);  // ~1 s near the edge
  EXPECT_NEAR(right.offset().y(), 0.0f, 1e-6f);

  ViewNavigator top(settings, camera);
  for (int i = 0; i < 30; ++i) top.update(camera.deproject(159.5f, 2.0f, 0.4f), 1.0f / 30.0f);
  EXPECT_LT(top.offset().y(), 0.0f);

  settings.enabled = false;
  ViewNavigator off(settings, camera);
  off.update(nearRight, 1.0f);
  EXPECT_EQ(off.offset(), Vec3::Zero());
}

TEST(Navigation, PlaygroundAppliesTheOffsetToTheHand) {
  const auto pg = build(loadExample("wall"));
  ASSERT_NE(pg, nullptr);
  Intrinsics camera{320, 240, 224.0f, 224.0f, 159.5f, 119.5f};
  pg->setCameraIntrinsics(camera);
  model::ModelPose rest = restHandInCamera();
  const Vec3 shift = camera.deproject(316.0f, 119.5f, rest.bodies[1].p.z()) -
                     Vec3(rest.bodies[1].p.x(), rest.bodies[1].p.y(), rest.bodies[1].p.z());
  for (Pose& p : rest.bodies) p.p.x() += shift.x();
  const Vec3 before = pg->trackingToScene().p;
  for (int i = 0; i < 15; ++i) pg->step(rest, 1.0f / 30.0f);
  // The workspace moves along the camera's x axis (as seen in the scene).
  const Vec3 cameraRight = pg->scene().camera.rotate(Vec3::UnitX());
  EXPECT_GT((pg->trackingToScene().p - before).dot(cameraRight), 0.05f);
}

TEST(PlayOutput, HeaderAndFrameLines) {
  const auto pg = build(loadExample("barbell"));
  ASSERT_NE(pg, nullptr);
  const std::string header = playHeaderJson(*pg);
  EXPECT_NE(header.find(R"("format": "dynahand-play", "version": 1, "scene": "barbell")"),
            std::string::npos)
      << header;
  EXPECT_NE(header.find(R"("barbell/cap1")"), std::string::npos);
  pg->step(std::nullopt, 1.0f / 30.0f);
  const std::string frame = playFrameJson(*pg, 0);
  EXPECT_EQ(frame.rfind(R"({"frame": 0, "time": 0.033333335, "offset": [0, 0, 0], "poses": [[)", 0),
            0u)
      << frame;
  std::size_t poses = 0;
  for (std::size_t at = frame.find("[", frame.find("poses")); at != std::string::npos;
       at = frame.find("[", at + 1))
    ++poses;
  EXPECT_EQ(poses, pg->bodies().size() + 1);  // the outer list plus one per body
}

}  // namespace
}  // namespace dynahand::playground
