// The procedural clip library: joint-angle keyframes on the default hand (joint layout of
// makeDefaultHand: 0 wrist, 1-3 thumb CMC/MCP/IP, then index, middle, ring, pinky
// MCP/PIP/DIP), authored in degrees for a right hand, smoothly interpolated and looped.
// Angles per joint are the model's (model_pose.h): flexion toward the palm, abduction
// toward the thumb, twist; every keyframe lies within the default hand's limits (tested).
//
// The root (forearm body) pose is relative to the hand's rest placement in the scene:
// offset in m along the forearm frame's axes (x radial, y dorsal, z distal) and rotation
// in degrees about those axes (x: pitch, y: yaw, z: roll = pronation/supination).
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "clip_library.h"

namespace dynahand::synth {
namespace {

using detail::ClipDefinition;
using detail::Key;
using detail::Shape;

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;
using detail::kJointCount;

Vec3 digit(float flexion, float abduction = 0.0f, float twist = 0.0f) {
  return {flexion, abduction, twist};
}

// Thumb: CMC (flexion, abduction, twist), MCP flexion, IP flexion.
void setThumb(Shape& s, Vec3 cmc, float mcp, float ip) {
  s.joints[1] = cmc;
  s.joints[2] = digit(mcp);
  s.joints[3] = digit(ip);
}
// Finger f (0 index .. 3 pinky): MCP flexion and abduction, PIP, DIP.
void setFinger(Shape& s, int f, float mcp, float abduction, float pip, float dip) {
  const std::size_t base = 4 + 3 * static_cast<std::size_t>(f);
  s.joints[base] = digit(mcp, abduction);
  s.joints[base + 1] = digit(pip);
  s.joints[base + 2] = digit(dip);
}
void setWrist(Shape& s, float flexion, float deviation) {
  s.joints[0] = digit(flexion, deviation);
}

// ---- Named shapes ----

Shape flat() {
  Shape s;
  setThumb(s, digit(0, 15), 0, 0);
  return s;
}
Shape relaxed() {
  Shape s;
  setThumb(s, digit(5, 10), 8, 8);
  for (int f = 0; f < 4; ++f)
    setFinger(s, f, 8.0f + 3.0f * static_cast<float>(f), 0, 12.0f + 4.0f * static_cast<float>(f),
              6);
  return s;
}
void curl(Shape& s, int f) {
  setFinger(s, f, 85, 0, 100, 60);
}
// The fist's thumb rests along the radial side of the curled index finger: tucked across
// the fingers it ran into the middle finger's distal phalanx, a pose no hand and no tracker
// whose bones collide can take (Clips.BonesOfTheDefaultHandDoNotOverlap).
void thumbAlongIndex(Shape& s) {
  setThumb(s, digit(10, 20, -20), 30, 10);
}
Shape fist() {
  Shape s;
  for (int f = 0; f < 4; ++f) curl(s, f);
  thumbAlongIndex(s);
  return s;
}
Shape spread() {
  Shape s;
  setThumb(s, digit(-10, 35), 0, 0);
  setFinger(s, 0, 0, 15, 0, 0);
  setFinger(s, 1, 0, 0, 0, 0);
  setFinger(s, 2, 0, -12, 0, 0);
  setFinger(s, 3, 0, -25, 0, 0);
  return s;
}
Shape fingersTogether() {
  Shape s = flat();
  setFinger(s, 0, 0, -4, 0, 0);
  setFinger(s, 2, 0, 4, 0, 0);
  setFinger(s, 3, 0, 8, 0, 0);
  return s;
}
// Counting: the first n fingers (index first) extended, the rest curled; 5 adds the thumb.
Shape count(int n) {
  Shape s = fist();
  for (int f = 0; f < std::min(n, 4); ++f)
    setFinger(s, f, 0, f == 0 ? 6.0f : (f == 1 ? -2.0f : -6.0f * static_cast<float>(f)), 0, 0);
  if (n >= 5) setThumb(s, digit(-10, 30), 0, 0);
  return s;
}
Shape point() {
  return count(1);
}
Shape pinch() {
  Shape s = relaxed();
  setFinger(s, 0, 40, 0, 45, 25);
  setFinger(s, 1, 25, 0, 30, 12);
  setFinger(s, 2, 28, 0, 34, 14);
  setFinger(s, 3, 32, 0, 38, 16);
  setThumb(s, digit(30, 20, 15), 20, 20);
  return s;
}
Shape preGrasp() {
  Shape s = spread();
  for (int f = 0; f < 4; ++f) s.joints[5 + 3 * static_cast<std::size_t>(f)] = digit(15);
  setThumb(s, digit(10, 35), 5, 5);
  return s;
}
Shape cylinderGrasp() {
  Shape s;
  for (int f = 0; f < 4; ++f) setFinger(s, f, 45, 0, 65, 40);
  setThumb(s, digit(25, 25, 15), 20, 25);
  return s;
}

// Closing around an object under the palm: a power grasp aiming tighter than the object, so
// fingers and thumb wrap it as far as it lets them.
Shape powerGrasp() {
  Shape s;
  for (int f = 0; f < 4; ++f) setFinger(s, f, 70, 0, 100, 60);
  setThumb(s, digit(45, 20, 15), 35, 35);
  return s;
}
// A key grip: the thumb's pad against the radial side of the index's middle phalanx, for
// holding a fin or key between them.
Shape keyGrip() {
  Shape s;
  for (int f = 0; f < 4; ++f) setFinger(s, f, 55, 0, 85, 40);
  setThumb(s, digit(-5, 15, -20), 35, 15);
  return s;
}

Shape withWrist(Shape s, float flexion, float deviation) {
  setWrist(s, flexion, deviation);
  return s;
}

// ---- Keyframes and clips ----

Key key(float t, const Shape& s, Vec3 offset = Vec3::Zero(), Vec3 rotation = Vec3::Zero()) {
  return Key{t, s, offset, rotation};
}

// Turning a key: the key grip rolls the forearm from +55 to -55 degrees about the axis
// through the pinch (not about the forearm's own axis, which runs 7 cm away through the wrist),
// so what is pinched turns in place. The roll is keyed every 13.75 degrees: offsets are
// interpolated linearly, which keeps the pinch within 0.5 mm of the axis.
std::vector<Key> turnKeyTrack() {
  const Vec3 pinch(0.05f, -0.05f, 0.0f);  // m, forearm frame (x radial, y dorsal)
  auto rolled = [&](float t, float degrees) {
    const Vec3 offset = pinch - Eigen::AngleAxisf(degrees * kDeg, Vec3::UnitZ()) * pinch;
    return key(t, keyGrip(), offset, Vec3(0, 0, degrees));
  };
  std::vector<Key> track = {rolled(0.0f, 55.0f)};
  constexpr int kSegments = 8;
  for (int i = 0; i <= kSegments; ++i) {
    const float s = static_cast<float>(i) / kSegments;
    track.push_back(rolled(0.4f + 1.4f * s, 55.0f - 110.0f * s));
  }
  track.push_back(rolled(2.4f, -55.0f));
  return track;
}

std::vector<Key> openCloseTrack() {
  return {key(0.0f, relaxed()), key(0.3f, relaxed()), key(1.0f, fist()), key(1.3f, fist())};
}
std::vector<Key> waveTrack() {
  return {key(0.0f, withWrist(flat(), 0, 15), Vec3::Zero(), Vec3(0, 8, 0)),
          key(0.6f, withWrist(flat(), 0, -25), Vec3::Zero(), Vec3(0, -8, 0))};
}

std::vector<ClipDefinition> makeClips() {
  std::vector<ClipDefinition> c;
  c.push_back({{"open-close", "relaxed open hand closing to a fist and opening again", 2.6f, 1},
               {openCloseTrack()}});
  c.push_back({{"wave", "flat hand waving side to side from the wrist", 1.2f, 1}, {waveTrack()}});
  c.push_back({{"point", "index finger pointing, aiming around", 3.0f, 1},
               {{key(0.0f, relaxed()), key(0.6f, point()), key(1.2f, withWrist(point(), 20, 10)),
                 key(1.8f, withWrist(point(), -15, -20)), key(2.4f, point())}}});
  c.push_back(
      {{"pinch", "thumb and index pinching and releasing", 2.0f, 1},
       {{key(0.0f, relaxed()), key(0.4f, relaxed()), key(1.0f, pinch()), key(1.4f, pinch())}}});
  {
    std::vector<Key> track = {key(0.0f, fist())};
    for (int n = 1; n <= 5; ++n) {
      track.push_back(key(0.9f * static_cast<float>(n) - 0.5f, count(n)));
      track.push_back(key(0.9f * static_cast<float>(n) - 0.1f, count(n)));
    }
    c.push_back({{"count", "counting one to five on the fingers", 5.0f, 1}, {track}});
  }
  c.push_back({{"spread", "fingers spreading apart and closing together", 2.0f, 1},
               {{key(0.0f, fingersTogether()), key(0.3f, fingersTogether()), key(1.0f, spread()),
                 key(1.3f, spread())}}});
  c.push_back(
      {{"wrist-flex-roll", "wrist flexing and extending, then the forearm rolling", 4.0f, 1},
       {{key(0.0f, relaxed()), key(0.7f, withWrist(relaxed(), 60, 0)),
         key(1.4f, withWrist(relaxed(), -55, 0)), key(2.0f, relaxed()),
         key(2.7f, relaxed(), Vec3::Zero(), Vec3(0, 0, 70)),
         key(3.4f, relaxed(), Vec3::Zero(), Vec3(0, 0, -60))}}});
  c.push_back(
      {{"fast-translation", "relaxed hand darting around at up to about 1 m/s", 1.2f, 1},
       {{key(0.0f, relaxed(), Vec3(-0.12f, 0, 0)), key(0.3f, relaxed(), Vec3(0.12f, 0, 0.02f)),
         key(0.6f, relaxed(), Vec3(0, 0.06f, -0.06f)),
         key(0.9f, relaxed(), Vec3(0.1f, -0.04f, 0.05f))}}});
  c.push_back({{"finger-flips", "fingers flicking between fist and flat in 0.1 s", 0.6f, 1},
               {{key(0.0f, fist()), key(0.2f, fist()), key(0.3f, flat()), key(0.5f, flat())}}});
  c.push_back({{"grasp-cylinder", "reaching for and grasping an imaginary 5 cm cylinder", 3.0f, 1},
               {{key(0.0f, relaxed()), key(0.7f, preGrasp()), key(1.4f, cylinderGrasp()),
                 key(2.2f, cylinderGrasp())}}});
  // Playground scenarios (docs/playground.md): offsets along the forearm frame, so with the
  // head-mounted camera y is up and z is forward. reach-grasp-lift opens with the thumb
  // abducted (preGrasp), ready to close around the object, and moves 2 cm before closing; the
  // scenes place the hand low enough (their camera) for that approach to reach the object.
  c.push_back(
      {{"reach-grasp-lift",
        "open hand (thumb abducted) lowering 2 cm onto an object, closing around it, "
        "lifting it 16 cm and holding it",
        4.6f, 1},
       {{key(0.0f, preGrasp(), Vec3(0, 0.0f, 0)), key(0.7f, preGrasp(), Vec3(0, -0.02f, 0)),
         key(1.3f, powerGrasp(), Vec3(0, -0.02f, 0)), key(2.0f, powerGrasp(), Vec3(0, 0.14f, 0)),
         key(4.4f, powerGrasp(), Vec3(0, 0.14f, 0))}}});
  c.push_back({{"push-forward", "fist pushing 13 cm forward and staying there", 2.6f, 1},
               {{key(0.0f, fist(), Vec3(0, 0, -0.03f)), key(0.4f, fist(), Vec3(0, 0, -0.03f)),
                 key(1.6f, fist(), Vec3(0, 0, 0.1f)), key(2.4f, fist(), Vec3(0, 0, 0.1f))}}});
  // Sideways: a fist moving across its forearm, where push-forward moves it along the forearm's
  // own axis (the two directions the forearm's hold, TrackerSettings::forearmHoldForce, treats
  // differently).
  c.push_back({{"push-sideways",
                "fist pushing 13 cm sideways, little finger first, and staying there", 2.6f, 1},
               {{key(0.0f, fist(), Vec3(0.03f, 0, 0)), key(0.4f, fist(), Vec3(0.03f, 0, 0)),
                 key(1.6f, fist(), Vec3(-0.1f, 0, 0)), key(2.4f, fist(), Vec3(-0.1f, 0, 0))}}});
  c.push_back({{"turn-key", "key grip rolling the forearm 110 degrees about the pinch", 2.6f, 1},
               {turnKeyTrack()}});
  {
    std::vector<Key> right = openCloseTrack(), left = waveTrack();
    // 11 cm to the ulnar side (-x, the hand frame's radial axis): away from the body's midline
    // for either hand (the left hand's frame is mirrored), so that each arm stays on its own
    // side from its shoulder.
    for (Key& k : right) k.offset.x() -= 0.11f;
    for (Key& k : left) k.offset.x() -= 0.11f;
    c.push_back({{"two-hands", "right hand opening and closing while the left waves", 2.6f, 2},
                 {right, left}});
  }
  {
    // Side by side with the thumb tips touching: 6.5 cm to the ulnar side each (the thumbs
    // reach past the index knuckles), so the two hands make one connected surface.
    std::vector<Key> right = openCloseTrack(), left = {key(0.0f, relaxed())};
    for (Key& k : right) k.offset.x() -= 0.065f;
    for (Key& k : left) k.offset.x() -= 0.065f;
    c.push_back({{"hands-touching",
                  "two hands side by side, thumbs and index fingers touching, the right one "
                  "opening and closing",
                  2.6f, 2},
                 {right, left}});
  }
  return c;
}

float smoothstep(float s) {
  return s * s * (3.0f - 2.0f * s);
}

void sampleTrack(const std::vector<Key>& keys, float duration, float time,
                 model::JointAngles& angles) {
  float t = std::fmod(time, duration);
  if (t < 0.0f) t += duration;
  // Segment k runs from keys[k] to keys[k + 1] (the last wraps to keys[0] at duration).
  std::size_t k = 0;
  while (k + 1 < keys.size() && keys[k + 1].time <= t) ++k;
  const Key& a = keys[k];
  const Key& b = keys[(k + 1) % keys.size()];
  const float end = k + 1 < keys.size() ? b.time : duration;
  const float span = end - a.time;
  const float s = span > 0.0f ? smoothstep(std::clamp((t - a.time) / span, 0.0f, 1.0f)) : 0.0f;

  angles.angles.resize(kJointCount);
  for (std::size_t j = 0; j < kJointCount; ++j)
    angles.angles[j] = ((1.0f - s) * a.shape.joints[j] + s * b.shape.joints[j]) * kDeg;
  const Vec3 rotation = ((1.0f - s) * a.rotation + s * b.rotation) * kDeg;
  angles.root.p = (1.0f - s) * a.offset + s * b.offset;
  angles.root.q = (Eigen::AngleAxisf(rotation.x(), Vec3::UnitX()) *
                   Eigen::AngleAxisf(rotation.y(), Vec3::UnitY()) *
                   Eigen::AngleAxisf(rotation.z(), Vec3::UnitZ()))
                      .normalized();
}

}  // namespace

namespace detail {

const std::vector<ClipDefinition>& clipDefinitions() {
  static const std::vector<ClipDefinition> kClips = makeClips();
  return kClips;
}

const ClipDefinition* findClip(const std::string& name) {
  for (const ClipDefinition& d : clipDefinitions())
    if (d.info.name == name) return &d;
  return nullptr;
}

void sampleClipInto(const ClipDefinition& clip, float time, std::vector<HandMotionSample>& out) {
  out.resize(clip.tracks.size());
  for (std::size_t h = 0; h < clip.tracks.size(); ++h) {
    out[h].side = h == 0 ? model::Side::Right : model::Side::Left;
    sampleTrack(clip.tracks[h], clip.info.duration, time, out[h].angles);
  }
}

}  // namespace detail

const std::vector<ClipInfo>& clips() {
  static const std::vector<ClipInfo> kInfos = [] {
    std::vector<ClipInfo> infos;
    for (const detail::ClipDefinition& d : detail::clipDefinitions()) infos.push_back(d.info);
    return infos;
  }();
  return kInfos;
}

const std::vector<std::string>& defaultClipSet() {
  static const std::vector<std::string> kSet = {"wave", "open-close", "count", "pinch",
                                                "wrist-flex-roll"};
  return kSet;
}

Result<std::vector<HandMotionSample>> sampleClip(const std::string& name,
                                                 const model::ArticulatedModel& rightHand,
                                                 float time) {
  if (rightHand.jointCount() != kJointCount)
    return Error{"clip '" + name + "' needs the default hand's " + std::to_string(kJointCount) +
                 " joints, model has " + std::to_string(rightHand.jointCount())};
  if (const detail::ClipDefinition* clip = detail::findClip(name)) {
    std::vector<HandMotionSample> samples;
    detail::sampleClipInto(*clip, time, samples);
    return samples;
  }
  std::string names;
  for (const ClipInfo& info : clips()) names += (names.empty() ? "" : ", ") + info.name;
  return Error{"unknown clip '" + name + "' (known: " + names + ")"};
}

}  // namespace dynahand::synth
