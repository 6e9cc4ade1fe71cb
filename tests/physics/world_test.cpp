// Contacts, welding, snapshots, determinism and allocation behaviour of the world.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

#include "dynahand/physics_world.h"
#include "physics/kernel_paths.h"
#include "physics/physics_scenes.h"

#include "physics/alloc_counter.h"

namespace dynahand::physics {
namespace {

constexpr float kDt = 1.0f / 60.0f;

TEST(Contacts, FiveBoxStackStaysAtRestTenSeconds) {
  WorldSettings settings;
  settings.gravity = Vec3(0, -9.81f, 0);
  World w(settings);
  const int ground = w.addShape(ConvexShape::box(Vec3(0.5f, 0.05f, 0.5f)));
  const int box = w.addShape(ConvexShape::box(Vec3(0.05f, 0.05f, 0.05f)));
  BodyDef g;
  g.shape = ground;
  g.type = BodyType::Static;
  g.pose.p = Vec3(0, -0.05f, 0);
  w.addBody(g);
  std::vector<BodyId> boxes;
  std::vector<Vec3> start;
  for (int i = 0; i < 5; ++i) {
    BodyDef d;
    d.shape = box;
    d.pose.p = Vec3(0, 0.05f + 0.1f * static_cast<float>(i), 0);
    boxes.push_back(w.addBody(d));
    start.push_back(d.pose.p);
  }
  float worst = 0.0f;
  for (int i = 0; i < 600; ++i) {
    w.step(kDt);
    for (std::size_t k = 0; k < boxes.size(); ++k) {
      worst = std::max(worst, (w.pose(boxes[k]).p - start[k]).norm());
    }
  }
  EXPECT_LT(worst, 1e-3f);
  EXPECT_GE(w.contacts().size(), 20u);  // 4 points per face contact
}

TEST(Contacts, DrivenFingersDoNotInterpenetrate) {
  World w;
  const int bone = w.addShape(scenes::bonePrism(0.04f, 0.009f, 0.008f));
  BodyDef a;
  a.shape = bone;
  a.pose.p = Vec3(0, -0.015f, 0);
  BodyDef b = a;
  b.pose.p = Vec3(0, 0.015f, 0);
  const BodyId ia = w.addBody(a), ib = w.addBody(b);
  // Each is driven to a pose 1 cm into the other, with a strong force.
  w.setBodyDrive(ia, Pose{Vec3(0, 0.005f, 0), Quat::Identity()}, 20.0f, 1.0f);
  w.setBodyDrive(ib, Pose{Vec3(0, -0.005f, 0), Quat(Eigen::AngleAxisf(0.2f, Vec3::UnitX()))}, 20.0f,
                 1.0f);
  float deepest = 0.0f;
  const ConvexShape& s = w.bodyShape(ia);
  for (int i = 0; i < 240; ++i) {
    w.step(kDt);
    // Penetration: deepest vertex of either body inside the other (exact signed distance).
    for (const Vec3& v : s.vertices()) {
      deepest = std::max(deepest,
                         -s.signedDistance(w.pose(ia).inverseTransform(w.pose(ib).transform(v))));
      deepest = std::max(deepest,
                         -s.signedDistance(w.pose(ib).inverseTransform(w.pose(ia).transform(v))));
    }
  }
  EXPECT_LT(deepest, 1e-3f);
  EXPECT_FALSE(w.contacts().empty());
  // They did move towards each other until touching.
  EXPECT_LT(w.pose(ib).p.y() - w.pose(ia).p.y(), 0.0185f);
}

// A small body pressed into a tall static wall near its bottom: the line between the centres
// points at the wall's bottom face, but the contact must push out through the front face.
TEST(Contacts, SmallBodyLowOnAStaticWallIsPushedOutOfTheNearestFace) {
  WorldSettings settings;
  settings.contactMargin = 0.01f;
  World w(settings);
  BodyDef wall;
  wall.shape = w.addShape(ConvexShape::box(Vec3(0.4f, 0.2f, 0.025f)));
  wall.type = BodyType::Static;
  wall.pose.p = Vec3(0, 0.2f, 0);  // front face z = 0.025, bottom face y = 0
  w.addBody(wall);
  // A fingertip-sized ball (hull of 26 points, radius 1 cm).
  std::vector<Vec3> ball;
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      for (int k = -1; k <= 1; ++k)
        if (i != 0 || j != 0 || k != 0)
          ball.push_back(0.01f * Vec3(i, j, k).cast<float>().normalized());
  BodyDef small;
  small.shape = w.addShape(*ConvexShape::fromPoints(ball));
  small.pose.p = Vec3(0, 0.03f, 0.025f + 0.01f - 0.004f);  // 4 mm into the front face
  const BodyId b = w.addBody(small);
  w.step(kDt);
  ASSERT_FALSE(w.contacts().empty());
  for (const ContactPoint& c : w.contacts()) EXPECT_GT(std::abs(c.normal.z()), 0.99f);
  for (int i = 0; i < 30; ++i) w.step(kDt);
  EXPECT_GT(w.pose(b).p.z(), 0.025f + 0.01f - 0.0005f) << "pushed out of the front face";
  EXPECT_NEAR(w.pose(b).p.y(), 0.03f, 0.001f) << "not pushed along the face";
}

TEST(Contacts, FilteredPairsPassThrough) {
  World w;
  const int box = w.addShape(ConvexShape::box(Vec3(0.02f, 0.02f, 0.02f)));
  BodyDef a;
  a.shape = box;
  a.linearVelocity = Vec3(0.5f, 0, 0);
  BodyDef b = a;
  b.pose.p = Vec3(0.06f, 0, 0);
  b.linearVelocity = Vec3::Zero();
  const BodyId ia = w.addBody(a), ib = w.addBody(b);
  w.setCollisionEnabled(ia, ib, false);
  EXPECT_FALSE(w.collisionEnabled(ib, ia));
  for (int i = 0; i < 30; ++i) w.step(kDt);
  EXPECT_NEAR(w.pose(ia).p.x(), 0.25f, 1e-4f);
  EXPECT_EQ(w.pose(ib).p.x(), 0.06f);
}

TEST(Weld, KeepsRelativePosesWhileTheGroupMovesAndUnweldFrees) {
  scenes::HandLike h = scenes::makeHandLike();
  World& w = h.world;
  std::vector<BodyId> all = h.bodies;
  std::vector<Pose> relative;
  for (BodyId b : all) relative.push_back(w.pose(all[0]).inverse() * w.pose(b));
  const Vec3 palmStart = w.pose(all[1]).p;
  const GroupId g = w.weld(all);
  EXPECT_EQ(w.groupOf(all[5]), g);
  // Pull hard on one fingertip only: the whole hand must move rigidly.
  const BodyId tip = all[4];
  for (int i = 0; i < 60; ++i) {
    w.rows().clear();
    w.rows().addSurface(tip, Vec3(0.02f, 0, 0), Vec3::UnitY(),
                        w.pose(tip).transform(Vec3(0.02f, 0, 0)) + Vec3(0, 0.05f, 0), 1.0f);
    w.step(kDt);
  }
  EXPECT_GT((w.pose(all[1]).p - palmStart).norm(), 5e-3f);  // the whole hand moved
  float worst = 0.0f;
  for (std::size_t k = 0; k < all.size(); ++k) {
    const Pose expect = w.pose(all[0]) * relative[k];
    const Pose actual = w.pose(all[k]);
    for (const Vec3& v : w.bodyShape(all[k]).vertices()) {
      worst = std::max(worst, (expect.transform(v) - actual.transform(v)).norm());
    }
  }
  EXPECT_LT(worst, 1e-5f);
  // Unweld: the same pull now bends the finger relative to the palm.
  w.unweld(g);
  EXPECT_EQ(w.groupOf(all[5]), -1);
  const Pose palmToTip0 = w.pose(all[1]).inverse() * w.pose(tip);
  for (int i = 0; i < 30; ++i) {
    w.rows().clear();
    w.rows().addSurface(tip, Vec3(0.02f, 0, 0), Vec3::UnitZ(),
                        w.pose(tip).transform(Vec3(0.02f, 0, 0)) + Vec3(0, 0, 0.03f), 1.0f);
    w.step(kDt);
  }
  const Pose palmToTip1 = w.pose(all[1]).inverse() * w.pose(tip);
  EXPECT_GT((palmToTip1.p - palmToTip0.p).norm(), 2e-3f);
}

TEST(Weld, PreservesMomentum) {
  World w;
  const int box = w.addShape(ConvexShape::box(Vec3(0.02f, 0.01f, 0.01f)));
  BodyDef a;
  a.shape = box;
  a.linearVelocity = Vec3(0.1f, 0, 0);
  a.angularVelocity = Vec3(0, 0, 1);
  BodyDef b = a;
  b.pose.p = Vec3(0, 0.05f, 0);
  b.linearVelocity = Vec3(-0.1f, 0.2f, 0);
  const BodyId ia = w.addBody(a), ib = w.addBody(b);
  const Vec3 p0 = w.linearVelocity(ia) + w.linearVelocity(ib);
  const std::vector<BodyId> members = {ia, ib};
  w.weld(members);
  EXPECT_LT((w.linearVelocity(ia) + w.linearVelocity(ib) - p0).norm(), 1e-6f);
  w.step(kDt);
  w.unweldAll();
  EXPECT_LT((w.linearVelocity(ia) + w.linearVelocity(ib) - p0).norm(), 1e-5f);
}

TEST(State, RestoreReplaysIdentically) {
  scenes::HandLike h = scenes::makeHandLike();
  World& w = h.world;
  w.reserveRows(400);
  scenes::addRandomSurfaceRows(w, 300, 1, 0.01f);
  for (int i = 0; i < 5; ++i) w.step(kDt);
  WorldState saved;
  w.saveState(saved);
  for (int i = 0; i < 10; ++i) w.step(kDt);
  const std::uint64_t first = w.stateHash();
  w.restoreState(saved);
  for (int i = 0; i < 10; ++i) w.step(kDt);
  EXPECT_EQ(w.stateHash(), first);
}

// Same inputs, two independent worlds: identical bytes after every step.
TEST(Determinism, TwoRunsGiveIdenticalBytes) {
  auto run = [](std::vector<std::uint64_t>* hashes) {
    scenes::HandLike h = scenes::makeHandLike();
    World& w = h.world;
    w.reserveRows(1000);
    for (int i = 0; i < 120; ++i) {
      w.rows().clear();
      scenes::addRandomSurfaceRows(w, 500, static_cast<std::uint64_t>(i), 0.01f);
      if (i == 40) w.weld(std::vector<BodyId>{0, 1, 2});
      if (i == 80) w.unweldAll();
      w.step(kDt);
      hashes->push_back(w.stateHash());
    }
  };
  std::vector<std::uint64_t> a, b;
  run(&a);
  run(&b);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "step " << i;
}

// The surface rows prepared four at a time (SSE) and one at a time give the same bytes: rows of
// every kind (two-sided, line of sight, boundary; ahead of and behind their surface), on free
// bodies and on a weld group, with per-body counts that are and are not multiples of four.
TEST(Determinism, SurfaceRowsPreparedFourAtATimeGiveTheSameBytes) {
  auto run = [](bool wide, std::vector<std::uint64_t>* hashes, std::vector<float>* impulses) {
    useWideSurfacePrepare(wide);
    scenes::HandLike h = scenes::makeHandLike();
    World& w = h.world;
    w.reserveRows(1000);
    for (int i = 0; i < 60; ++i) {
      w.rows().clear();
      scenes::addRandomSurfaceRows(w, 301 + i, static_cast<std::uint64_t>(i), 0.01f);
      for (int k = 0; k < 40; ++k) {
        const BodyId b = k % w.bodyCount();
        const Vec3 p = w.pose(b).p + Vec3(0.004f * static_cast<float>(k % 5) - 0.008f, 0, -0.02f);
        w.rows().addLineOfSight(b, Vec3::Zero(), p.normalized(), p, 0.01f);
      }
      for (int b = 0; b < w.bodyCount(); ++b)
        w.addBoundary(b, Vec3(0.0f, -1.0f, 0.0f), -w.pose(1).p.y() - 0.01f, 0.01f, 0.03f);
      if (i == 20) w.weld(std::vector<BodyId>{0, 1, 2, 5});
      if (i == 40) w.unweldAll();
      w.step(kDt);
      hashes->push_back(w.stateHash());
      impulses->insert(impulses->end(), w.rows().impulse.begin(), w.rows().impulse.end());
    }
  };
  std::vector<std::uint64_t> wideHashes, narrowHashes;
  std::vector<float> wideImpulses, narrowImpulses;
  run(false, &narrowHashes, &narrowImpulses);
  const bool wide = useWideSurfacePrepare(true);
  run(true, &wideHashes, &wideImpulses);
  if (!wide) GTEST_SKIP() << "no SSE: only the one-at-a-time path exists";
  ASSERT_EQ(wideHashes.size(), narrowHashes.size());
  for (std::size_t i = 0; i < wideHashes.size(); ++i)
    ASSERT_EQ(wideHashes[i], narrowHashes[i]) << "step " << i;
  ASSERT_EQ(wideImpulses.size(), narrowImpulses.size());
  std::size_t nonZero = 0;
  for (std::size_t i = 0; i < wideImpulses.size(); ++i) {
    ASSERT_EQ(std::bit_cast<std::uint32_t>(wideImpulses[i]),
              std::bit_cast<std::uint32_t>(narrowImpulses[i]))
        << "row impulse " << i;
    nonZero += wideImpulses[i] != 0.0f;
  }
  EXPECT_GT(nonZero, wideImpulses.size() / 4);  // the rows did act
}

// Worlds stepped side by side (their sweeps interleaved) end every step with the same bytes
// as when each is stepped alone, and as with the one-by-one surface sweep: four worlds with
// different row counts (the shorter sweeps run out first; one now and then has none), a weld
// group in one of them (a slot split into copies), contacts and limits in all; side by side
// as four, as two pairs (stepTogether), and as three and one.
TEST(Determinism, WorldsSteppedSideBySideGiveTheSameBytesAsAlone) {
  constexpr int kWorlds = 4;
  struct Run {
    std::vector<std::uint64_t> hashes;
    std::vector<float> impulses;
  };
  auto fill = [](World& w, int step, int which) {
    w.rows().clear();
    if (which == 3 && step % 6 == 0) return;  // a step without surface rows: no batches
    const int counts[kWorlds] = {300 + 7 * step, 120 + 3 * step, 450 - 5 * step, 40 + step};
    scenes::addRandomSurfaceRows(w, counts[which], static_cast<std::uint64_t>(1000 * which + step),
                                 0.01f);
    for (int b = 0; b < w.bodyCount(); ++b)
      w.addBoundary(b, Vec3(0.0f, -1.0f, 0.0f), -w.pose(1).p.y() - 0.01f, 0.01f, 0.03f);
    if (which == 1 && step == 10) w.weld(std::vector<BodyId>{0, 1, 2, 3, 4, 5, 6, 7, 8});
    if (which == 1 && step == 30) w.unweldAll();
  };
  enum class Mode { Alone, AloneOneByOne, FourSideBySide, Pairs, ThreeAndOne };
  auto run = [&](Mode mode) {
    std::vector<scenes::HandLike> hands;
    for (int k = 0; k < kWorlds; ++k) hands.push_back(scenes::makeHandLike());
    std::array<World*, kWorlds> worlds;
    for (int k = 0; k < kWorlds; ++k) {
      worlds[static_cast<std::size_t>(k)] = &hands[static_cast<std::size_t>(k)].world;
      worlds[static_cast<std::size_t>(k)]->reserveRows(1000);
    }
    const bool vector = useVectorSweeps(mode != Mode::AloneOneByOne);
    std::array<Run, kWorlds> out;
    for (int step = 0; step < 45; ++step) {
      for (int k = 0; k < kWorlds; ++k) fill(*worlds[static_cast<std::size_t>(k)], step, k);
      switch (mode) {
        case Mode::Alone:
        case Mode::AloneOneByOne:
          for (World* w : worlds) w->step(kDt);
          break;
        case Mode::FourSideBySide:
          World::stepSideBySide(worlds, kDt);
          break;
        case Mode::Pairs:
          World::stepTogether(*worlds[0], *worlds[1], kDt);
          World::stepTogether(*worlds[2], *worlds[3], kDt);
          break;
        case Mode::ThreeAndOne:
          World::stepSideBySide(std::span(worlds).first(3), kDt);
          World::stepSideBySide(std::span(worlds).subspan(3), kDt);
          break;
      }
      for (int k = 0; k < kWorlds; ++k) {
        World& w = *worlds[static_cast<std::size_t>(k)];
        Run& r = out[static_cast<std::size_t>(k)];
        r.hashes.push_back(w.stateHash());
        r.impulses.insert(r.impulses.end(), w.rows().impulse.begin(), w.rows().impulse.end());
      }
    }
    useVectorSweeps(true);
    return std::make_pair(out, vector);
  };
  const auto [alone, vectorAlone] = run(Mode::Alone);
  EXPECT_EQ(vectorAlone, useVectorSweeps(true));
  for (Mode mode : {Mode::AloneOneByOne, Mode::FourSideBySide, Mode::Pairs, Mode::ThreeAndOne}) {
    const auto [other, vector] = run(mode);
    SCOPED_TRACE(testing::Message() << "mode " << static_cast<int>(mode) << " vector " << vector);
    for (std::size_t k = 0; k < kWorlds; ++k) {
      ASSERT_EQ(alone[k].hashes.size(), other[k].hashes.size());
      for (std::size_t i = 0; i < alone[k].hashes.size(); ++i)
        ASSERT_EQ(alone[k].hashes[i], other[k].hashes[i]) << "world " << k << " step " << i;
      ASSERT_EQ(alone[k].impulses.size(), other[k].impulses.size());
      for (std::size_t i = 0; i < alone[k].impulses.size(); ++i)
        ASSERT_EQ(std::bit_cast<std::uint32_t>(alone[k].impulses[i]),
                  std::bit_cast<std::uint32_t>(other[k].impulses[i]))
            << "world " << k << " row impulse " << i;
    }
  }
  // The worlds moved (the comparison is not between resting states).
  for (std::size_t k = 0; k < kWorlds; ++k)
    EXPECT_NE(alone[k].hashes.front(), alone[k].hashes.back()) << "world " << k;
}

TEST(Allocation, NoHeapAllocationPerStepAfterWarmUp) {
  if (!test::AllocationCounter::supported())
    GTEST_SKIP() << "allocation counting is off under ASan";
  scenes::HandLike h = scenes::makeHandLike();
  World& w = h.world;
  w.reserveRows(1000);
  WorldState saved;
  for (int i = 0; i < 3; ++i) {
    w.rows().clear();
    scenes::addRandomSurfaceRows(w, 1000, 9, 0.01f);
    w.step(kDt);
  }
  w.saveState(saved);
  for (int i = 0; i < 3; ++i) {  // warm-up of the restore cycle itself
    w.restoreState(saved);
    w.rows().clear();
    scenes::addRandomSurfaceRows(w, 1000, 9, 0.01f);
    w.step(kDt);
  }
  test::AllocationCounter counter;
  for (int i = 0; i < 20; ++i) {
    w.restoreState(saved);
    w.rows().clear();
    scenes::addRandomSurfaceRows(w, 1000, 9, 0.01f);
    w.step(kDt);
  }
  EXPECT_EQ(counter.count(), 0);
}

TEST(HandLike, SeventeenBodiesSixteenJointsHoldTogether) {
  scenes::HandLike h = scenes::makeHandLike();
  World& w = h.world;
  EXPECT_EQ(w.bodyCount(), 17);
  EXPECT_EQ(w.jointCount(), 16);
  w.reserveRows(1000);
  float worst = 0.0f;
  for (int i = 0; i < 120; ++i) {
    w.rows().clear();
    scenes::addRandomSurfaceRows(w, 300, static_cast<std::uint64_t>(i), 0.01f);
    w.step(kDt);
    for (int j = 0; j < w.jointCount(); ++j) worst = std::max(worst, w.jointSeparation(j));
  }
  EXPECT_LT(worst, 1e-4f);
}

}  // namespace
}  // namespace dynahand::physics
