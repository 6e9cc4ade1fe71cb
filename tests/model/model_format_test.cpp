// Model files: round trips and one test per kind of malformed input.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include <nlohmann/json.hpp>

#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "test_support.h"

namespace dynahand::model {
namespace {

using nlohmann::json;

std::filesystem::path armPath() {
  return std::filesystem::path(DYNAHAND_SOURCE_DIR) / "tests/model/data/three_link_arm.json";
}

std::string readText(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

json armJson() {
  return json::parse(readText(armPath()));
}

// Parses a (possibly broken) document and returns the error message, or "" when it loaded.
std::string loadError(const json& doc) {
  const Result<ArticulatedModel> model = parseModel(doc.dump(), "test.json");
  return model.ok() ? std::string() : model.message();
}

TEST(ModelFormat, DefaultHandFileRoundTripIsByteIdentical) {
  const ArticulatedModel hand = makeDefaultHand();
  const std::filesystem::path dir = test::scratchDir("model_format_roundtrip");
  ASSERT_TRUE(saveModel(hand, dir / "hand.json").ok());
  const Result<ArticulatedModel> loaded = loadModel(dir / "hand.json");
  ASSERT_TRUE(loaded.ok()) << loaded.message();
  ASSERT_TRUE(saveModel(*loaded, dir / "hand2.json").ok());
  EXPECT_EQ(readText(dir / "hand.json"), readText(dir / "hand2.json"));
  // And the loaded model is the same model.
  ASSERT_EQ(loaded->bodyCount(), hand.bodyCount());
  for (int b = 0; b < hand.bodyCount(); ++b) {
    EXPECT_EQ(loaded->bodies()[static_cast<size_t>(b)].mass,
              hand.bodies()[static_cast<size_t>(b)].mass);
    EXPECT_EQ(loaded->bodies()[static_cast<size_t>(b)].vertices,
              hand.bodies()[static_cast<size_t>(b)].vertices);
  }
  for (int j = 0; j < hand.jointCount(); ++j) {
    const Joint& a = hand.joints()[static_cast<size_t>(j)];
    const Joint& b = loaded->joints()[static_cast<size_t>(j)];
    EXPECT_TRUE(a.frame.coeffs() == b.frame.coeffs());
    EXPECT_LT((a.minAngle - b.minAngle).norm(), 1e-5f);  // limits are stored in degrees to 1e-4
    EXPECT_LT((a.maxAngle - b.maxAngle).norm(), 1e-5f);
  }
}

TEST(ModelFormat, HandWrittenArmLoadsAndIsCanonicalAfterOneRoundTrip) {
  const Result<ArticulatedModel> arm = loadModel(armPath());
  ASSERT_TRUE(arm.ok()) << arm.message();
  EXPECT_EQ(arm->bodyCount(), 4);
  EXPECT_EQ(arm->jointCount(), 3);
  EXPECT_EQ(arm->metadata().handedness, Handedness::None);
  EXPECT_FALSE(arm->hasKeypoints21());
  // mass given, density given (2000 kg/m^3 x 0.2 x 0.2 x 0.05 m^3 = 4 kg).
  EXPECT_FLOAT_EQ(arm->bodies()[1].mass, 2.0f);
  EXPECT_NEAR(arm->bodies()[0].mass, 4.0f, 1e-4f);
  EXPECT_FALSE(arm->collides(0, 1));  // joint neighbours
  EXPECT_FALSE(arm->collides(0, 2));  // ignored pair
  EXPECT_TRUE(arm->collides(0, 3));
  EXPECT_NEAR(arm->joints()[1].maxAngle.x(), 150.0f * std::numbers::pi_v<float> / 180.0f, 1e-6f);
  const std::string once = modelToJson(*arm);
  const Result<ArticulatedModel> again = parseModel(once, "once.json");
  ASSERT_TRUE(again.ok()) << again.message();
  EXPECT_EQ(modelToJson(*again), once);
}

TEST(ModelFormat, ArmForwardKinematicsMatchesClosedForm) {
  const Result<ArticulatedModel> arm = loadModel(armPath());
  ASSERT_TRUE(arm.ok()) << arm.message();
  JointAngles angles = zeroAngles(*arm);
  const float a1 = 0.4f, a2 = 0.9f, a3 = -0.3f;
  angles.angles = {Vec3(a1, 0, 0), Vec3(a2, 0, 0), Vec3(a3, 0, 0)};
  const ModelPose pose = forwardKinematics(*arm, angles);
  const Vec3 tip = pose.bodies[3].transform(Vec3(0, 0, 0.15f));
  // Planar chain in the y-z plane; flexion about +x turns +z toward -y.
  const float z =
      0.02f + 0.3f * std::cos(a1) + 0.25f * std::cos(a1 + a2) + 0.15f * std::cos(a1 + a2 + a3);
  const float y =
      -(0.3f * std::sin(a1) + 0.25f * std::sin(a1 + a2) + 0.15f * std::sin(a1 + a2 + a3));
  EXPECT_NEAR(tip.x(), 0.0f, 1e-6f);
  EXPECT_NEAR(tip.y(), y, 1e-5f);
  EXPECT_NEAR(tip.z(), z, 1e-5f);
}

TEST(ModelFormatErrors, MissingFile) {
  const Result<ArticulatedModel> m = loadModel("/nonexistent/model.json");
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.message().find("/nonexistent/model.json: cannot open"), std::string::npos)
      << m.message();
}

TEST(ModelFormatErrors, TruncatedFile) {
  const std::string text = readText(armPath());
  const Result<ArticulatedModel> m = parseModel(text.substr(0, text.size() / 2), "cut.json");
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.message().find("cut.json: not valid JSON"), std::string::npos) << m.message();
}

TEST(ModelFormatErrors, NaNLiteralIsInvalidJson) {
  std::string text = readText(armPath());
  text.replace(text.find("-0.1, -0.1, -0.05"), 4, "NaN");
  const Result<ArticulatedModel> m = parseModel(text, "nan.json");
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.message().find("nan.json: not valid JSON"), std::string::npos) << m.message();
}

TEST(ModelFormatErrors, OverflowingNumberIsRejected) {
  std::string text = readText(armPath());
  text.replace(text.find("-0.1, -0.1, -0.05"), 4, "1e999");
  const Result<ArticulatedModel> m = parseModel(text, "inf.json");
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.message().find("inf.json: not valid JSON"), std::string::npos) << m.message();
  EXPECT_NE(m.message().find("number overflow"), std::string::npos) << m.message();
}

TEST(ModelFormatErrors, MissingBodyName) {
  json doc = armJson();
  doc["bodies"][1].erase("name");
  EXPECT_EQ(loadError(doc), "test.json: bodies[1].name: missing");
}

TEST(ModelFormatErrors, MissingVertices) {
  json doc = armJson();
  doc["bodies"][2].erase("vertices");
  EXPECT_EQ(loadError(doc), "test.json: bodies[2].vertices: missing");
}

TEST(ModelFormatErrors, MissingJointLimits) {
  json doc = armJson();
  doc["joints"][0].erase("maxDeg");
  EXPECT_EQ(loadError(doc), "test.json: joints[0].maxDeg: missing");
}

TEST(ModelFormatErrors, MissingFormatAndWrongVersion) {
  json doc = armJson();
  doc.erase("format");
  EXPECT_EQ(loadError(doc), "test.json: format: missing");
  doc = armJson();
  doc["version"] = 2;
  EXPECT_NE(loadError(doc).find("version: 2 is not supported"), std::string::npos);
}

TEST(ModelFormatErrors, UnknownField) {
  json doc = armJson();
  doc["bodies"][0]["mas"] = 1.0;
  EXPECT_EQ(loadError(doc), "test.json: bodies[0].mas: unknown field");
}

TEST(ModelFormatErrors, VertexNotATriple) {
  json doc = armJson();
  doc["bodies"][3]["vertices"][1] = json::array({0.0, 1.0});
  EXPECT_EQ(loadError(doc), "test.json: bodies[3].vertices[1]: expected [x, y, z]");
}

TEST(ModelFormatErrors, FewerThanFourVertices) {
  json doc = armJson();
  doc["bodies"][3]["vertices"] =
      json::array({json::array({0, 0, 0}), json::array({1, 0, 0}), json::array({0, 1, 0})});
  const std::string error = loadError(doc);
  EXPECT_EQ(error.rfind("test.json: bodies[3].vertices: fewer than 4 non-coplanar points (", 0), 0u)
      << error;
}

TEST(ModelFormatErrors, CoplanarVertices) {
  json doc = armJson();
  doc["bodies"][5 - 2]["vertices"] =
      json::array({json::array({0, 0, 0}), json::array({0.1, 0, 0}), json::array({0, 0.1, 0}),
                   json::array({0.1, 0.1, 0})});
  const std::string error = loadError(doc);
  EXPECT_EQ(error.rfind("test.json: bodies[3].vertices: fewer than 4 non-coplanar points (", 0), 0u)
      << error;
}

TEST(ModelFormatErrors, NonConvexPointSetIsHulled) {
  // Points inside the hull are allowed (the body is their hull); only degenerate sets fail.
  json doc = armJson();
  doc["bodies"][3]["vertices"].push_back(json::array({0, 0, 0.01}));
  EXPECT_EQ(loadError(doc), "");
}

TEST(ModelFormatErrors, CycleInParentGraph) {
  json doc = armJson();
  // lower -> upper closes upper -> lower -> upper; base is left as a lone root.
  doc["joints"][0]["parent"] = "lower";
  const std::string error = loadError(doc);
  EXPECT_NE(error.find("test.json: joints: cycle in the parent graph"), std::string::npos) << error;
  EXPECT_NE(error.find("upper"), std::string::npos);
}

TEST(ModelFormatErrors, UnknownBodyInJoint) {
  json doc = armJson();
  doc["joints"][2]["child"] = "claw";
  EXPECT_EQ(loadError(doc), "test.json: joints[2].child: unknown body 'claw'");
}

TEST(ModelFormatErrors, UnknownBodyInKeypoint) {
  json doc = armJson();
  doc["keypoints"][1]["body"] = "elbow";
  EXPECT_EQ(loadError(doc), "test.json: keypoints[1].body: unknown body 'elbow'");
}

TEST(ModelFormatErrors, UnknownBodyInCollisionPair) {
  json doc = armJson();
  doc["collision"]["ignorePairs"][0][1] = "floor";
  EXPECT_EQ(loadError(doc), "test.json: collision.ignorePairs[0][1]: unknown body 'floor'");
}

TEST(ModelFormatErrors, DuplicateBodyName) {
  json doc = armJson();
  doc["bodies"][2]["name"] = "upper";
  EXPECT_EQ(loadError(doc), "test.json: bodies[2].name: duplicate name 'upper' (also bodies[1])");
}

TEST(ModelFormatErrors, TwoRoots) {
  json doc = armJson();
  doc["joints"].erase(2);
  const std::string error = loadError(doc);
  EXPECT_NE(error.find("2 bodies have no parent joint ('base', 'hand')"), std::string::npos)
      << error;
}

TEST(ModelFormatErrors, BodyWithTwoParents) {
  json doc = armJson();
  doc["joints"][2]["parent"] = "base";
  doc["joints"][2]["child"] = "lower";
  EXPECT_EQ(loadError(doc),
            "test.json: joints[2].child: body 'lower' is already the child of joints[1]");
}

TEST(ModelFormatErrors, MinAngleAboveMax) {
  json doc = armJson();
  doc["joints"][1]["minDeg"][0] = 160;
  EXPECT_EQ(loadError(doc), "test.json: joints[1].minDeg[0]: greater than maxDeg");
}

TEST(ModelFormatErrors, AbductionLimitAtNinetyDegrees) {
  json doc = armJson();
  doc["joints"][0]["maxDeg"][1] = 90;
  EXPECT_EQ(loadError(doc),
            "test.json: joints[0].maxDeg[1]: abduction limits must lie inside (-90, 90) degrees");
}

TEST(ModelFormatErrors, FrameNotUnit) {
  json doc = armJson();
  doc["joints"][0]["frame"] = json::array({0, 0, 0, 0});
  EXPECT_EQ(loadError(doc), "test.json: joints[0].frame: not a unit quaternion [w, x, y, z]");
}

TEST(ModelFormatErrors, BadMass) {
  json doc = armJson();
  doc["bodies"][1]["mass"] = -1;
  EXPECT_EQ(loadError(doc), "test.json: bodies[1].mass: must be a positive number (kg)");
  doc["bodies"][1]["mass"] = 1;
  doc["bodies"][1]["density"] = 1000;
  EXPECT_EQ(loadError(doc), "test.json: bodies[1]: give mass or density, not both");
}

// Found by fuzz/fuzz_model_json.cpp: a density was only checked to be positive, so a large
// density on a large hull gave an infinite mass and a tiny one on a small hull a zero mass;
// the model loaded, but saved (with its mass) it no longer did.
TEST(ModelFormatErrors, DensityGivingNoFiniteMass) {
  const std::string cube = R"([[0,0,0],[S,0,0],[0,S,0],[0,0,S],[S,S,0],[S,0,S],[0,S,S],[S,S,S]])";
  auto body = [&](const std::string& density, const std::string& size) {
    std::string vertices = cube;
    for (std::size_t at = vertices.find('S'); at != std::string::npos; at = vertices.find('S'))
      vertices.replace(at, 1, size);
    return R"({"format": "dynahand-model", "version": 1,
               "metadata": {"name": "b", "handedness": "none", "units": "m"},
               "bodies": [{"name": "b", "density": )" +
           density + R"(, "vertices": )" + vertices + R"(}], "joints": []})";
  };
  for (const auto& [density, size] : {std::pair{"3e38", "10"}, std::pair{"1e-44", "0.001"}}) {
    const Result<ArticulatedModel> model = parseModel(body(density, size), "test.json");
    ASSERT_FALSE(model.ok()) << density;
    EXPECT_EQ(model.message().rfind("test.json: bodies[0].density: gives a mass of ", 0), 0u)
        << model.message();
  }
  EXPECT_TRUE(parseModel(body("1000", "0.01"), "test.json").ok());
}

// Found by fuzz/fuzz_model_json.cpp: a keypoint near the float limit gave a bone of infinite
// length, and the OpenXR joint frames built along it were NaN. Such a model now has no
// OpenXR joints (as one with a bone of no length), and its 21 keypoints still work.
TEST(ModelFormat, KeypointNearTheFloatLimitLeavesNoNaNOpenXrFrames) {
  json doc = json::parse(modelToJson(makeDefaultHand()));
  for (json& k : doc["keypoints"]) {
    if (k["name"] == "thumb_cmc") k["point"] = json::array({3e38, 3e38, 0});
  }
  const Result<ArticulatedModel> model = parseModel(doc.dump(), "test.json");
  ASSERT_TRUE(model.ok()) << model.message();
  EXPECT_TRUE(model->hasKeypoints21());
  EXPECT_FALSE(model->hasOpenXrJoints());
  EXPECT_TRUE(makeDefaultHand().hasOpenXrJoints());
}

TEST(ModelFormatErrors, WrongTypes) {
  json doc = armJson();
  doc["bodies"] = json::object();
  EXPECT_EQ(loadError(doc), "test.json: bodies: expected an array");
  doc = armJson();
  doc["bodies"][0]["name"] = 3;
  EXPECT_EQ(loadError(doc), "test.json: bodies[0].name: expected a string");
  doc = armJson();
  doc["metadata"]["units"] = "mm";
  EXPECT_EQ(loadError(doc), "test.json: metadata.units: 'mm' is not supported (only \"m\")");
}

}  // namespace
}  // namespace dynahand::model
