// Fitting the hand to 21 keypoints.
#include <gtest/gtest.h>

#include <random>

#include "dynahand/model.h"
#include "dynahand/model_fit.h"
#include "dynahand/model_pose.h"
#include "model/model_test_util.h"

namespace dynahand::model {
namespace {

const ArticulatedModel& hand() {
  static const ArticulatedModel model = makeDefaultHand();
  return model;
}

float meanDistance(const std::array<Vec3, 21>& a, const std::array<Vec3, 21>& b) {
  float sum = 0.0f;
  for (size_t i = 0; i < 21; ++i) sum += (a[i] - b[i]).norm();
  return sum / 21.0f;
}

TEST(Fit, RecoversRandomValidPosesFromTheirOwnKeypoints) {
  std::mt19937 rng(42);
  KeypointFitter fitter(hand());
  float worst = 0.0f;
  for (int trial = 0; trial < 25; ++trial) {
    const JointAngles truth = fixtures::randomValidAngles(hand(), rng);
    const auto targets = keypoints21(hand(), forwardKinematics(hand(), truth));
    const Result<FitResult> fit = fitter.fit21(targets);
    ASSERT_TRUE(fit.ok()) << fit.message();
    EXPECT_TRUE(withinLimits(hand(), fit->angles));
    const float error =
        meanDistance(keypoints21(hand(), forwardKinematics(hand(), fit->angles)), targets);
    EXPECT_NEAR(error, fit->meanError, 1e-6f);
    EXPECT_LT(error, 0.001f) << "trial " << trial;
    worst = std::max(worst, error);
  }
  RecordProperty("worstMeanErrorMicrometres", static_cast<int>(worst * 1e6f));
}

TEST(Fit, RecoversTheScale) {
  std::mt19937 rng(8);
  const ArticulatedModel big = scaleModel(hand(), 1.12f);
  for (int trial = 0; trial < 5; ++trial) {
    const JointAngles truth = fixtures::randomValidAngles(big, rng);
    const auto targets = keypoints21(big, forwardKinematics(big, truth));
    FitOptions options;
    options.fitScale = true;
    const Result<FitResult> fit = fitToKeypoints(hand(), targets, options);
    ASSERT_TRUE(fit.ok()) << fit.message();
    EXPECT_NEAR(fit->scale, 1.12f, 0.005f);
    EXPECT_LT(fit->meanError, 0.001f);
    // The angles are for the scaled model.
    const ArticulatedModel fitted = scaleModel(hand(), fit->scale);
    EXPECT_LT(meanDistance(keypoints21(fitted, forwardKinematics(fitted, fit->angles)), targets),
              0.001f);
  }
}

TEST(Fit, NoisyKeypointsGiveAPlausiblePose) {
  std::mt19937 rng(9);
  std::normal_distribution<float> noise(0.0f, 0.003f);
  const JointAngles truth = fixtures::randomValidAngles(hand(), rng);
  const auto clean = keypoints21(hand(), forwardKinematics(hand(), truth));
  auto noisy = clean;
  for (Vec3& p : noisy) p += Vec3(noise(rng), noise(rng), noise(rng));
  const Result<FitResult> fit = fitToKeypoints(hand(), noisy);
  ASSERT_TRUE(fit.ok()) << fit.message();
  EXPECT_TRUE(withinLimits(hand(), fit->angles));
  EXPECT_LT(fit->meanError, 0.006f);
  EXPECT_LT(meanDistance(keypoints21(hand(), forwardKinematics(hand(), fit->angles)), clean),
            0.006f);
}

TEST(Fit, StartsFromAGivenPose) {
  std::mt19937 rng(10);
  const JointAngles truth = fixtures::randomValidAngles(hand(), rng);
  JointAngles start = truth;
  for (Vec3& a : start.angles) a *= 0.8f;
  start.root.p += Vec3(0.01f, 0, 0);
  FitOptions options;
  options.initial = &start;
  const Result<FitResult> fit =
      fitToKeypoints(hand(), keypoints21(hand(), forwardKinematics(hand(), truth)), options);
  ASSERT_TRUE(fit.ok()) << fit.message();
  EXPECT_LT(fit->meanError, 0.001f);
}

// A target far off, weighted low, leaves the others where they belong; weighted alike, it drags
// the finger (and the hand) toward it.
TEST(Fit, WeightsDiscountAnUnsureTarget) {
  std::mt19937 rng(11);
  const JointAngles truth = fixtures::randomValidAngles(hand(), rng);
  const auto clean = keypoints21(hand(), forwardKinematics(hand(), truth));
  constexpr std::size_t kOff = 8;  // the index tip, 4 cm off
  auto targets = clean;
  targets[kOff] += Vec3(0.04f, 0.0f, 0.0f);
  std::array<float, 21> weights;
  weights.fill(1.0f);
  weights[kOff] = 1e-4f;
  // Mean distance of the other 20 fitted keypoints from their true places.
  const auto othersError = [&](const FitOptions& options) {
    const Result<FitResult> fit = fitToKeypoints(hand(), targets, options);
    EXPECT_TRUE(fit.ok()) << fit.message();
    if (!fit) return 1.0f;
    const auto fitted = keypoints21(hand(), forwardKinematics(hand(), fit->angles));
    float sum = 0.0f;
    for (std::size_t i = 0; i < 21; ++i)
      if (i != kOff) sum += (fitted[i] - clean[i]).norm();
    return sum / 20.0f;
  };
  FitOptions weighted;
  weighted.weights = weights;
  const float alike = othersError(FitOptions{});
  const float discounted = othersError(weighted);
  EXPECT_GT(alike, 0.001f);
  EXPECT_LT(discounted, 0.25f * alike);
}

TEST(FitErrors, WeightsMustMatchTheTargets) {
  const std::array<Vec3, 21> targets =
      keypoints21(hand(), forwardKinematics(hand(), zeroAngles(hand())));
  std::array<float, 20> tooFew;
  tooFew.fill(1.0f);
  FitOptions options;
  options.weights = tooFew;
  Result<FitResult> fit = fitToKeypoints(hand(), targets, options);
  ASSERT_FALSE(fit.ok());
  EXPECT_EQ(fit.message(), "fitToKeypoints: 20 weights for 21 targets");
  std::array<float, 21> negative;
  negative.fill(1.0f);
  negative[3] = -0.5f;
  options.weights = negative;
  fit = fitToKeypoints(hand(), targets, options);
  ASSERT_FALSE(fit.ok());
  EXPECT_EQ(fit.message(), "fitToKeypoints: weight 3 is negative or not finite");
}

TEST(FitErrors, NonFiniteTarget) {
  std::array<Vec3, 21> targets = keypoints21(hand(), forwardKinematics(hand(), zeroAngles(hand())));
  targets[7].y() = std::numeric_limits<float>::quiet_NaN();
  const Result<FitResult> fit = fitToKeypoints(hand(), targets);
  ASSERT_FALSE(fit.ok());
  EXPECT_EQ(fit.message(), "fitToKeypoints: target 7 is not finite");
}

TEST(FitErrors, ModelWithoutHandKeypoints) {
  ModelSpec spec;
  spec.bodies.push_back({"box",
                         {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)},
                         std::nullopt,
                         std::nullopt});
  const ArticulatedModel box = buildModel(spec).value();
  const Result<FitResult> fit = fitToKeypoints(box, std::array<Vec3, 21>{});
  ASSERT_FALSE(fit.ok());
  EXPECT_NE(fit.message().find("21 hand keypoints"), std::string::npos);
}

}  // namespace
}  // namespace dynahand::model
