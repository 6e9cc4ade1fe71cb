#include "viewer_messages.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>

#include "dynahand/track_io.h"

namespace dynahand::viewer {
namespace {

using Out = std::back_insert_iterator<std::string>;

// Clouds are drawn, not measured: 0.1 mm is plenty and keeps the messages small.
void appendPoint(std::string& s, const Vec3& v) {
  fmt::format_to(Out(s), "{:.4f},{:.4f},{:.4f}", v.x(), v.y(), v.z());
}
void appendVec(std::string& s, const Vec3& v) {
  fmt::format_to(Out(s), "[{:.6g},{:.6g},{:.6g}]", v.x(), v.y(), v.z());
}
void appendPose(std::string& s, const Pose& pose) {
  const float sign = pose.q.w() < 0 ? -1.0f : 1.0f;
  s += "{\"p\":";
  appendVec(s, pose.p);
  fmt::format_to(Out(s), ",\"q\":[{:.6g},{:.6g},{:.6g},{:.6g}]}}", sign * pose.q.w(),
                 sign * pose.q.x(), sign * pose.q.y(), sign * pose.q.z());
}
void appendString(std::string& s, const std::string& text) {
  s += '"';
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      s += '\\';
      s += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      fmt::format_to(Out(s), "\\u{:04x}", static_cast<int>(c));
    } else {
      s += c;
    }
  }
  s += '"';
}
void appendShape(std::string& s, const physics::ConvexShape& shape) {
  s += "\"vertices\":[";
  for (std::size_t i = 0; i < shape.vertices().size(); ++i) {
    if (i > 0) s += ',';
    appendVec(s, shape.vertices()[i]);
  }
  s += "],\"faces\":[";
  for (std::size_t f = 0; f < shape.faces().size(); ++f) {
    if (f > 0) s += ',';
    s += '[';
    const auto& idx = shape.faces()[f].vertices;
    for (std::size_t k = 0; k < idx.size(); ++k) {
      if (k > 0) s += ',';
      fmt::format_to(Out(s), "{}", idx[k]);
    }
    s += ']';
  }
  s += ']';
}
const char* sideName(model::Side side) {
  return side == model::Side::Right ? "right" : "left";
}

}  // namespace

std::string helloMessage(const HelloInfo& info) {
  std::string s;
  s.reserve(16384);
  s += "{\"type\":\"hello\",";
  fmt::format_to(Out(s), "\"version\":{},\"source\":", kStreamFormatVersion);
  appendString(s, info.source);
  fmt::format_to(Out(s),
                 ",\"fps\":{:.6g},\"frame_count\":{},\"ground_truth\":{},"
                 "\"intrinsics\":{{\"width\":{},\"height\":{},\"fx\":{:.6g},\"fy\":{:.6g},"
                 "\"cx\":{:.6g},\"cy\":{:.6g}}},\"simulations\":[",
                 info.framesPerSecond, info.frameCount, info.groundTruth ? "true" : "false",
                 info.intrinsics.width, info.intrinsics.height, info.intrinsics.fx,
                 info.intrinsics.fy, info.intrinsics.cx, info.intrinsics.cy);
  for (int k = 0; k < track::kStrategyCount; ++k) {
    if (k > 0) s += ',';
    appendString(s, track::strategyName(static_cast<track::StrategyKind>(k)));
  }
  s += "],\"models\":[";
  for (std::size_t m = 0; m < info.models.size(); ++m) {
    const model::ArticulatedModel& model = *info.models[m];
    if (m > 0) s += ',';
    s += "{\"bodies\":[";
    for (std::size_t b = 0; b < model.bodies().size(); ++b) {
      const model::Body& body = model.bodies()[b];
      if (b > 0) s += ',';
      s += "{\"name\":";
      appendString(s, body.name);
      fmt::format_to(Out(s), ",\"parent\":{},", body.parent);
      appendShape(s, body.shape);
      s += '}';
    }
    s += "]}";
  }
  s += "]}";
  return s;
}

std::string frameMessage(const FrameInfo& info) {
  std::string s;
  s.reserve(65536);
  fmt::format_to(Out(s),
                 "{{\"type\":\"frame\",\"version\":{},\"index\":{},\"loop\":{},"
                 "\"tracking_fps\":{:.1f},\"paused\":{},\"track\":",
                 kStreamFormatVersion, info.index, info.loop, info.trackingFps,
                 info.paused ? "true" : "false");
  io::JsonOptions json;
  json.candidates = true;
  json.candidatePoses = true;
  s += io::trackResultToJson(*info.result, *info.model, json);

  if (info.depth != nullptr && info.intrinsics != nullptr) {
    const DepthFrame& d = *info.depth;
    // The largest pixel grid that fits the point budget (most pixels hold data).
    const double pixels = static_cast<double>(d.width) * d.height;
    const int stride = std::max(
        1, static_cast<int>(std::ceil(std::sqrt(pixels / std::max(1, info.maxCloudPoints)))));
    s += ",\"cloud\":[";
    bool first = true;
    for (int v = stride / 2; v < d.height; v += stride) {
      for (int u = stride / 2; u < d.width; u += stride) {
        const float z = d.metres(u, v);
        if (z <= 0.0f) continue;
        if (!first) s += ',';
        first = false;
        appendPoint(s, info.intrinsics->deproject(static_cast<float>(u), static_cast<float>(v), z));
      }
    }
    s += ']';
  }
  if (info.samples != nullptr) {
    const std::size_t n = info.samples->size();
    const std::size_t step =
        std::max<std::size_t>(1, (n + static_cast<std::size_t>(info.maxSamplePoints) - 1) /
                                     static_cast<std::size_t>(std::max(1, info.maxSamplePoints)));
    s += ",\"samples\":[";
    for (std::size_t i = 0; i < n; i += step) {
      if (i > 0) s += ',';
      appendPoint(s, (*info.samples)[i]);
    }
    s += ']';
  }
  if (!info.truth.empty()) {
    s += ",\"truth\":[";
    for (std::size_t h = 0; h < info.truth.size(); ++h) {
      const TruthHand& t = info.truth[h];
      if (h > 0) s += ',';
      fmt::format_to(Out(s), "{{\"side\":\"{}\",\"keypoints21\":", sideName(t.side));
      if (t.keypoints) {
        s += '[';
        for (std::size_t k = 0; k < t.keypoints->size(); ++k) {
          if (k > 0) s += ',';
          appendVec(s, (*t.keypoints)[k]);
        }
        s += ']';
      } else {
        s += "null";
      }
      s += ",\"bodies\":[";
      for (std::size_t b = 0; b < t.pose.bodies.size(); ++b) {
        if (b > 0) s += ',';
        appendPose(s, t.pose.bodies[b]);
      }
      s += "]}";
    }
    s += ']';
  }
  s += '}';
  return s;
}

std::string sceneMessage(const std::vector<SceneBody>& bodies, const std::string& up) {
  std::string s;
  fmt::format_to(Out(s), "{{\"type\":\"scene\",\"version\":{},\"up\":", kStreamFormatVersion);
  appendString(s, up);
  s += ",\"bodies\":[";
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    if (b > 0) s += ',';
    s += "{\"name\":";
    appendString(s, bodies[b].name);
    if (!bodies[b].color.empty()) {
      s += ",\"color\":";
      appendString(s, bodies[b].color);
    }
    s += ',';
    appendShape(s, *bodies[b].shape);
    s += '}';
  }
  s += "]}";
  return s;
}

std::string scenePosesMessage(int step, double timeS, const std::vector<Pose>& poses) {
  std::string s;
  s.reserve(64 + poses.size() * 80);
  fmt::format_to(Out(s),
                 "{{\"type\":\"scene_poses\",\"version\":{},\"step\":{},\"time\":{:.6g},"
                 "\"poses\":[",
                 kStreamFormatVersion, step, timeS);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (i > 0) s += ',';
    appendPose(s, poses[i]);
  }
  s += "]}";
  return s;
}

}  // namespace dynahand::viewer
