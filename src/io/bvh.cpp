// BVH export. Each body becomes a BVH joint placed at its joint centre (the root at
// its body-frame origin) whose frame has the body's orientation; OFFSETs are then
// constant: the child's anchor in the parent minus the parent's own anchor, both in
// the parent body frame. Channels hold the rotation relative to the parent body as
// Z, X, Y Euler angles (R = Rz Rx Ry), degrees; lengths in centimetres.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>

#include "dynahand/atomic_file.h"
#include "dynahand/model_pose.h"
#include "dynahand/track_io.h"

namespace dynahand::io {

namespace {

constexpr float kCmPerM = 100.0f;
constexpr float kDegPerRad = 180.0f / std::numbers::pi_v<float>;

// (z, x, y) angles, rad, with R = Rz(z) Rx(x) Ry(y).
Vec3 eulerZXY(const Quat& q) {
  const Mat3 r = q.toRotationMatrix();
  // R(2,1) = sin x; R(0,1) = -sin z cos x; R(1,1) = cos z cos x; R(2,0) = -cos x sin y; R(2,2) =
  // cos x cos y.
  const float x = std::asin(std::clamp(r(2, 1), -1.0f, 1.0f));
  float z, y;
  if (std::abs(r(2, 1)) < 0.9999f) {
    z = std::atan2(-r(0, 1), r(1, 1));
    y = std::atan2(-r(2, 0), r(2, 2));
  } else {  // gimbal lock: put everything in z
    z = std::atan2(r(1, 0), r(0, 0));
    y = 0.0f;
  }
  return {z, x, y};
}

// BVH joint origin of a body, in its own body frame: its joint's anchor, or 0 for the root.
Vec3 jointOrigin(const model::ArticulatedModel& m, int body) {
  const int j = m.bodies()[static_cast<std::size_t>(body)].joint;
  return j < 0 ? Vec3::Zero() : m.joints()[static_cast<std::size_t>(j)].anchorChild;
}

std::string safeName(const std::string& name) {
  std::string s = name;
  for (char& c : s) {
    if (c == ' ' || c == '\t' || c == '{' || c == '}') c = '_';
  }
  return s;
}

}  // namespace

BvhWriter::BvhWriter(const model::ArticulatedModel& model, float framesPerSecond)
    : model_(&model), fps_(framesPerSecond) {}

void BvhWriter::add(const model::ModelPose& pose) {
  const auto& m = *model_;
  std::vector<float> channels;
  channels.reserve(static_cast<std::size_t>(3 + 3 * m.bodyCount()));
  for (int b : m.kinematicOrder()) {
    const Pose& body = pose.bodies[static_cast<std::size_t>(b)];
    const int parent = m.bodies()[static_cast<std::size_t>(b)].parent;
    Quat relative = body.q;
    if (parent < 0) {
      const Vec3 p = body.p * kCmPerM;
      channels.insert(channels.end(), {p.x(), p.y(), p.z()});
    } else {
      relative = pose.bodies[static_cast<std::size_t>(parent)].q.conjugate() * body.q;
    }
    const Vec3 e = eulerZXY(relative.normalized()) * kDegPerRad;
    channels.insert(channels.end(), {e.x(), e.y(), e.z()});
  }
  frames_.push_back(std::move(channels));
}

std::string BvhWriter::text() const {
  const auto& m = *model_;
  std::string s = "HIERARCHY\n";
  // Children lists, written depth first in kinematic order (parents before children).
  std::vector<std::vector<int>> children(static_cast<std::size_t>(m.bodyCount()));
  for (int b : m.kinematicOrder()) {
    const int parent = m.bodies()[static_cast<std::size_t>(b)].parent;
    if (parent >= 0) children[static_cast<std::size_t>(parent)].push_back(b);
  }
  // The order channels are written must match add(): kinematicOrder. Depth-first output
  // can differ from it, so add() order is mapped when writing MOTION below.
  std::vector<int> hierarchyOrder;
  auto writeJoint = [&](auto&& self, int b, int depth) -> void {
    const std::string indent(static_cast<std::size_t>(2 * depth), ' ');
    const int parent = m.bodies()[static_cast<std::size_t>(b)].parent;
    const std::string& name = m.bodies()[static_cast<std::size_t>(b)].name;
    hierarchyOrder.push_back(b);
    Vec3 offset = Vec3::Zero();
    if (parent < 0) {
      s += fmt::format("{}ROOT {}\n{}{{\n", indent, safeName(name), indent);
    } else {
      const int j = m.bodies()[static_cast<std::size_t>(b)].joint;
      offset =
          (m.joints()[static_cast<std::size_t>(j)].anchorParent - jointOrigin(m, parent)) * kCmPerM;
      s += fmt::format("{}JOINT {}\n{}{{\n", indent, safeName(name), indent);
    }
    s += fmt::format("{}  OFFSET {:.6f} {:.6f} {:.6f}\n", indent, offset.x(), offset.y(),
                     offset.z());
    s += parent < 0
             ? fmt::format(
                   "{}  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n",
                   indent)
             : fmt::format("{}  CHANNELS 3 Zrotation Xrotation Yrotation\n", indent);
    const auto& kids = children[static_cast<std::size_t>(b)];
    if (kids.empty()) {
      // End site: the farthest hull vertex from the joint (the fingertip for a finger).
      const auto& shape = m.bodies()[static_cast<std::size_t>(b)].shape;
      const Vec3 origin = jointOrigin(m, b);
      Vec3 tip = origin;
      for (const Vec3& v : shape.vertices()) {
        if ((v - origin).squaredNorm() > (tip - origin).squaredNorm()) tip = v;
      }
      const Vec3 end = (tip - origin) * kCmPerM;
      s += fmt::format("{}  End Site\n{}  {{\n{}    OFFSET {:.6f} {:.6f} {:.6f}\n{}  }}\n", indent,
                       indent, indent, end.x(), end.y(), end.z(), indent);
    }
    for (int c : kids) self(self, c, depth + 1);
    s += indent + "}\n";
  };
  writeJoint(writeJoint, m.root(), 0);

  // Channel offsets of each body in add()'s layout (kinematic order).
  std::vector<int> channelStart(static_cast<std::size_t>(m.bodyCount()));
  int at = 0;
  for (int b : m.kinematicOrder()) {
    channelStart[static_cast<std::size_t>(b)] = at;
    at += m.bodies()[static_cast<std::size_t>(b)].parent < 0 ? 6 : 3;
  }
  s += fmt::format("MOTION\nFrames: {}\nFrame Time: {:.6f}\n", frames_.size(),
                   1.0 / static_cast<double>(fps_));
  for (const auto& frame : frames_) {
    std::string line;
    for (int b : hierarchyOrder) {
      const int count = m.bodies()[static_cast<std::size_t>(b)].parent < 0 ? 6 : 3;
      for (int c = 0; c < count; ++c) {
        if (!line.empty()) line += ' ';
        fmt::format_to(
            std::back_inserter(line), "{:.5f}",
            frame[static_cast<std::size_t>(channelStart[static_cast<std::size_t>(b)] + c)]);
      }
    }
    s += line + '\n';
  }
  return s;
}

Status BvhWriter::save(const std::filesystem::path& path) const {
  return writeFileAtomically(path, text());  // never a truncated file under PATH
}

}  // namespace dynahand::io
