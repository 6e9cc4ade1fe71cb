// BVH export checked by a strict BVH reader written here: the hierarchy must parse
// (ROOT/JOINT/End Site, OFFSET, CHANNELS), the motion block must have one value per
// channel per frame, and forward kinematics of the parsed file (R = Rz Rx Ry per
// joint, lengths in cm) must put every joint where the model's joint centres are.
#include <gtest/gtest.h>

#include <numbers>
#include <random>
#include <sstream>

#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "dynahand/track_io.h"

namespace dynahand::io {
namespace {

struct BvhJoint {
  std::string name;
  int parent = -1;
  Vec3 offset = Vec3::Zero();
  std::vector<std::string> channels;
};

struct BvhFile {
  std::vector<BvhJoint> joints;
  int frames = 0;
  double frameTime = 0;
  std::vector<std::vector<float>> motion;
};

// Throws std::runtime_error on anything that is not strict BVH.
BvhFile parseBvh(const std::string& text) {
  std::istringstream in(text);
  auto expect = [&](const std::string& want) {
    std::string got;
    if (!(in >> got) || got != want)
      throw std::runtime_error("expected '" + want + "', got '" + got + "'");
  };
  BvhFile f;
  expect("HIERARCHY");
  std::vector<int> stack;
  std::string token;
  in >> token;
  if (token != "ROOT") throw std::runtime_error("no ROOT");
  auto readJoint = [&](const std::string& kind, auto&& self) -> void {
    BvhJoint j;
    if (kind != "End")
      in >> j.name;
    else
      expect("Site");
    j.parent = stack.empty() ? -1 : stack.back();
    expect("{");
    expect("OFFSET");
    float x, y, z;
    if (!(in >> x >> y >> z)) throw std::runtime_error("bad OFFSET");
    j.offset = Vec3(x, y, z);
    const bool endSite = kind == "End";
    if (!endSite) {
      expect("CHANNELS");
      int n;
      in >> n;
      if (n != 3 && n != 6) throw std::runtime_error("bad channel count");
      for (int c = 0; c < n; ++c) {
        std::string ch;
        in >> ch;
        j.channels.push_back(ch);
      }
    }
    const int index = static_cast<int>(f.joints.size());
    f.joints.push_back(j);
    if (endSite) f.joints.back().name = "End";
    stack.push_back(index);
    while (in >> token && token != "}") {
      if (token == "JOINT")
        self("JOINT", self);
      else if (token == "End")
        self("End", self);
      else
        throw std::runtime_error("unexpected '" + token + "'");
    }
    if (token != "}") throw std::runtime_error("unclosed joint");
    stack.pop_back();
  };
  readJoint("ROOT", readJoint);
  expect("MOTION");
  expect("Frames:");
  in >> f.frames;
  expect("Frame");
  expect("Time:");
  in >> f.frameTime;
  int channels = 0;
  for (const auto& j : f.joints) channels += static_cast<int>(j.channels.size());
  for (int i = 0; i < f.frames; ++i) {
    std::vector<float> row(static_cast<std::size_t>(channels));
    for (float& v : row) {
      if (!(in >> v)) throw std::runtime_error("short motion row");
    }
    f.motion.push_back(row);
  }
  if (in >> token) throw std::runtime_error("trailing data: " + token);
  return f;
}

Mat3 axisRotation(const std::string& channel, float degrees) {
  const float r = degrees * std::numbers::pi_v<float> / 180.0f;
  const Vec3 axis =
      channel[0] == 'X' ? Vec3::UnitX() : (channel[0] == 'Y' ? Vec3::UnitY() : Vec3::UnitZ());
  return Eigen::AngleAxisf(r, axis).toRotationMatrix();
}

// World positions (cm) of every non-end joint for one frame.
std::vector<Vec3> bvhJointPositions(const BvhFile& f, int frame) {
  std::vector<Mat3> rot(f.joints.size());
  std::vector<Vec3> pos(f.joints.size());
  std::size_t c = 0;
  for (std::size_t j = 0; j < f.joints.size(); ++j) {
    const BvhJoint& joint = f.joints[j];
    Mat3 local = Mat3::Identity();
    Vec3 translation = joint.offset;
    for (const auto& ch : joint.channels) {
      const float v = f.motion[static_cast<std::size_t>(frame)][c++];
      if (ch.find("position") != std::string::npos) {
        translation[ch[0] - 'X'] = v;
      } else {
        local = local * axisRotation(ch, v);
      }
    }
    if (joint.parent < 0) {
      rot[j] = local;
      pos[j] = translation;
    } else {
      const auto p = static_cast<std::size_t>(joint.parent);
      pos[j] = pos[p] + rot[p] * translation;
      rot[j] = rot[p] * local;
    }
  }
  std::vector<Vec3> out;
  for (std::size_t j = 0; j < f.joints.size(); ++j) {
    if (f.joints[j].name != "End") out.push_back(pos[j]);
  }
  return out;
}

TEST(Bvh, ParsesStrictlyAndReproducesJointCentres) {
  const auto hand = model::makeDefaultHand();
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  BvhWriter writer(hand, 30.0f);
  std::vector<model::ModelPose> poses;
  for (int f = 0; f < 5; ++f) {
    model::JointAngles a = model::zeroAngles(hand);
    for (int j = 0; j < hand.jointCount(); ++j) {
      const auto& joint = hand.joints()[static_cast<std::size_t>(j)];
      for (int k = 0; k < 3; ++k)
        a.angles[static_cast<std::size_t>(j)][k] =
            joint.minAngle[k] + u(rng) * (joint.maxAngle[k] - joint.minAngle[k]);
    }
    a.root = {Vec3(0.05f * u(rng), -0.02f, 0.4f),
              Quat(Eigen::AngleAxisf(3.0f * u(rng), Vec3(u(rng), u(rng), 1).normalized()))};
    poses.push_back(model::forwardKinematics(hand, a));
    writer.add(poses.back());
  }
  BvhFile f;
  ASSERT_NO_THROW(f = parseBvh(writer.text()));
  EXPECT_EQ(f.frames, 5);
  EXPECT_NEAR(f.frameTime, 1.0 / 30.0, 1e-6);
  int named = 0;
  for (const auto& j : f.joints) named += j.name != "End";
  EXPECT_EQ(named, hand.bodyCount());
  for (int frame = 0; frame < 5; ++frame) {
    const auto positions = bvhJointPositions(f, frame);
    // The parsed joints come in hierarchy (depth-first) order; match them by name.
    std::size_t k = 0;
    for (const auto& j : f.joints) {
      if (j.name == "End") continue;
      const int b = hand.bodyIndex(j.name);
      ASSERT_GE(b, 0) << j.name;
      const auto& body = hand.bodies()[static_cast<std::size_t>(b)];
      const Vec3 local = body.joint < 0
                             ? Vec3::Zero()
                             : hand.joints()[static_cast<std::size_t>(body.joint)].anchorChild;
      const Vec3 expected =
          poses[static_cast<std::size_t>(frame)].bodies[static_cast<std::size_t>(b)].transform(
              local) *
          100.0f;
      EXPECT_LT((positions[k] - expected).norm(), 0.01f) << j.name << " frame " << frame;  // 0.1 mm
      ++k;
    }
  }
}

TEST(Bvh, EmptyAnimationIsValid) {
  const auto hand = model::makeDefaultHand();
  BvhWriter writer(hand, 60.0f);
  BvhFile f;
  ASSERT_NO_THROW(f = parseBvh(writer.text()));
  EXPECT_EQ(f.frames, 0);
}

}  // namespace
}  // namespace dynahand::io
