// Hand proportions: random factors, the stretched skeleton, scaled radii and a synthetic
// sequence whose rendered hand and ground-truth keypoints follow them while the model's
// poses do not.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "dynahand/synth.h"
#include "synth_support.h"
#include "test_support.h"

namespace dynahand::synth {
namespace {

constexpr int kFingerBase[5] = {1, 5, 9, 13, 17};

HandKeypoints someHand() {
  const model::ArticulatedModel hand = model::makeDefaultHand();
  Result<std::vector<HandMotionSample>> s = sampleClip("count", hand, 1.3f);
  EXPECT_TRUE(s.ok());
  return model::keypoints21(hand, model::forwardKinematics(hand, (*s)[0].angles));
}

TEST(HandProportions, DefaultIsAllOnesAndChangesNothing) {
  const HandProportions p;
  EXPECT_TRUE(p.identity());
  for (const auto& finger : p.boneLength)
    for (float f : finger) EXPECT_EQ(f, 1.0f);
  for (float f : p.fingerThickness) EXPECT_EQ(f, 1.0f);
  EXPECT_EQ(p.palmThickness, 1.0f);
  const HandKeypoints before = someHand();
  HandKeypoints after = before;
  applyProportions(p, after);
  for (std::size_t i = 0; i < 21; ++i) EXPECT_EQ(after[i], before[i]);
  const SurfaceRadii radii;
  const SurfaceRadii same = scaledRadii(radii, p);
  EXPECT_EQ(same.finger, radii.finger);
  EXPECT_EQ(same.palmHalfThickness, radii.palmHalfThickness);
  EXPECT_TRUE(randomProportions(5, 0.0f).identity());
}

TEST(HandProportions, RandomFactorsAreDeterministicWithinTheSpread) {
  const HandProportions a = randomProportions(11, 0.15f), b = randomProportions(11, 0.15f);
  const HandProportions c = randomProportions(12, 0.15f);
  EXPECT_EQ(a.boneLength, b.boneLength);
  EXPECT_EQ(a.fingerThickness, b.fingerThickness);
  EXPECT_EQ(a.palmThickness, b.palmThickness);
  EXPECT_NE(a.boneLength, c.boneLength);
  float lo = 2.0f, hi = 0.0f;
  auto see = [&](float f) {
    lo = std::min(lo, f);
    hi = std::max(hi, f);
  };
  for (std::uint64_t seed = 0; seed < 50; ++seed) {
    const HandProportions p = randomProportions(seed, 0.15f);
    for (const auto& finger : p.boneLength)
      for (float f : finger) see(f);
    for (float f : p.fingerThickness) see(f);
    see(p.palmThickness);
  }
  EXPECT_GE(lo, 0.85f);
  EXPECT_LE(hi, 1.15f);
  EXPECT_LT(lo, 0.87f);  // the whole range is used
  EXPECT_GT(hi, 1.13f);
}

TEST(HandProportions, EachBoneStretchesAboutItsParentMovingTheChildrenAlong) {
  const HandKeypoints before = someHand();
  HandProportions p = randomProportions(3, 0.2f);
  HandKeypoints after = before;
  applyProportions(p, after);
  EXPECT_EQ(after[0], before[0]);  // wrist fixed
  for (int f = 0; f < 5; ++f) {
    int parent = 0;
    for (int b = 0; b < 4; ++b) {
      const int child = kFingerBase[f] + b;
      const Vec3 was =
          before[static_cast<std::size_t>(child)] - before[static_cast<std::size_t>(parent)];
      const Vec3 now =
          after[static_cast<std::size_t>(child)] - after[static_cast<std::size_t>(parent)];
      const float factor = p.boneLength[static_cast<std::size_t>(f)][static_cast<std::size_t>(b)];
      EXPECT_LT((now - factor * was).norm(), 1e-6f) << "finger " << f << " bone " << b;
      parent = child;
    }
  }
  // Only the index metacarpal longer: the whole index chain shifts by the same offset.
  HandProportions one;
  one.boneLength[1][0] = 1.2f;
  HandKeypoints shifted = before;
  applyProportions(one, shifted);
  const Vec3 offset = 0.2f * (before[5] - before[0]);
  for (std::size_t i = 5; i <= 8; ++i) EXPECT_LT((shifted[i] - before[i] - offset).norm(), 1e-6f);
  for (std::size_t i : {0u, 1u, 4u, 9u, 12u, 20u}) EXPECT_EQ(shifted[i], before[i]);
}

// model::makeDefaultHand given the proportions is the rendered hand's skeleton: in any pose its
// keypoints are the default hand's stretched by applyProportions (the benchmark's
// `--true-shape`), and the thickness factors widen the digits' keypoint radii.
TEST(HandProportions, TheModelShapedByThemHasTheStretchedSkeleton) {
  const model::ArticulatedModel plain = model::makeDefaultHand();
  const HandProportions p = randomProportions(3, 0.15f);
  const model::ArticulatedModel shaped = model::makeDefaultHand({}, model::Side::Right, p);
  ASSERT_EQ(shaped.bodies().size(), plain.bodies().size());
  for (const char* clip : {"count", "pinch", "wave"}) {
    Result<std::vector<HandMotionSample>> s = sampleClip(clip, plain, 0.7f);
    ASSERT_TRUE(s.ok());
    const model::JointAngles& angles = (*s)[0].angles;
    HandKeypoints expected = model::keypoints21(plain, model::forwardKinematics(plain, angles));
    applyProportions(p, expected);
    const HandKeypoints got = model::keypoints21(shaped, model::forwardKinematics(shaped, angles));
    for (std::size_t i = 0; i < 21; ++i)
      EXPECT_LT((got[i] - expected[i]).norm(), 1e-5f) << clip << " keypoint " << i;
  }
  // Thicker digits: each digit's keypoint radii scale with its factor; the default shape is the
  // default hand bit for bit.
  const auto& indices = plain.keypoints21Indices();
  for (int f = 0; f < 5; ++f) {
    const auto tip = static_cast<std::size_t>(indices[static_cast<std::size_t>(4 * f + 4)]);
    EXPECT_FLOAT_EQ(shaped.keypoints()[tip].radius,
                    plain.keypoints()[tip].radius * p.fingerThickness[static_cast<std::size_t>(f)]);
  }
  EXPECT_EQ(model::modelToJson(model::makeDefaultHand({}, model::Side::Right, HandProportions{})),
            model::modelToJson(plain));
}

TEST(HandProportions, ScaledRadiiMultiplyFingersAndPalm) {
  HandProportions p;
  p.fingerThickness = {1.1f, 0.9f, 1.0f, 1.2f, 0.8f};
  p.palmThickness = 1.3f;
  const SurfaceRadii radii;
  const SurfaceRadii s = scaledRadii(radii, p);
  for (std::size_t f = 0; f < 5; ++f)
    for (std::size_t j = 0; j < 4; ++j)
      EXPECT_FLOAT_EQ(s.finger[f][j], radii.finger[f][j] * p.fingerThickness[f]);
  EXPECT_FLOAT_EQ(s.palmHalfThickness, 1.3f * radii.palmHalfThickness);
  EXPECT_EQ(s.wrist, radii.wrist);
}

TEST(HandProportions, SequenceRendersAndReportsTheProportionedHand) {
  SynthOptions o;
  o.clip = "open-close";
  o.profile = "ideal";
  o.frameCount = 20;
  Result<SyntheticSequence> plain = SyntheticSequence::create(o);
  ASSERT_TRUE(plain.ok());
  SynthOptions longer = o;
  for (auto& finger : longer.proportions.boneLength) finger = {1.0f, 1.25f, 1.25f, 1.25f};
  longer.proportions.fingerThickness.fill(1.2f);
  Result<SyntheticSequence> shaped = SyntheticSequence::create(longer);
  ASSERT_TRUE(shaped.ok()) << shaped.message();
  for (int f : {0, 10}) {
    const HandTruth a = plain->truth(f, 0), b = shaped->truth(f, 0);
    // The model's poses are the same; the keypoints are the stretched skeleton.
    for (std::size_t i = 0; i < a.pose.bodies.size(); ++i) {
      EXPECT_EQ(a.pose.bodies[i].p, b.pose.bodies[i].p);
      EXPECT_EQ(a.pose.bodies[i].q.coeffs(), b.pose.bodies[i].q.coeffs());
    }
    HandKeypoints expected = a.keypoints;
    applyProportions(longer.proportions, expected);
    for (std::size_t i = 0; i < 21; ++i) EXPECT_EQ(b.keypoints[i], expected[i]);
    EXPECT_GT((b.keypoints[12] - a.keypoints[12]).norm(), 0.01f);
    // Rendered: more hand pixels, and every keypoint of the longer hand inside its mask.
    auto handPixels = [](SyntheticSequence& seq) {
      int n = 0;
      for (PixelLabel l : seq.labels()) n += l == PixelLabel::Hand0;
      return n;
    };
    const SyntheticFrame& frame = shaped->frame(f);
    EXPECT_EQ(test::keypointsOnHandPixels(*shaped, frame), 21) << "frame " << f;
    const int shapedPixels = handPixels(*shaped);
    plain->frame(f);
    EXPECT_GT(shapedPixels, handPixels(*plain) + 200) << "frame " << f;
  }
}

TEST(HandProportions, OutOfRangeFactorsAreRejectedAndWrittenToSynthJson) {
  SynthOptions o;
  o.frameCount = 2;
  o.proportions.boneLength[2][1] = 1.6f;
  const Result<SyntheticSequence> bad = SyntheticSequence::create(o);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("proportion"), std::string::npos) << bad.message();

  o.proportions = randomProportions(9, 0.15f);
  Result<SyntheticSequence> seq = SyntheticSequence::create(o);
  ASSERT_TRUE(seq.ok());
  const std::filesystem::path dir = test::scratchDir("synth_proportions") / "seq";
  ASSERT_TRUE(writeSequence(*seq, dir).ok());
  std::ifstream in(dir / "synth.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["version"], 4);
  EXPECT_EQ(j["scene"]["held_object"], "none");
  EXPECT_EQ(j["scene"]["view_shift_px"], nlohmann::json::array({0.0, 0.0}));
  ASSERT_TRUE(j.contains("proportions"));
  HandProportions read;
  for (std::size_t f = 0; f < 5; ++f) {
    for (std::size_t b = 0; b < 4; ++b)
      read.boneLength[f][b] = j["proportions"]["bone_length"][f][b].get<float>();
    read.fingerThickness[f] = j["proportions"]["finger_thickness"][f].get<float>();
  }
  read.palmThickness = j["proportions"]["palm_thickness"].get<float>();
  EXPECT_EQ(read.boneLength, o.proportions.boneLength);  // exact: regenerates bit for bit
  EXPECT_EQ(read.fingerThickness, o.proportions.fingerThickness);
  EXPECT_EQ(read.palmThickness, o.proportions.palmThickness);
}

}  // namespace
}  // namespace dynahand::synth
