// The detector's crop: its coordinates round-trip, mirroring, a rendered hand's crop, and the
// synthetic training data.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>

#include "dynahand/detector.h"
#include "dynahand/detector_data.h"
#include "dynahand/synth.h"
#include "synth_support.h"

namespace dynahand::detect {
namespace {

TEST(CropFrame, CropCoordinatesRoundTrip) {
  Intrinsics k{320, 240, 220.0f, 221.0f, 160.5f, 119.5f};
  for (const bool mirrored : {false, true}) {
    CropFrame f{150.0f, 100.0f, 44.0f, 0.5f, mirrored};
    for (const Vec3& p : {Vec3(0.01f, -0.02f, 0.5f), Vec3(-0.05f, 0.04f, 0.58f)}) {
      const Vec3 uvd = f.toCrop(k, p);
      EXPECT_LT((f.toCamera(k, uvd) - p).norm(), 1e-5f);
    }
  }
  // Mirroring flips u only.
  CropFrame plain{150.0f, 100.0f, 44.0f, 0.5f, false};
  CropFrame mirrored = plain;
  mirrored.mirrored = true;
  const Vec3 p(0.03f, 0.01f, 0.52f);
  const Vec3 a = plain.toCrop(k, p), b = mirrored.toCrop(k, p);
  EXPECT_FLOAT_EQ(a.x(), -b.x());
  EXPECT_FLOAT_EQ(a.y(), b.y());
  EXPECT_FLOAT_EQ(a.z(), b.z());
}

TEST(HandCrop, RenderedHandFillsTheCropAroundItsKeypoints) {
  auto seq = synth::SyntheticSequence::create(test::clipOptions("wave", "tof", 5));
  ASSERT_TRUE(seq);
  const synth::SyntheticFrame& frame = seq->frame(2);
  CloudPipeline pipeline(seq->intrinsics());
  CloudFrame cloud;
  ASSERT_TRUE(pipeline.process(frame.depth, cloud));
  ASSERT_TRUE(cloud.segment.found);
  for (const bool mirrored : {false, true}) {
    HandCrop crop;
    ASSERT_TRUE(makeCrop(cloud, mirrored, crop));
    ASSERT_EQ(crop.pixels.size(), static_cast<std::size_t>(kCropPixels * kCropPixels));
    int hand = 0;
    for (const float v : crop.pixels) {
      EXPECT_GE(v, -1.0f);
      EXPECT_LE(v, 1.0f);
      hand += v < 1.0f ? 1 : 0;
    }
    EXPECT_GT(hand, kCropPixels * kCropPixels / 10);
    // Every keypoint of the hand lies in the crop, and a visible fingertip's crop pixel holds
    // hand depth near its own.
    for (const Vec3& p : frame.hands[0].keypoints) {
      const Vec3 uvd = crop.frame.toCrop(seq->intrinsics(), p);
      EXPECT_LT(std::abs(uvd.x()), 1.0f);
      EXPECT_LT(std::abs(uvd.y()), 1.0f);
      EXPECT_LT(std::abs(uvd.z()), 1.0f);
    }
    const Vec3 tip = crop.frame.toCrop(seq->intrinsics(), frame.hands[0].keypoints[12]);
    const int col = static_cast<int>((tip.x() + 1.0f) * 0.5f * kCropPixels);
    const int row = static_cast<int>((tip.y() + 1.0f) * 0.5f * kCropPixels);
    bool near = false;
    for (int dr = -2; dr <= 2; ++dr)
      for (int dc = -2; dc <= 2; ++dc) {
        const int r = std::clamp(row + dr, 0, kCropPixels - 1);
        const int c = std::clamp(col + dc, 0, kCropPixels - 1);
        near = near || std::abs(crop.pixels[static_cast<std::size_t>(r * kCropPixels + c)] -
                                tip.z()) < 0.15f;
      }
    EXPECT_TRUE(near) << "mirrored " << mirrored;
  }
}

// Two touching hands are one segment; given the two hands' centres, a hand's crop keeps its
// own pixels as they were and leaves out those whose point lies nearer the other hand.
TEST(HandCrop, TheOtherHandOfTwoIsLeftOut) {
  auto seq = synth::SyntheticSequence::create(test::clipOptions("hands-touching", "tof", 1));
  ASSERT_TRUE(seq);
  const synth::SyntheticFrame& frame = seq->frame(0);
  ASSERT_EQ(frame.hands.size(), 2u);
  CloudPipeline pipeline(seq->intrinsics());
  CloudFrame cloud;
  ASSERT_TRUE(pipeline.process(frame.depth, cloud));
  const auto centreOf = [](const synth::HandKeypoints& k) {
    Vec3 sum = Vec3::Zero();
    for (const Vec3& p : k) sum += p;
    return Vec3(sum / static_cast<float>(k.size()));
  };
  const Vec3 right = centreOf(frame.hands[0].keypoints), left = centreOf(frame.hands[1].keypoints);
  const Vec3 centre = keypointBoxCentre(frame.hands[0].keypoints);
  const CropHandSplit split{right, left};
  HandCrop whole, own;
  ASSERT_TRUE(makeCrop(cloud, false, whole, &centre));
  ASSERT_TRUE(makeCrop(cloud, false, own, &centre, &split));
  const Intrinsics& k = seq->intrinsics();
  int otherHand = 0, kept = 0;
  for (std::size_t i = 0; i < whole.pixels.size(); ++i) {
    if (whole.pixels[i] >= 1.0f) {
      EXPECT_EQ(own.pixels[i], 1.0f);
      continue;
    }
    const int row = static_cast<int>(i) / kCropPixels, col = static_cast<int>(i) % kCropPixels;
    const Vec3 uvd((static_cast<float>(col) + 0.5f) * 2.0f / kCropPixels - 1.0f,
                   (static_cast<float>(row) + 0.5f) * 2.0f / kCropPixels - 1.0f, whole.pixels[i]);
    const Vec3 p = whole.frame.toCamera(k, uvd);
    // Pixels on the boundary between the two hands may go either way (pixel centres round).
    const float margin = (p - right).norm() - (p - left).norm();
    if (margin > 0.005f) {
      ++otherHand;
      EXPECT_EQ(own.pixels[i], 1.0f) << "the other hand's pixel " << i << " is kept";
    } else if (margin < -0.005f) {
      ++kept;
      EXPECT_EQ(own.pixels[i], whole.pixels[i]) << "an own pixel changed";
    }
  }
  std::printf("crop pixels of the right hand %d, of the touching left hand %d\n", kept, otherHand);
  EXPECT_GT(otherHand, 100) << "the other hand lies in the crop";
  EXPECT_GT(kept, kCropPixels * kCropPixels / 10);
}

TEST(DetectorData, SamplesAreDeterministicAndLabelledInsideTheCrop) {
  DataOptions o;
  o.seed = 5;
  for (const DataSplit split : {DataSplit::Train, DataSplit::HeldBack}) {
    o.split = split;
    for (int i = 0; i < 6; ++i) {
      const DataSample a = makeSample(o, i);
      const DataSample b = makeSample(o, i);
      EXPECT_EQ(a.pixels, b.pixels);
      for (std::size_t j = 0; j < a.uvd.size(); ++j) {
        EXPECT_EQ(a.uvd[j], b.uvd[j]);
        EXPECT_LE(a.uvd[j].head<2>().cwiseAbs().maxCoeff(), 1.3f);
      }
      if (split == DataSplit::HeldBack) {
        EXPECT_NE(a.source, 0);  // clip poses only
      }
    }
  }
}

// A head-mounted camera sees the forearm come toward it in nine frames of ten of animbank.pose
// (the wrist-to-knuckle line at least 0.3 in cosine toward the camera); uniform rotations put
// 23 % of the samples there, the generator nearly half.
// Share of the samples whose wrist-to-knuckle line comes toward the camera (the forearm
// behind the hand, as a head-mounted camera sees it).
double shareSeenAsFromTheHead(const DataOptions& o, int samples) {
  int toward = 0;
  for (int i = 0; i < samples; ++i) {
    const DataSample s = makeSample(o, i);
    const Vec3 forearm = (s.keypoints[0] - s.keypoints[9]).normalized();  // wrist side
    const Vec3 palm = 0.5f * (s.keypoints[0] + s.keypoints[9]);
    if (forearm.dot(-palm.normalized()) >= 0.3f) ++toward;
  }
  return static_cast<double>(toward) / samples;
}

TEST(DetectorData, NearlyHalfTheSamplesSeeTheForearmComeTowardTheCamera) {
  DataOptions o;
  o.seed = 11;
  const double share = shareSeenAsFromTheHead(o, 160);
  std::printf("forearm toward the camera in %.0f %% of the samples\n", 100.0 * share);
  EXPECT_GT(share, 0.35);
  EXPECT_LT(share, 0.65);
}

// headViewShare sets that share: none drawn as head-mounted leaves the uniform rotations' share
// (about a quarter); all drawn so gives two thirds (segmentation redraws and wrist flex take
// the rest out of that view).
TEST(DetectorData, HeadViewShareSetsHowManySamplesSeeTheForearmComeToward) {
  DataOptions none;
  none.seed = 11;
  none.headViewShare = 0.0f;
  DataOptions all = none;
  all.headViewShare = 1.0f;
  const double uniform = shareSeenAsFromTheHead(none, 120);
  const double head = shareSeenAsFromTheHead(all, 120);
  std::printf("forearm toward the camera: %.0f %% (share 0), %.0f %% (share 1)\n", 100.0 * uniform,
              100.0 * head);
  EXPECT_LT(uniform, 0.35);
  EXPECT_GT(head, 0.6);
}

// The held-object settings reach the generator: with share 0 the box setting changes no byte
// (it acts only where an object is drawn); share 1 and the box setting each change the samples
// (an object drawn, or a box drawn instead of a ball or cylinder, also moves the random draws
// that follow it, so this checks that the settings act, not what the object looks like).
TEST(DetectorData, HeldObjectsFollowTheirShareAndBoxesOnlyWhenAsked) {
  DataOptions none;
  none.seed = 9;
  none.heldObjectShare = 0.0f;
  DataOptions noneBoxes = none;
  noneBoxes.heldObjectBoxes = true;
  DataOptions all = none;
  all.heldObjectShare = 1.0f;
  DataOptions allBoxes = all;
  allBoxes.heldObjectBoxes = true;
  constexpr int kSamples = 12;
  int changedByObject = 0, changedByBoxes = 0;
  for (int i = 0; i < kSamples; ++i) {
    const DataSample a = makeSample(none, i);
    EXPECT_EQ(a.pixels, makeSample(noneBoxes, i).pixels) << "sample " << i;
    const DataSample b = makeSample(all, i);
    const DataSample c = makeSample(allBoxes, i);
    changedByObject += a.pixels != b.pixels ? 1 : 0;
    changedByBoxes += b.pixels != c.pixels ? 1 : 0;
  }
  EXPECT_GE(changedByObject, kSamples - 1);
  EXPECT_GE(changedByBoxes, 1);
}

// How far a finger (digit 1..4) is curled, from its keypoints: 1 - (knuckle to tip) / (the
// sum of its three bones), 0 straight.
float fingerCurl(const std::array<Vec3, kKeypointCount>& k, int digit) {
  const std::size_t b = static_cast<std::size_t>(1 + 4 * digit);
  float bones = 0.0f;
  for (std::size_t i = 0; i < 3; ++i) bones += (k[b + i + 1] - k[b + i]).norm();
  return 1.0f - (k[b + 3] - k[b]).norm() / bones;
}

// Mean correlation between neighbouring fingers' curls over the random-pose samples of a set.
double neighbourCurlCorrelation(const DataOptions& options, int samples) {
  std::vector<std::array<double, 4>> curls;
  for (int i = 0; i < samples; ++i) {
    const DataSample s = makeSample(options, i);
    if (s.source != 0) continue;
    std::array<double, 4> c{};
    for (int d = 0; d < 4; ++d) c[static_cast<std::size_t>(d)] = fingerCurl(s.keypoints, d + 1);
    curls.push_back(c);
  }
  double sum = 0.0;
  for (std::size_t f = 0; f < 3; ++f) {
    double ma = 0.0, mb = 0.0;
    for (const auto& c : curls) ma += c[f], mb += c[f + 1];
    ma /= static_cast<double>(curls.size());
    mb /= static_cast<double>(curls.size());
    double ab = 0.0, aa = 0.0, bb = 0.0;
    for (const auto& c : curls) {
      ab += (c[f] - ma) * (c[f + 1] - mb);
      aa += (c[f] - ma) * (c[f] - ma);
      bb += (c[f + 1] - mb) * (c[f + 1] - mb);
    }
    sum += ab / std::sqrt(aa * bb);
  }
  return sum / 3.0;
}

// The shared-curl share sets how often a random pose's fingers curl together: at 1 every
// random pose is a grasp, neighbouring fingers' curls then correlate strongly; at 0 each
// finger curls on its own.
TEST(DetectorData, SharedCurlShareMakesFingersCurlTogether) {
  DataOptions apart;
  apart.seed = 11;
  apart.heldObjectShare = 0.0f;
  apart.sharedCurlShare = 0.0f;
  DataOptions together = apart;
  together.sharedCurlShare = 1.0f;
  constexpr int kSamples = 160;  // about half are random poses
  const double rApart = neighbourCurlCorrelation(apart, kSamples);
  const double rTogether = neighbourCurlCorrelation(together, kSamples);
  std::printf("neighbouring fingers' curl correlation: %.2f apart, %.2f together\n", rApart,
              rTogether);
  EXPECT_LT(rApart, 0.35);
  EXPECT_GT(rTogether, 0.7);
}

TEST(DetectorData, FileBytesDoNotDependOnThreads) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("dynahand-detector-data-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  DataOptions o;
  o.count = 70;
  o.seed = 3;
  ASSERT_TRUE(writeDataFile(o, dir / "one.bin"));
  o.threads = 2;
  ASSERT_TRUE(writeDataFile(o, dir / "two.bin"));
  const auto size = std::filesystem::file_size(dir / "one.bin");
  EXPECT_EQ(size, 20u + 70u * (kCropPixels * kCropPixels + 4u * (3u * kKeypointCount + 2u)));
  auto read = [](const std::filesystem::path& file) {
    std::string bytes(std::filesystem::file_size(file), '\0');
    std::ifstream in(file, std::ios::binary);
    in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return bytes;
  };
  EXPECT_EQ(read(dir / "one.bin"), read(dir / "two.bin"));
  EXPECT_FALSE(std::filesystem::exists(dir / "one.bin.partial"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace dynahand::detect
