// Acquisition on real frames (Intel RealSense SR305, ../shared/data/sr305-hands): every
// frame a fresh acquisition (the frames are 20 source frames apart), automatic start, no
// camera-specific setting. Open palm, fingers spread: the fitted model must explain the hand's
// samples and lie on the hand. Measured per frame (docs/tracker.md, real data).
#include <gtest/gtest.h>

#include <cstdio>

#include "dynahand/model.h"
#include "dynahand/sequence.h"
#include "dynahand/tracker.h"
#include "test_support.h"

namespace dynahand::track {
namespace {

TEST(RealData, OpenPalmFramesAreAcquiredAndTheModelLiesOnTheHand) {
  DYNAHAND_REQUIRE_SHARED_DATA(shared);
  const auto dir = shared / "sr305-hands" / "20210326-230536";
  auto reader = SequenceReader::open(dir);
  ASSERT_TRUE(reader.ok()) << reader.message();
  TrackerSettings settings;
  settings.perFrame = true;
  auto tracker = Tracker::create(model::makeDefaultHand(), reader->info().intrinsics, settings);
  ASSERT_TRUE(tracker.ok()) << tracker.message();
  int acquired = 0;
  int framesWithATipOff = 0;
  float nearSum = 0.0f;
  // Frame 7: the forearm points at the camera from the top border and is nearer than the hand;
  // segmentation moves to the limb's free end (docs/cloud.md), so it is acquired like the rest.
  for (int i = 0; i < reader->frameCount(); ++i) {
    auto frame = reader->frame(i);
    ASSERT_TRUE(frame.ok()) << frame.message();
    const HandResult& h = (*tracker)->track(*frame).hands.at(0);
    std::printf(
        "frame %d: tracked %d, samples within 10 mm %.3f, model on hand %.3f, "
        "fingertips off hand %d\n",
        i, h.tracked, static_cast<double>(h.quality.dataNearModel),
        static_cast<double>(h.quality.modelOnHand), h.quality.fingertipsOffHand);
    EXPECT_TRUE(h.tracked) << "frame " << i;
    if (!h.tracked) continue;
    ++acquired;
    nearSum += h.quality.dataNearModel;
    EXPECT_GE(h.quality.dataNearModel, 0.85f) << "frame " << i;
    EXPECT_GE(h.quality.modelOnHand, 0.80f) << "frame " << i;
    EXPECT_LE(h.quality.fingertipsOffHand, 1) << "frame " << i << ": fingertips over background";
    framesWithATipOff += h.quality.fingertipsOffHand > 0 ? 1 : 0;
  }
  ASSERT_GT(acquired, 0);
  // With the shipped detector one frame (6) has a fingertip just past the mask's edge, the rest
  // of the model on the hand (model on hand 0.96-1.00 per frame); one such frame is allowed.
  EXPECT_LE(framesWithATipOff, 1);
  EXPECT_GE(nearSum / static_cast<float>(acquired), 0.85f);
}

}  // namespace
}  // namespace dynahand::track
