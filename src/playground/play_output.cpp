// Play files (docs/formats/play.md): JSON lines of every scene body's pose per frame.
// Floats are printed in their shortest round-trip form (fmt's default).
#include <fmt/format.h>

#include "dynahand/playground_io.h"

namespace dynahand::playground {
namespace {

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

}  // namespace

std::string playHeaderJson(const Playground& playground) {
  std::string names;
  for (const SceneBody& body : playground.bodies())
    names += (names.empty() ? "" : ", ") + quoted(body.name);
  return fmt::format(R"({{"format": "dynahand-play", "version": {}, "scene": {}, "bodies": [{}]}})",
                     kPlayFormatVersion, quoted(playground.scene().name), names);
}

std::string playFrameJson(const Playground& playground, int frame) {
  const Pose toScene = playground.trackingToScene();
  const Vec3 offset = toScene.p - playground.scene().camera.p;
  std::string out =
      fmt::format(R"({{"frame": {}, "time": {}, "offset": [{}, {}, {}], "poses": [)", frame,
                  static_cast<float>(playground.time()), offset.x(), offset.y(), offset.z());
  bool first = true;
  for (const SceneBody& body : playground.bodies()) {
    const Pose p = playground.world().pose(body.id);
    out += fmt::format("{}[{}, {}, {}, {}, {}, {}, {}]", first ? "" : ", ", p.p.x(), p.p.y(),
                       p.p.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z());
    first = false;
  }
  return out + "]}";
}

}  // namespace dynahand::playground
