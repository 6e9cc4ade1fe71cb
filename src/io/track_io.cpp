#include "dynahand/track_io.h"

#include "dynahand/model_intel.h"

#include <fmt/format.h>

#include <cmath>

namespace dynahand::io {

namespace {

void appendVec(std::string& s, const Vec3& v) {
  fmt::format_to(std::back_inserter(s), "[{:.6g},{:.6g},{:.6g}]", v.x(), v.y(), v.z());
}
void appendQuat(std::string& s, const Quat& q) {
  // w first; the sign is chosen so w >= 0 (the same rotation, stable output).
  const float sign = q.w() < 0 ? -1.0f : 1.0f;
  fmt::format_to(std::back_inserter(s), "[{:.6g},{:.6g},{:.6g},{:.6g}]", sign * q.w(), sign * q.x(),
                 sign * q.y(), sign * q.z());
}
// JSON has no NaN/inf: non-finite numbers are written as null.
void appendNumber(std::string& s, float v) {
  if (std::isfinite(v)) {
    fmt::format_to(std::back_inserter(s), "{:.6g}", v);
  } else {
    s += "null";
  }
}

const char* sideName(model::Side side) {
  return side == model::Side::Right ? "right" : "left";
}

// "hand_size":{...}, (given, or estimated from frames with a fit score).
void appendHandSize(std::string& s, const HandSizeRecord& size) {
  s += "\"hand_size\":{\"length\":";
  appendNumber(s, size.dimensions.length);
  s += ",\"width\":";
  appendNumber(s, size.dimensions.width);
  if (size.estimated) {
    fmt::format_to(std::back_inserter(s),
                   ",\"source\":\"estimated\",\"frames\":{},\"fit\":", size.frames);
    appendNumber(s, size.fitScore);
    s += ",\"metacarpals\":[";
    for (std::size_t d = 0; d < size.metacarpals.size(); ++d) {
      if (d > 0) s += ',';
      appendNumber(s, size.metacarpals[d]);
    }
    s += "]},";
  } else {
    s += ",\"source\":\"given\"},";
  }
}

// ,"keypoints21":[...] and, as asked, ,"openxr26":[...] and ,"bodies":[...] of a tracked hand.
void appendTrackedPose(std::string& s, const track::HandResult& hand,
                       const model::ArticulatedModel& model, const JsonOptions& o) {
  s += ",\"keypoints21\":[";
  for (int k = 0; k < 21; ++k) {
    if (k > 0) s += ',';
    appendVec(s, hand.keypoints21[static_cast<std::size_t>(k)]);
  }
  s += ']';
  if (o.openxr && model.hasOpenXrJoints()) {
    s += ",\"openxr26\":[";
    for (int j = 0; j < 26; ++j) {
      const auto& joint = hand.openxr26[static_cast<std::size_t>(j)];
      if (j > 0) s += ',';
      s += "{\"p\":";
      appendVec(s, joint.pose.p);
      s += ",\"q\":";
      appendQuat(s, joint.pose.q);
      fmt::format_to(std::back_inserter(s), ",\"r\":{:.6g}}}", joint.radius);
    }
    s += ']';
  }
  if (o.bodies) {
    s += ",\"bodies\":[";
    for (std::size_t b = 0; b < hand.pose.bodies.size(); ++b) {
      if (b > 0) s += ',';
      fmt::format_to(std::back_inserter(s), "{{\"name\":\"{}\",\"p\":", model.bodies()[b].name);
      appendVec(s, hand.pose.bodies[b].p);
      s += ",\"q\":";
      appendQuat(s, hand.pose.bodies[b].q);
      s += '}';
    }
    s += ']';
  }
}

// ,"detector":{...}: the learned detector's keypoints, confidences and disagreement.
void appendDetector(std::string& s, const track::HandResult& hand) {
  s += ",\"detector\":{\"keypoints21\":[";
  for (std::size_t k = 0; k < hand.detectorKeypoints21.size(); ++k) {
    if (k > 0) s += ',';
    appendVec(s, hand.detectorKeypoints21[k]);
  }
  s += "],\"confidence\":[";
  for (std::size_t k = 0; k < hand.detectorConfidence.size(); ++k) {
    if (k > 0) s += ',';
    appendNumber(s, hand.detectorConfidence[k]);
  }
  s += "],\"disagreement\":";
  appendNumber(s, hand.detectorDisagreement);
  fmt::format_to(std::back_inserter(s), ",\"disagreeing_frames\":{}}}", hand.disagreeingFrames);
}

// ,"candidates":[...]: every simulation that ran, its error and (as asked) its body poses.
void appendCandidates(std::string& s, const track::HandResult& hand, const JsonOptions& o) {
  s += ",\"candidates\":[";
  bool first = true;
  for (const auto& c : hand.candidates) {
    if (!c.ran) continue;
    if (!first) s += ',';
    first = false;
    fmt::format_to(std::back_inserter(s),
                   "{{\"simulation\":\"{}\",\"error\":", track::strategyName(c.kind));
    appendNumber(s, c.error);
    if (o.candidatePoses && !c.pose.bodies.empty()) {
      s += ",\"bodies\":[";
      for (std::size_t b = 0; b < c.pose.bodies.size(); ++b) {
        if (b > 0) s += ',';
        s += "{\"p\":";
        appendVec(s, c.pose.bodies[b].p);
        s += ",\"q\":";
        appendQuat(s, c.pose.bodies[b].q);
        s += '}';
      }
      s += ']';
    }
    s += '}';
  }
  s += ']';
}

// One hand's object.
void appendHand(std::string& s, const track::HandResult& hand, const model::ArticulatedModel& model,
                const JsonOptions& o) {
  fmt::format_to(std::back_inserter(s), "{{\"side\":\"{}\",\"tracked\":{}", sideName(hand.side),
                 hand.tracked ? "true" : "false");
  if (hand.tracked) {
    appendTrackedPose(s, hand, model, o);
  } else {
    s += ",\"keypoints21\":null";
  }
  s += ",\"error\":";
  appendNumber(s, hand.error);
  s += ",\"error_fit\":";
  appendNumber(s, hand.fitError);
  s += ",\"error_occlusion\":";
  appendNumber(s, hand.occlusionError);
  fmt::format_to(std::back_inserter(s), ",\"simulation\":\"{}\",\"acquired\":{},\"points\":{}",
                 track::strategyName(hand.simulation), hand.acquired ? "true" : "false",
                 hand.pointCount);
  if (hand.detected) appendDetector(s, hand);
  if (hand.tracked) {
    s += ",\"fit\":{\"data_near_model\":";
    appendNumber(s, hand.quality.dataNearModel);
    s += ",\"model_on_hand\":";
    appendNumber(s, hand.quality.modelOnHand);
    fmt::format_to(std::back_inserter(s), ",\"fingertips_off_hand\":{}}}",
                   hand.quality.fingertipsOffHand);
  }
  if (o.candidates) appendCandidates(s, hand, o);
  s += '}';
}

}  // namespace

model::HandShape HandSizeRecord::shape() const {
  model::HandShape shape;
  for (std::size_t d = 0; d < metacarpals.size(); ++d) shape.boneLength[d][0] = metacarpals[d];
  return shape;
}

HandSizeRecord HandSizeRecord::fromEstimate(const track::HandSizeEstimate& estimate) {
  HandSizeRecord record{estimate.dimensions, true, estimate.framesUsed, estimate.fitScore};
  for (std::size_t d = 0; d < record.metacarpals.size(); ++d)
    record.metacarpals[d] = estimate.shape.boneLength[d][0];
  return record;
}

std::string trackResultToJson(const track::TrackResult& r, const model::ArticulatedModel& model,
                              const JsonOptions& o) {
  std::string s;
  s.reserve(4096);
  fmt::format_to(std::back_inserter(s), "{{\"version\":{},\"frame\":{},\"time_ms\":{:.3f},",
                 kTrackFormatVersion, r.frame + o.firstFrame, r.timeMs);
  if (o.handSize) appendHandSize(s, *o.handSize);
  s += "\"hands\":[";
  for (std::size_t h = 0; h < r.hands.size(); ++h) {
    if (h > 0) s += ',';
    appendHand(s, r.hands[h], model, o);
  }
  s += "]}";
  return s;
}

Result<std::unique_ptr<TrackWriter>> TrackWriter::create(const std::filesystem::path& path,
                                                         const model::ArticulatedModel& model,
                                                         const JsonOptions& options) {
  auto w = std::unique_ptr<TrackWriter>(new TrackWriter());
  w->model_ = &model;
  w->options_ = options;
  const std::string ext = path.extension().string();
  if (ext == ".csv") {
    w->format_ = Format::Csv;
  } else if (ext == ".jsonl" || ext == ".json" || ext == ".ndjson") {
    w->format_ = Format::JsonLines;
  } else if (ext == ".pose") {
    w->format_ = Format::IntelPose;
  } else {
    return Error{path.string() + ": unknown output format '" + ext +
                 "' (use .jsonl, .csv or .pose)"};
  }
  if (Status opened = w->file_.open(path); !opened) return Error{opened.message()};
  if (w->format_ == Format::Csv) {
    w->file_.stream() << "frame,time_ms,side,tracked,error_m,simulation";
    const auto& names = model::keypoint21Names();
    for (const char* name : names)
      w->file_.stream() << ',' << name << "_x," << name << "_y," << name << "_z";
    w->file_.stream() << '\n';
  }
  return w;
}

Status TrackWriter::write(const track::TrackResult& r) {
  if (format_ == Format::JsonLines) {
    file_.stream() << trackResultToJson(r, *model_, options_) << '\n';
  } else if (format_ == Format::IntelPose) {
    // The format has no frame numbers, so every frame gets a line: lost frames repeat
    // the last tracked pose, and frames before the first tracked one wait for it.
    const track::HandResult* hand = r.hands.empty() ? nullptr : &r.hands.front();
    if (hand != nullptr && hand->tracked) lastTracked_ = hand->pose;
    if (lastTracked_.bodies.empty()) {
      ++pendingLines_;
      return Ok{};
    }
    const std::string line = model::intelPoseLine(lastTracked_, *model_);
    for (; pendingLines_ >= 0; --pendingLines_) file_.stream() << line << '\n';
    pendingLines_ = 0;
  } else {
    for (const auto& hand : r.hands) {
      std::string row = fmt::format("{},{:.3f},{},{},{:.6g},{}", r.frame + options_.firstFrame,
                                    r.timeMs, sideName(hand.side), hand.tracked ? 1 : 0, hand.error,
                                    track::strategyName(hand.simulation));
      for (const Vec3& k : hand.keypoints21) {
        if (hand.tracked) {
          fmt::format_to(std::back_inserter(row), ",{:.6g},{:.6g},{:.6g}", k.x(), k.y(), k.z());
        } else {
          row += ",,,";
        }
      }
      file_.stream() << row << '\n';
    }
  }
  return file_.flush();  // an interrupted run keeps every frame written so far
}

Status TrackWriter::close() {
  return file_.commit();
}

}  // namespace dynahand::io
