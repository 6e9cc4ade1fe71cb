// The original authors' model and poses (../shared/data/intel): import, conversion, export.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>

#include "dynahand/model_intel.h"
#include "test_support.h"

namespace dynahand::model {
namespace {

// A unit cube as a quad mesh.
PolygonMesh cube() {
  PolygonMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.push_back(Vec3(i & 1 ? 1.f : -1.f, i & 2 ? 1.f : -1.f, i & 4 ? 1.f : -1.f));
  m.faces = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  return m;
}

TEST(CatmullClark, CubeCountsAndKnownPositions) {
  const PolygonMesh once = catmullClark(cube());
  EXPECT_EQ(once.vertices.size(), 8u + 6u + 12u);
  EXPECT_EQ(once.faces.size(), 24u);
  // Corner of a cube after one step: (F + 2R + (n-3)P)/n with n = 3: F = (2/3)P-ish...
  // for P = (1,1,1): F = (2/3, 2/3, 2/3), R = (2/3, 2/3, 2/3)... closed form 5/9.
  EXPECT_LT((once.vertices[7] - Vec3::Constant(5.0f / 9.0f)).norm(), 1e-6f);
  // Face point of the +z face and the edge point of the (+x,+y) vertical edge.
  bool foundFace = false;
  bool foundEdge = false;
  for (const Vec3& v : once.vertices) {
    foundFace = foundFace || (v - Vec3(0, 0, 1)).norm() < 1e-6f;
    foundEdge = foundEdge || (v - Vec3(0.75f, 0.75f, 0)).norm() < 1e-6f;
  }
  EXPECT_TRUE(foundFace);
  EXPECT_TRUE(foundEdge);
  const PolygonMesh twice = catmullClark(once);
  EXPECT_EQ(twice.faces.size(), 96u);
  for (const Vec3& v : twice.vertices)
    EXPECT_LE(v.cwiseAbs().maxCoeff(), 1.0f + 1e-6f);  // shrinks inside the cage
}

class IntelData : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const std::filesystem::path dir = test::sharedDataDir();
    if (dir.empty()) return;
    Result<IntelModel> imported = importIntelModel(dir / "intel/model_hand.json");
    ASSERT_TRUE(imported.ok()) << imported.message();
    intel_ = new IntelModel(std::move(imported).value());
  }
  static void TearDownTestSuite() {
    delete intel_;
    intel_ = nullptr;
  }
  static IntelModel* intel_;
};
IntelModel* IntelData::intel_ = nullptr;

TEST_F(IntelData, ModelImports) {
  DYNAHAND_REQUIRE_SHARED_DATA(dir);
  const ArticulatedModel& m = intel_->model;
  EXPECT_EQ(m.bodyCount(), 17);
  EXPECT_EQ(m.jointCount(), 16);
  EXPECT_EQ(m.bodies()[5].name, "index_proximal");
  EXPECT_TRUE(m.hasKeypoints21());
  EXPECT_TRUE(m.hasOpenXrJoints());
  // "Wrist joint to middle fingertip is about 0.185 m" (README of the data).
  EXPECT_NEAR(m.metadata().referenceLength, 0.185f, 0.01f);
  for (const Body& b : m.bodies()) EXPECT_GT(b.shape.volume(), 1e-6f) << b.name;
  // The imported model writes and reads back as a dynahand model file.
  const Result<ArticulatedModel> again = parseModel(modelToJson(m), "intel.json");
  ASSERT_TRUE(again.ok()) << again.message();
  EXPECT_EQ(modelToJson(*again), modelToJson(m));
}

TEST_F(IntelData, AnimbankKeypointsHaveConstantBoneLengths) {
  DYNAHAND_REQUIRE_SHARED_DATA(dir);
  const Result<std::vector<ModelPose>> poses =
      loadIntelPoses(dir / "intel/animbank.pose", intel_->model);
  ASSERT_TRUE(poses.ok()) << poses.message();
  ASSERT_EQ(poses->size(), 2336u);
  // Bones of the 21-keypoint skeleton: (parent, child) keypoint pairs across two bodies.
  std::vector<std::pair<int, int>> bones;
  for (int d = 0; d < 5; ++d) {
    bones.emplace_back(0, 1 + 4 * d);
    for (int k = 1; k < 4; ++k) bones.emplace_back(4 * d + k, 4 * d + k + 1);
  }
  std::vector<float> lo(bones.size(), 1e9f), hi(bones.size(), 0.0f);
  // Joint centres seen from parent and child: their tracker's joints are soft, so they
  // separate a little; a wrong centre-of-mass conversion would show centimetres.
  std::vector<float> meanDrift(intel_->model.joints().size(), 0.0f);
  for (const ModelPose& pose : *poses) {
    const auto kp = keypoints21(intel_->model, pose);
    for (size_t i = 0; i < bones.size(); ++i) {
      const float len =
          (kp[static_cast<size_t>(bones[i].first)] - kp[static_cast<size_t>(bones[i].second)])
              .norm();
      lo[i] = std::min(lo[i], len);
      hi[i] = std::max(hi[i], len);
    }
    for (size_t jj = 0; jj < meanDrift.size(); ++jj) {
      const Joint& j = intel_->model.joints()[jj];
      meanDrift[jj] += (pose.bodies[static_cast<size_t>(j.parent)].transform(j.anchorParent) -
                        pose.bodies[static_cast<size_t>(j.child)].transform(j.anchorChild))
                           .norm() /
                       static_cast<float>(poses->size());
    }
    // Anatomy in the palm frame: index radial (+x) of middle, ring, pinky; thumb base radial
    // of the pinky; knuckles distal (+z) of the wrist.
    const Pose& palm = pose.bodies[1];
    EXPECT_GT(palm.inverseTransform(kp[5]).x(), palm.inverseTransform(kp[9]).x());
    EXPECT_GT(palm.inverseTransform(kp[9]).x(), palm.inverseTransform(kp[13]).x());
    EXPECT_GT(palm.inverseTransform(kp[13]).x(), palm.inverseTransform(kp[17]).x());
    EXPECT_GT(palm.inverseTransform(kp[1]).x(), palm.inverseTransform(kp[17]).x());
    EXPECT_GT(palm.inverseTransform(kp[9]).z(), 0.05f);
  }
  for (size_t i = 0; i < bones.size(); ++i) {
    EXPECT_LT(hi[i] - lo[i], 0.001f) << "bone " << bones[i].first << "-" << bones[i].second;
    EXPECT_GT(lo[i], 0.005f);  // their thumb base sits 9 mm from the wrist centre
  }
  for (size_t j = 0; j < meanDrift.size(); ++j) EXPECT_LT(meanDrift[j], 0.002f) << "joint " << j;
}

TEST_F(IntelData, PoseFileExportRoundTrip) {
  DYNAHAND_REQUIRE_SHARED_DATA(dir);
  const Result<std::vector<ModelPose>> poses =
      loadIntelPoses(dir / "intel/hand_data_example.pose", intel_->model);
  ASSERT_TRUE(poses.ok()) << poses.message();
  ASSERT_EQ(poses->size(), 69u);
  const std::filesystem::path out = test::scratchDir("intel_pose") / "out.pose";
  ASSERT_TRUE(saveIntelPoses(out, intel_->model, *poses).ok());
  const Result<std::vector<ModelPose>> again = loadIntelPoses(out, intel_->model);
  ASSERT_TRUE(again.ok()) << again.message();
  ASSERT_EQ(again->size(), 69u);
  for (size_t f = 0; f < 69; ++f) {
    for (size_t b = 0; b < 17; ++b) {
      EXPECT_LT(((*again)[f].bodies[b].p - (*poses)[f].bodies[b].p).norm(), 1e-6f);
      EXPECT_LT((*again)[f].bodies[b].q.angularDistance((*poses)[f].bodies[b].q), 1e-5f);
    }
  }
}

TEST_F(IntelData, MalformedPoseLines) {
  DYNAHAND_REQUIRE_SHARED_DATA(dir);
  const std::filesystem::path scratch = test::scratchDir("intel_pose_errors");
  std::ofstream(scratch / "short.pose") << "0 0 0 0 0 0 1\n";
  const auto shortPoses = loadIntelPoses(scratch / "short.pose", intel_->model);
  ASSERT_FALSE(shortPoses.ok());
  EXPECT_NE(shortPoses.message().find("short.pose:1: 7 numbers, expected 119 (17 bodies x 7)"),
            std::string::npos)
      << shortPoses.message();
  std::ofstream(scratch / "text.pose") << "0 0 zero\n";
  const auto textPoses = loadIntelPoses(scratch / "text.pose", intel_->model);
  ASSERT_FALSE(textPoses.ok());
  EXPECT_NE(textPoses.message().find("text.pose:1: 'zero' is not a number"), std::string::npos)
      << textPoses.message();
  std::ofstream(scratch / "empty.pose") << "\n";
  EXPECT_FALSE(loadIntelPoses(scratch / "empty.pose", intel_->model).ok());
}

TEST(IntelImportErrors, MissingAndMalformedFiles) {
  EXPECT_FALSE(importIntelModel("/nonexistent/model_hand.json").ok());
  const std::filesystem::path scratch = test::scratchDir("intel_import_errors");
  std::ofstream(scratch / "bad.json")
      << R"({"controlcages": [{"verts": [[0,0,0]], "faces": [[0, 1, 2]]}], "joints": [], "pose": [[0,0,0,0,0,0,1]]})";
  const Result<IntelModel> bad = importIntelModel(scratch / "bad.json");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("controlcages[0].faces[0][1]: index 1 out of range [0, 1)"),
            std::string::npos)
      << bad.message();
}

}  // namespace
}  // namespace dynahand::model
