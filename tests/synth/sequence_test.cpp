// Synthetic sequences: clips within the joint limits, ground truth consistent with the
// rendered image and the model, reproducibility, scenes, pose-file playback, disk round trip.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>

#include "dynahand/sequence.h"
#include "dynahand/synth.h"
#include "synth_support.h"
#include "test_support.h"

namespace dynahand::synth {
namespace {

SynthOptions optionsFor(const std::string& clip, const std::string& profile = "ideal",
                        int frames = 60) {
  SynthOptions o;
  o.clip = clip;
  o.profile = profile;
  o.frameCount = frames;
  return o;
}

TEST(Clips, EveryClipStaysWithinTheJointLimits) {
  const model::ArticulatedModel hand = model::makeDefaultHand();
  ASSERT_GE(clips().size(), 11u);
  for (const ClipInfo& clip : clips()) {
    for (int i = 0; i <= 40; ++i) {
      const float t = clip.duration * static_cast<float>(i) / 40.0f;
      Result<std::vector<HandMotionSample>> samples = sampleClip(clip.name, hand, t);
      ASSERT_TRUE(samples.ok()) << samples.message();
      ASSERT_EQ(static_cast<int>(samples->size()), clip.handCount);
      for (const HandMotionSample& s : *samples)
        EXPECT_TRUE(model::withinLimits(hand, s.angles, 1e-4f)) << clip.name << " at t = " << t;
    }
  }
}

// Ground truth the tracker's model can reach: no two bones of the default hand that collide
// (not joined by a joint, not an ignored pair) overlap anywhere along any clip, at any hand
// size, beyond the few millimetres soft tissue gives. The deepest hull vertex of each bone
// inside each other bone is the measure.
TEST(Clips, BonesOfTheDefaultHandDoNotOverlap) {
  constexpr float kSoftTissueM = 0.0025f;
  for (const model::HandDimensions size :
       {model::HandDimensions{0.165f, 0.075f}, model::HandDimensions{0.19f, 0.085f},
        model::HandDimensions{0.215f, 0.095f}}) {
    const model::ArticulatedModel hand = model::makeDefaultHand(size);
    const int n = hand.bodyCount();
    for (const ClipInfo& clip : clips()) {
      float deepest = 0.0f;
      std::string where;
      for (int i = 0; i < 40; ++i) {
        const float t = clip.duration * static_cast<float>(i) / 40.0f;
        Result<std::vector<HandMotionSample>> samples = sampleClip(clip.name, hand, t);
        ASSERT_TRUE(samples.ok()) << samples.message();
        model::JointAngles angles = (*samples)[0].angles;
        angles.root = Pose::identity();
        const model::ModelPose pose = model::forwardKinematics(hand, angles);
        for (int a = 0; a < n; ++a) {
          for (int b = 0; b < n; ++b) {
            if (a == b || !hand.collides(a, b)) continue;
            const auto& ba = hand.bodies()[static_cast<std::size_t>(a)];
            const auto& bb = hand.bodies()[static_cast<std::size_t>(b)];
            const Pose& pa = pose.bodies[static_cast<std::size_t>(a)];
            const Pose& pb = pose.bodies[static_cast<std::size_t>(b)];
            const float apart =
                (pa.transform(ba.shape.centroid()) - pb.transform(bb.shape.centroid())).norm();
            // Bounding spheres apart: no vertex can be inside.
            if (apart > ba.shape.boundingRadius() + bb.shape.boundingRadius()) continue;
            for (const Vec3& v : ba.shape.vertices()) {
              const float depth = -bb.shape.signedDistance(pb.inverseTransform(pa.transform(v)));
              if (depth > deepest) {
                deepest = depth;
                where = ba.name + " in " + bb.name + " at t = " + std::to_string(t);
              }
            }
          }
        }
      }
      EXPECT_LE(deepest, kSoftTissueM) << clip.name << " (hand length " << size.length
                                       << "): " << 1000 * deepest << " mm, " << where;
    }
  }
}

// The clips are authored with abduction toward the thumb and flexion toward the palm: the
// "spread" clip must move the index fingertip radially and "open-close" curl the fingers
// toward the palm.
TEST(Clips, AuthoredAnglesMoveTheFingersTheIntendedWay) {
  const model::ArticulatedModel hand = model::makeDefaultHand();
  auto tips = [&](const std::string& clip, float t) {
    Result<std::vector<HandMotionSample>> s = sampleClip(clip, hand, t);
    model::JointAngles angles = (*s)[0].angles;
    angles.root = Pose::identity();  // forearm frame: x radial, y dorsal, z distal
    return model::keypoints21(hand, model::forwardKinematics(hand, angles));
  };
  const Keypoints21 together = tips("spread", 0.1f), spread = tips("spread", 1.1f);
  EXPECT_GT(spread[8].x() - together[8].x(), 0.01f);     // index toward the thumb (+x)
  EXPECT_LT(spread[20].x() - together[20].x(), -0.01f);  // pinky away from it
  const Keypoints21 open = tips("open-close", 0.1f), fist = tips("open-close", 1.1f);
  EXPECT_LT(fist[10].y() - open[10].y(), -0.02f);  // middle PIP toward the palm (-y)
  EXPECT_LT((fist[12] - fist[0]).norm(), (open[12] - open[0]).norm() - 0.08f);  // tip curled in
}

TEST(Clips, DefaultSetNamesExistingClipsAndLoops) {
  const model::ArticulatedModel hand = model::makeDefaultHand();
  for (const std::string& name : defaultClipSet()) {
    const auto info = std::find_if(clips().begin(), clips().end(),
                                   [&](const ClipInfo& c) { return c.name == name; });
    ASSERT_NE(info, clips().end()) << name;
    // Looping: t and t + duration give the same pose.
    const auto a = sampleClip(name, hand, 0.3f);
    const auto b = sampleClip(name, hand, 0.3f + info->duration);
    ASSERT_TRUE(a.ok() && b.ok());
    for (std::size_t j = 0; j < (*a)[0].angles.angles.size(); ++j)
      EXPECT_NEAR(((*a)[0].angles.angles[j] - (*b)[0].angles.angles[j]).norm(), 0.0f, 1e-4f);
  }
}

TEST(Clips, UnknownClipIsAnErrorListingTheClips) {
  const auto r = sampleClip("moonwalk", model::makeDefaultHand(), 0.0f);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.message().find("moonwalk"), std::string::npos);
  EXPECT_NE(r.message().find("wave"), std::string::npos);
}

TEST(SyntheticSequence, BadOptionsAreErrorsNamingTheProblem) {
  auto expectError = [](SynthOptions o, const std::string& needle) {
    const Result<SyntheticSequence> s = SyntheticSequence::create(o);
    ASSERT_FALSE(s.ok()) << needle;
    EXPECT_NE(s.message().find(needle), std::string::npos) << s.message();
  };
  SynthOptions o = optionsFor("wave");
  o.frameCount = 0;
  expectError(o, "frame count");
  o = optionsFor("wave");
  o.speed = -1.0f;
  expectError(o, "speed");
  o = optionsFor("wave");
  o.framesPerSecond = 0.0f;
  expectError(o, "frames per second");
  o = optionsFor("wave", "lidar");
  expectError(o, "lidar");
  o = optionsFor("no-such-clip");
  expectError(o, "no-such-clip");
  o = optionsFor("wave");
  o.hand.length = 0.5f;
  expectError(o, "hand length");
  o = optionsFor("wave");
  o.poseFile = "/nonexistent/poses.jsonl";
  expectError(o, "/nonexistent/poses.jsonl");
}

// Every ground-truth keypoint projects onto a pixel the renderer labelled as a hand.
TEST(SyntheticSequence, KeypointsProjectInsideTheRenderedHandMask) {
  for (const ClipInfo& clip : clips()) {
    for (const CameraPlacement placement :
         {CameraPlacement::DeskFacing, CameraPlacement::HeadMounted}) {
      SynthOptions o = optionsFor(clip.name);
      o.scene.placement = placement;
      o.scene.background = Background::Wall;
      Result<SyntheticSequence> seq = SyntheticSequence::create(o);
      ASSERT_TRUE(seq.ok()) << seq.message();
      const Intrinsics& k = seq->intrinsics();
      for (int f = 0; f < o.frameCount; f += 7) {
        const SyntheticFrame& frame = seq->frame(f);
        for (const HandTruth& hand : frame.hands) {
          for (std::size_t i = 0; i < 21; ++i) {
            const Vec2 uv = k.project(hand.keypoints[i]);
            ASSERT_TRUE(k.contains(uv.x(), uv.y()))
                << clip.name << " frame " << f << " keypoint " << i;
            const int u = static_cast<int>(std::lround(uv.x())),
                      v = static_cast<int>(std::lround(uv.y()));
            const PixelLabel label = seq->labels()[static_cast<std::size_t>(v) * k.width + u];
            EXPECT_TRUE(label == PixelLabel::Hand0 || label == PixelLabel::Hand1)
                << clip.name << (placement == CameraPlacement::HeadMounted ? " head" : " desk")
                << " frame " << f << " keypoint " << i;
          }
        }
      }
    }
  }
}

TEST(SyntheticSequence, GroundTruthMatchesTheModelPoseAndIsTheRightSize) {
  for (const float length : {0.16f, 0.19f, 0.22f}) {
    SynthOptions o = optionsFor("wave");
    o.hand.length = length;
    o.hand.width = 0.085f * length / 0.19f;
    Result<SyntheticSequence> seq = SyntheticSequence::create(o);
    ASSERT_TRUE(seq.ok());
    const HandTruth truth = seq->truth(5, 0);
    const Keypoints21 fromPose = model::keypoints21(seq->model(0), truth.pose);
    for (std::size_t i = 0; i < 21; ++i)
      EXPECT_LT((fromPose[i] - truth.keypoints[i]).norm(), 1e-6f);
    // Flat hand: wrist to middle fingertip is the hand length (to a few mm of joint bend).
    EXPECT_NEAR((truth.keypoints[12] - truth.keypoints[0]).norm(), length, 0.02f * length / 0.19f);
    // truth() without rendering equals the rendered frame's truth.
    const SyntheticFrame& frame = seq->frame(5);
    for (std::size_t i = 0; i < 21; ++i) EXPECT_EQ(frame.hands[0].keypoints[i], truth.keypoints[i]);
  }
}

TEST(SyntheticSequence, SameSeedSameBytesInAnyOrderAndSeedsDiffer) {
  SynthOptions o = optionsFor("pinch", "tof", 10);
  o.scene.background = Background::Torso;
  Result<SyntheticSequence> a = SyntheticSequence::create(o), b = SyntheticSequence::create(o);
  o.seed = 2;
  Result<SyntheticSequence> c = SyntheticSequence::create(o);
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  std::vector<std::vector<std::uint16_t>> forward;
  for (int f = 0; f < 10; ++f) forward.push_back(a->frame(f).depth.depth);
  for (int f = 9; f >= 0; --f)
    EXPECT_EQ(b->frame(f).depth.depth, forward[static_cast<std::size_t>(f)]) << f;
  EXPECT_NE(c->frame(3).depth.depth, forward[3]);
}

TEST(SyntheticSequence, TwoHandsAreARightAndAMirroredLeftHand) {
  Result<SyntheticSequence> seq = SyntheticSequence::create(optionsFor("two-hands"));
  ASSERT_TRUE(seq.ok());
  ASSERT_EQ(seq->handCount(), 2);
  const SyntheticFrame& frame = seq->frame(0);
  ASSERT_EQ(frame.hands.size(), 2u);
  EXPECT_EQ(frame.hands[0].side, model::Side::Right);
  EXPECT_EQ(frame.hands[1].side, model::Side::Left);
  // The desk camera faces the user: their right hand is on the image's left, each arm on its
  // own side of the body (not crossed); a head-mounted camera sees it on the right.
  EXPECT_LT(frame.hands[0].keypoints[0].x(), -0.05f);
  EXPECT_GT(frame.hands[1].keypoints[0].x(), 0.05f);
  SynthOptions head = optionsFor("two-hands");
  head.scene.placement = CameraPlacement::HeadMounted;
  Result<SyntheticSequence> fromHead = SyntheticSequence::create(head);
  ASSERT_TRUE(fromHead.ok());
  EXPECT_GT(fromHead->frame(0).hands[0].keypoints[0].x(), 0.05f);
  EXPECT_LT(fromHead->frame(0).hands[1].keypoints[0].x(), -0.05f);
  int left = 0, right = 0;
  for (const PixelLabel l : seq->labels()) {
    right += l == PixelLabel::Hand0;
    left += l == PixelLabel::Hand1;
  }
  EXPECT_GT(left, 500);
  EXPECT_GT(right, 500);
}

TEST(SyntheticSequence, SceneBackgroundTableAndForearmEnteringFromTheBorder) {
  for (const CameraPlacement placement :
       {CameraPlacement::DeskFacing, CameraPlacement::HeadMounted}) {
    SynthOptions o = optionsFor("open-close");
    o.scene.placement = placement;
    o.scene.background = Background::Wall;
    o.scene.table = true;
    Result<SyntheticSequence> seq = SyntheticSequence::create(o);
    ASSERT_TRUE(seq.ok());
    seq->frame(0);
    const Intrinsics& k = seq->intrinsics();
    int bottomHand = 0, background = 0;
    for (int u = 0; u < k.width; ++u)
      bottomHand +=
          seq->labels()[static_cast<std::size_t>(k.height - 1) * k.width + u] == PixelLabel::Hand0;
    for (const PixelLabel l : seq->labels()) background += l == PixelLabel::Background;
    EXPECT_GT(bottomHand, 10) << "the forearm should cross the bottom border";
    EXPECT_GT(background, k.width * k.height / 2);
    // Nothing but the hand is nearer than the wall.
    const float wall = seq->truth(0, 0).keypoints[0].z() + o.scene.backgroundDistance;
    for (std::size_t i = 0; i < seq->exactDepth().size(); ++i)
      if (seq->labels()[i] == PixelLabel::Background) {
        ASSERT_LE(seq->exactDepth()[i], wall + 0.05f);
      }
  }
}

// Joints of `frame` whose pixel shows the background (the table) 1 cm or more in front of them.
int jointsBehindTheTable(const SyntheticSequence& seq, const SyntheticFrame& frame) {
  const Intrinsics& k = seq.intrinsics();
  int hidden = 0;
  for (const Vec3& joint : frame.hands[0].keypoints) {
    const Vec2 px = k.project(joint);
    if (!k.contains(px.x(), px.y())) continue;
    const auto i =
        static_cast<std::size_t>(std::lround(px.y())) * static_cast<std::size_t>(k.width) +
        static_cast<std::size_t>(std::lround(px.x()));
    hidden += seq.labels()[i] == PixelLabel::Background && seq.exactDepth()[i] < joint.z() - 0.01f;
  }
  return hidden;
}

// A table at the wrist's height: the head-mounted open-close hand dips its fingers into it;
// Scene::tableBelowHand lowers it so that no joint is ever behind it, and by no more than that.
TEST(SyntheticSequence, ATableBelowTheHandIsLoweredOutOfTheMotionsWay) {
  int hiddenAtTheWrist = 0, hiddenBelowHand = 0;
  float lowered = 0.0f;
  for (const bool belowHand : {false, true}) {
    SynthOptions o = optionsFor("open-close", "ideal", 30);
    o.scene.placement = CameraPlacement::HeadMounted;
    o.scene.table = true;
    o.scene.tableDrop = 0.0f;
    o.scene.tableBelowHand = belowHand;
    Result<SyntheticSequence> seq = SyntheticSequence::create(o);
    ASSERT_TRUE(seq.ok()) << seq.error().message;
    for (int f = 0; f < seq->frameCount(); f += 3)
      (belowHand ? hiddenBelowHand : hiddenAtTheWrist) += jointsBehindTheTable(*seq, seq->frame(f));
    if (belowHand) lowered = seq->options().scene.tableDrop;
  }
  EXPECT_GT(hiddenAtTheWrist, 10);
  EXPECT_EQ(hiddenBelowHand, 0);
  EXPECT_GT(lowered, kTableClearance);
  EXPECT_LT(lowered, 0.15f);
}

// Each held object is drawn against the palm on every frame, labelled as the object, nearer
// than the hand's back seen from a desk camera (palm toward it); without one, no pixel is.
TEST(SyntheticSequence, HeldObjectsAreDrawnAgainstThePalm) {
  for (const HeldObject object :
       {HeldObject::None, HeldObject::Ball, HeldObject::Cylinder, HeldObject::Box}) {
    SCOPED_TRACE(heldObjectName(object));
    SynthOptions o = optionsFor("grasp-cylinder", "ideal", 12);
    o.scene.heldObject = object;
    Result<SyntheticSequence> seq = SyntheticSequence::create(o);
    ASSERT_TRUE(seq.ok()) << seq.error().message;
    for (int f = 0; f < 12; f += 11) {
      const SyntheticFrame& frame = seq->frame(f);
      const Keypoints21& kp = frame.hands[0].keypoints;
      const Vec3 palm = 0.5f * (kp[0] + kp[9]);
      int pixels = 0;
      float nearest = 1e9f;
      for (std::size_t i = 0; i < seq->labels().size(); ++i) {
        if (seq->labels()[i] != PixelLabel::HeldObject) continue;
        ++pixels;
        nearest = std::min(nearest, seq->exactDepth()[i]);
      }
      if (object == HeldObject::None) {
        EXPECT_EQ(pixels, 0);
        continue;
      }
      EXPECT_GT(pixels, 200) << "frame " << f;
      // In front of the palm (toward the camera) by the palm's skin and the object's size.
      EXPECT_LT(nearest, palm.z() - 0.02f) << "frame " << f;
      EXPECT_GT(nearest, palm.z() - 0.1f) << "frame " << f;
    }
  }
  SynthOptions bad = optionsFor("wave", "ideal", 1);
  bad.scene.heldObjectSize = 0.2f;
  EXPECT_FALSE(SyntheticSequence::create(bad).ok());
}

// The view shift moves the principal point: the same scene lands that many pixels over, the
// ground truth (camera frame) stays, and a hand near the border goes on out of view.
TEST(SyntheticSequence, ViewShiftMovesTheSceneInTheImage) {
  SynthOptions o = optionsFor("wave", "ideal", 1);
  Result<SyntheticSequence> centred = SyntheticSequence::create(o);
  o.scene.viewShift = Vec2(24.0f, -100.0f);
  Result<SyntheticSequence> shifted = SyntheticSequence::create(o);
  ASSERT_TRUE(centred.ok() && shifted.ok());
  const Intrinsics& a = centred->intrinsics();
  const Intrinsics& b = shifted->intrinsics();
  EXPECT_FLOAT_EQ(b.cx, a.cx + 24.0f);
  EXPECT_FLOAT_EQ(b.cy, a.cy - 100.0f);
  const SyntheticFrame& fa = centred->frame(0);
  const std::vector<float> depthA(centred->exactDepth().begin(), centred->exactDepth().end());
  const SyntheticFrame& fb = shifted->frame(0);
  for (std::size_t j = 0; j < 21; ++j)
    EXPECT_EQ(fa.hands[0].keypoints[j], fb.hands[0].keypoints[j]);
  int compared = 0, same = 0, outOfView = 0;
  for (int v = 0; v < a.height; ++v) {
    for (int u = 0; u < a.width; ++u) {
      const float za = depthA[static_cast<std::size_t>(v * a.width + u)];
      if (za <= 0.0f) continue;
      const int ub = u + 24, vb = v - 100;
      if (ub >= b.width || vb < 0) {
        ++outOfView;
        continue;
      }
      const float zb = shifted->exactDepth()[static_cast<std::size_t>(vb * b.width + ub)];
      ++compared;
      same += std::fabs(za - zb) < 1e-4f;
    }
  }
  EXPECT_GT(outOfView, 500) << "the fingers go out past the top edge";
  EXPECT_GT(same, compared * 99 / 100);
  o.scene.viewShift = Vec2(0.0f, 300.0f);
  const Result<SyntheticSequence> bad = SyntheticSequence::create(o);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("view shift"), std::string::npos) << bad.message();
  o.scene.viewShift = Vec2(std::numeric_limits<float>::quiet_NaN(), 0.0f);
  const Result<SyntheticSequence> notFinite = SyntheticSequence::create(o);
  ASSERT_FALSE(notFinite.ok());
  EXPECT_NE(notFinite.message().find("view shift must be finite"), std::string::npos)
      << notFinite.message();
}

TEST(SyntheticSequence, PoseFilePlaybackReproducesTheRecordedPoses) {
  const std::filesystem::path dir = test::scratchDir("synth_pose_playback");
  SynthOptions o = optionsFor("count", "ideal", 12);
  Result<SyntheticSequence> original = SyntheticSequence::create(o);
  ASSERT_TRUE(original.ok());
  model::PoseSequence poses;
  for (const model::Body& b : original->model(0).bodies()) poses.bodyNames.push_back(b.name);
  for (int f = 0; f < 12; ++f) poses.frames.push_back(original->truth(f, 0).pose);
  ASSERT_TRUE(model::savePoseSequence(poses, dir / "poses.jsonl").ok());

  SynthOptions replay = o;
  replay.poseFile = dir / "poses.jsonl";
  Result<SyntheticSequence> played = SyntheticSequence::create(replay);
  ASSERT_TRUE(played.ok()) << played.message();
  for (int f = 0; f < 12; ++f) {
    const HandTruth a = original->truth(f, 0), b = played->truth(f, 0);
    for (std::size_t i = 0; i < 21; ++i)
      EXPECT_LT((a.keypoints[i] - b.keypoints[i]).norm(), 1e-4f) << f << " " << i;
  }
}

TEST(SyntheticSequence, PlaysTheAuthorsAnimbankRetargetedToOurHand) {
  DYNAHAND_REQUIRE_SHARED_DATA(data);
  SynthOptions o = optionsFor("", "tof", 4);
  o.poseFile = data / "intel" / "animbank.pose";
  Result<SyntheticSequence> seq = SyntheticSequence::create(o);
  ASSERT_TRUE(seq.ok()) << seq.message();
  for (int f = 0; f < 4; ++f) {
    const SyntheticFrame& frame = seq->frame(f);
    EXPECT_EQ(test::keypointsOnHandPixels(*seq, frame), 21) << "frame " << f;
  }
}

// All 21 keypoints project into the image within the profile's range.
bool handInView(const SyntheticSequence& seq, const Keypoints21& k) {
  for (const Vec3& p : k) {
    const Vec2 uv = seq.intrinsics().project(p);
    if (!seq.intrinsics().contains(uv.x(), uv.y())) return false;
    if (p.z() < seq.profile().minRange || p.z() > seq.profile().maxRange) return false;
  }
  return true;
}

TEST(SyntheticSequence, HeadPlacementReplacesPoseFilesRigidly) {
  const std::filesystem::path dir = test::scratchDir("synth_pose_head");
  SynthOptions o = optionsFor("count", "tof", 30);
  Result<SyntheticSequence> original = SyntheticSequence::create(o);
  ASSERT_TRUE(original.ok());
  model::PoseSequence poses;
  for (const model::Body& b : original->model(0).bodies()) poses.bodyNames.push_back(b.name);
  for (int f = 0; f < 30; ++f) poses.frames.push_back(original->truth(f, 0).pose);
  ASSERT_TRUE(model::savePoseSequence(poses, dir / "poses.jsonl").ok());

  SynthOptions desk = o, head = o;
  desk.poseFile = head.poseFile = dir / "poses.jsonl";
  head.scene.placement = CameraPlacement::HeadMounted;
  Result<SyntheticSequence> a = SyntheticSequence::create(desk),
                            b = SyntheticSequence::create(head);
  ASSERT_TRUE(a.ok() && b.ok());
  const Result<SyntheticSequence> headClip = [&] {
    SynthOptions c = o;
    c.scene.placement = CameraPlacement::HeadMounted;
    return SyntheticSequence::create(c);
  }();
  ASSERT_TRUE(headClip.ok());
  const HandTruth a0 = a->truth(0, 0), b0 = b->truth(0, 0);
  // Seen from elsewhere: the back of the hand toward the camera, as the head clip has it.
  EXPECT_GT((a0.keypoints[9] - b0.keypoints[9]).norm(), 0.02f);
  const HandTruth clip0 = headClip->truth(0, 0);
  const Vec3 palmDesk =
      (a0.keypoints[5] - a0.keypoints[0]).cross(a0.keypoints[17] - a0.keypoints[0]);
  const Vec3 palmHead =
      (b0.keypoints[5] - b0.keypoints[0]).cross(b0.keypoints[17] - b0.keypoints[0]);
  const Vec3 palmClip =
      (clip0.keypoints[5] - clip0.keypoints[0]).cross(clip0.keypoints[17] - clip0.keypoints[0]);
  EXPECT_LT(palmDesk.z() * palmHead.z(), 0.0f);  // the other side of the hand faces the camera
  EXPECT_GT(palmHead.z() * palmClip.z(), 0.0f);
  // The same motion: distances between any keypoints of any two frames are kept.
  for (int f : {0, 7, 19, 29}) {
    const HandTruth ta = a->truth(f, 0), tb = b->truth(f, 0);
    for (std::size_t i : {0u, 4u, 8u, 12u, 20u})
      for (std::size_t j : {0u, 8u, 16u}) {
        EXPECT_NEAR((ta.keypoints[i] - a0.keypoints[j]).norm(),
                    (tb.keypoints[i] - b0.keypoints[j]).norm(), 1e-4f);
      }
    EXPECT_TRUE(handInView(*b, tb.keypoints)) << "frame " << f;
    const SyntheticFrame& frame = b->frame(f);
    int inside = 0;
    for (const Vec3& p : frame.hands[0].keypoints) {
      const Vec2 uv = b->intrinsics().project(p);
      const std::size_t i = static_cast<std::size_t>(std::lround(uv.y())) * b->intrinsics().width +
                            static_cast<std::size_t>(std::lround(uv.x()));
      inside += b->labels()[i] == PixelLabel::Hand0;
    }
    EXPECT_GE(inside, 19) << "frame " << f;  // a few may hide behind the hand seen from above
  }
}

// All of animbank.pose on `tof`, its poses loaded once into poseAngles (empty on failure).
SynthOptions animbankOptions(const std::filesystem::path& data) {
  SynthOptions o = optionsFor("", "tof", 2336);
  o.poseFile = data / "intel" / "animbank.pose";
  Result<std::vector<model::JointAngles>> angles = loadPoseAngles(o);
  EXPECT_TRUE(angles.ok()) << angles.message();
  if (angles.ok())
    o.poseAngles = std::make_shared<const std::vector<model::JointAngles>>(std::move(*angles));
  return o;
}

TEST(SyntheticSequence, AnimbankStaysInViewFromTheHeadAndPlaysFromAnyPose) {
  DYNAHAND_REQUIRE_SHARED_DATA(data);
  SynthOptions o = animbankOptions(data);
  ASSERT_TRUE(o.poseAngles);
  ASSERT_EQ(o.poseAngles->size(), 2336u);
  for (CameraPlacement placement : {CameraPlacement::DeskFacing, CameraPlacement::HeadMounted}) {
    o.scene.placement = placement;
    Result<SyntheticSequence> seq = SyntheticSequence::create(o);
    ASSERT_TRUE(seq.ok());
    int inView = 0, total = 0;
    for (int f = 0; f < seq->frameCount(); f += 8, ++total)
      inView += handInView(*seq, seq->truth(f, 0).keypoints);
    const double fraction = static_cast<double>(inView) / total;
    std::printf("animbank %s: %.1f%% of frames with every keypoint in view (tof)\n",
                placement == CameraPlacement::HeadMounted ? "head" : "desk", 100.0 * fraction);
    EXPECT_GT(fraction, 0.85);
  }
  // A later first pose: frame 0 is that pose, and the file loaded directly agrees.
  o.scene.placement = CameraPlacement::DeskFacing;
  o.poseStart = 500;
  o.frameCount = 3;
  Result<SyntheticSequence> shared = SyntheticSequence::create(o);
  SynthOptions direct = o;
  direct.poseAngles.reset();
  Result<SyntheticSequence> loaded = SyntheticSequence::create(direct);
  ASSERT_TRUE(shared.ok() && loaded.ok());
  for (int f = 0; f < 3; ++f)
    for (std::size_t i = 0; i < 21; ++i)
      EXPECT_LT((shared->truth(f, 0).keypoints[i] - loaded->truth(f, 0).keypoints[i]).norm(),
                2e-3f);
}

// An arm comes from the body. Seen from the eyes, a pose file's forearm (left free by its 21
// keypoints) is kept within 30 degrees of the head-mounted rest direction; from either camera
// the rendered arm goes on past the elbow to the shoulder, out of the image.
TEST(SyntheticSequence, ArmComesFromTheBody) {
  DYNAHAND_REQUIRE_SHARED_DATA(data);
  SynthOptions o = animbankOptions(data);
  ASSERT_TRUE(o.poseAngles);
  const float pitch = 35.0f * std::numbers::pi_v<float> / 180.0f;
  const Vec3 restForearm(0.0f, -std::sin(pitch), std::cos(pitch));  // elbow to wrist
  for (CameraPlacement placement : {CameraPlacement::HeadMounted, CameraPlacement::DeskFacing}) {
    const bool head = placement == CameraPlacement::HeadMounted;
    o.scene.placement = placement;
    Result<SyntheticSequence> seq = SyntheticSequence::create(o);
    ASSERT_TRUE(seq.ok()) << seq.message();
    const Intrinsics& k = seq->intrinsics();
    int frames = 0, turned = 0, reachBorder = 0;
    for (int f = 0; f < seq->frameCount(); f += 8, ++frames) {
      if (head) {
        const HandTruth truth = seq->truth(f, 0);
        const Pose& forearm = truth.pose.bodies[static_cast<std::size_t>(seq->model(0).root())];
        const float angle =
            std::acos(std::clamp((forearm.q * Vec3::UnitZ()).dot(restForearm), -1.0f, 1.0f));
        EXPECT_LE(angle, 30.01f * std::numbers::pi_v<float> / 180.0f) << "frame " << f;
        turned += angle > 29.99f * std::numbers::pi_v<float> / 180.0f;
      }
      seq->frame(f);
      bool border = false;
      for (int v = 0; v < k.height && !border; ++v)
        for (int u = 0; u < k.width && !border; ++u)
          border = (u == 0 || v == 0 || u + 1 == k.width || v + 1 == k.height) &&
                   seq->labels()[static_cast<std::size_t>(v) * k.width + u] == PixelLabel::Hand0;
      reachBorder += border;
    }
    if (head)
      std::printf("animbank head: forearm turned toward the body on %.1f%% of frames\n",
                  100.0 * turned / frames);
    EXPECT_EQ(reachBorder, frames) << (head ? "head" : "desk");
  }
}

TEST(SyntheticSequence, AuthorsPoseFileWithoutTheirModelIsAnError) {
  const std::filesystem::path dir = test::scratchDir("synth_pose_no_model");
  std::ofstream(dir / "one.pose") << "0 0 0.4 0 0 0 1\n";
  SynthOptions o = optionsFor("", "tof", 4);
  o.poseFile = dir / "one.pose";
  const Result<SyntheticSequence> seq = SyntheticSequence::create(o);
  ASSERT_FALSE(seq.ok());
  EXPECT_NE(seq.message().find("model_hand.json"), std::string::npos) << seq.message();
}

TEST(SyntheticSequence, WrittenSequenceReadsBackWithGroundTruthAndPoses) {
  const std::filesystem::path dir = test::scratchDir("synth_write") / "seq";
  Result<SyntheticSequence> seq = SyntheticSequence::create(optionsFor("two-hands", "tof", 6));
  ASSERT_TRUE(seq.ok());
  int calls = 0;
  ASSERT_TRUE(writeSequence(*seq, dir, [&](int done, int total) {
                EXPECT_EQ(total, 6);
                EXPECT_EQ(done, ++calls);
                return true;
              }).ok());
  Result<SequenceReader> reader = SequenceReader::open(dir);
  ASSERT_TRUE(reader.ok()) << reader.message();
  ASSERT_EQ(reader->frameCount(), 6);
  EXPECT_EQ(reader->info().intrinsics.width, 320);
  const Result<model::PoseSequence> poses = model::loadPoseSequence(dir / "poses.jsonl");
  ASSERT_TRUE(poses.ok()) << poses.message();
  ASSERT_EQ(poses->frames.size(), 6u);
  EXPECT_TRUE(model::loadPoseSequence(dir / "poses_hand1.jsonl").ok());
  EXPECT_TRUE(std::filesystem::exists(dir / "groundtruth_hand1.jsonl"));
  EXPECT_TRUE(std::filesystem::exists(dir / "synth.json"));
  for (int f = 0; f < 6; ++f) {
    const SyntheticFrame& frame = seq->frame(f);
    const Result<DepthFrame> read = reader->frame(f);
    ASSERT_TRUE(read.ok());
    EXPECT_EQ(read->depth, frame.depth.depth);
    const std::optional<Keypoints21> truth = reader->groundTruth(f);
    ASSERT_TRUE(truth.has_value());
    for (std::size_t i = 0; i < 21; ++i)
      EXPECT_LT(((*truth)[i] - frame.hands[0].keypoints[i]).norm(), 1e-5f);
    const Keypoints21 fromPose =
        model::keypoints21(seq->model(0), poses->frames[static_cast<std::size_t>(f)]);
    for (std::size_t i = 0; i < 21; ++i)
      EXPECT_LT((fromPose[i] - frame.hands[0].keypoints[i]).norm(), 1e-5f);
  }
  // A second write into the same folder is refused.
  EXPECT_FALSE(writeSequence(*seq, dir).ok());
}

TEST(SyntheticSequence, StoppingEarlyLeavesAValidShorterSequence) {
  const std::filesystem::path dir = test::scratchDir("synth_stop") / "seq";
  Result<SyntheticSequence> seq = SyntheticSequence::create(optionsFor("wave", "tof", 10));
  ASSERT_TRUE(seq.ok());
  ASSERT_TRUE(writeSequence(*seq, dir, [](int done, int) { return done < 4; }).ok());
  Result<SequenceReader> reader = SequenceReader::open(dir);
  ASSERT_TRUE(reader.ok());
  EXPECT_EQ(reader->frameCount(), 4);
}

TEST(ContactSheet, WritesAPngWithATilePerProfileAndClip) {
  const std::filesystem::path png = test::scratchDir("synth_sheet") / "sheet.png";
  Scene scene;
  scene.background = Background::Wall;
  ASSERT_TRUE(writeContactSheet(png, {"wave", "pinch"}, scene).ok());
  ASSERT_TRUE(std::filesystem::exists(png));
  EXPECT_GT(std::filesystem::file_size(png), 10000u);
  EXPECT_FALSE(writeContactSheet(png, {"nope"}, scene).ok());
  EXPECT_FALSE(writeContactSheet(png, {}, scene).ok());
}

}  // namespace
}  // namespace dynahand::synth
