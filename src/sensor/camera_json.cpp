#include "sensor/camera_json.h"

#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>

#include "sensor/reader_error.h"

namespace dynahand::sensor {
namespace {

using nlohmann::json;

using detail::fail;

std::string typeName(const json& value) {
  return value.type_name();
}

Result<json> parse(std::string_view text, const std::string& name) {
  json document = json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (document.is_discarded()) return fail(name, "not valid JSON");
  if (!document.is_object())
    return fail(name, "expected a JSON object, found " + typeName(document));
  return document;
}

Result<double> number(const json& object, const char* key, const std::string& name) {
  const auto it = object.find(key);
  if (it == object.end()) return fail(name, std::string("missing \"") + key + "\"");
  if (!it->is_number()) {
    return fail(name, std::string("\"") + key + "\" is not a number (found " + typeName(*it) + " " +
                          it->dump().substr(0, 40) + ")");
  }
  const double value = it->get<double>();
  if (!std::isfinite(value)) return fail(name, std::string("\"") + key + "\" is not finite");
  return value;
}

Result<int> pixelCount(double value, const char* key, const std::string& name) {
  if (value != std::floor(value) || value < 1.0 || value > 16384.0) {
    return fail(name, std::string("\"") + key +
                          "\" must be a whole number of pixels in 1..16384, found " +
                          json(value).dump());
  }
  return static_cast<int>(value);
}

// Element `index` of a numeric array under `key`, e.g. "dims"[0].
Result<double> arrayNumber(const json& object, const char* key, std::size_t index, std::size_t size,
                           const std::string& name) {
  const auto it = object.find(key);
  if (it == object.end()) return fail(name, std::string("missing \"") + key + "\"");
  if (!it->is_array() || it->size() != size) {
    return fail(name, std::string("\"") + key + "\" must be an array of " + std::to_string(size) +
                          " numbers");
  }
  const json& element = (*it)[index];
  if (!element.is_number() || !std::isfinite(element.get<double>())) {
    return fail(
        name, std::string("\"") + key + "\"[" + std::to_string(index) + "] is not a finite number");
  }
  return element.get<double>();
}

Status checkIntrinsics(const Intrinsics& k, const std::string& name) {
  if (const std::string problem = k.problem(); !problem.empty())
    return fail(name, "bad intrinsics: " + problem);
  return Ok{};
}

// Intrinsics from {width, height, fx, fy, cx, cy} read from a file, checked; widthKey and
// heightKey name the first two in messages.
Result<Intrinsics> intrinsicsFrom(const double values[6], const char* widthKey,
                                  const char* heightKey, const std::string& name) {
  auto width = pixelCount(values[0], widthKey, name);
  if (!width) return width.error();
  auto height = pixelCount(values[1], heightKey, name);
  if (!height) return height.error();
  const Intrinsics k{*width,
                     *height,
                     static_cast<float>(values[2]),
                     static_cast<float>(values[3]),
                     static_cast<float>(values[4]),
                     static_cast<float>(values[5])};
  if (auto ok = checkIntrinsics(k, name); !ok) return ok.error();
  return k;
}

// Shortest text that reads back as exactly the same float.
std::string shortest(float value) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, value).ptr;
  return std::string(buffer, end);
}

}  // namespace

Status checkDepthScale(double scale, const std::string& name) {
  if (!std::isfinite(scale) || scale <= 0.0 || scale > 1.0) {
    return fail(name,
                "\"depth_scale\" must be in (0, 1] metres per unit, found " + json(scale).dump());
  }
  return Ok{};
}

Result<CameraDescription> parseCameraJson(std::string_view text, const std::string& name) {
  auto document = parse(text, name);
  if (!document) return document.error();
  if (const auto it = document->find("version"); it != document->end()) {
    if (!it->is_number_integer() || it->get<std::int64_t>() < 1) {
      return fail(name, "\"version\" must be a positive integer");
    }
    if (it->get<std::int64_t>() > kSequenceFormatVersion) {
      return fail(name, "format version " + it->dump() +
                            " is newer than this dynahand understands (" +
                            std::to_string(kSequenceFormatVersion) + ")");
    }
  }
  CameraDescription camera;
  double values[7] = {};
  const char* keys[7] = {"width", "height", "fx", "fy", "cx", "cy", "depth_scale"};
  for (int i = 0; i < 7; ++i) {
    auto value = number(*document, keys[i], name);
    if (!value) return value.error();
    values[i] = *value;
  }
  auto intrinsics = intrinsicsFrom(values, "width", "height", name);
  if (!intrinsics) return intrinsics.error();
  camera.intrinsics = *intrinsics;
  if (auto ok = checkDepthScale(values[6], name); !ok) return ok.error();
  camera.depthScale = static_cast<float>(values[6]);
  if (document->contains("fps")) {
    auto fps = number(*document, "fps", name);
    if (!fps) return fps.error();
    if (*fps <= 0.0 || *fps > 10000.0) return fail(name, "\"fps\" must be in (0, 10000]");
    camera.framesPerSecond = static_cast<float>(*fps);
  }
  if (document->contains("min_range_m")) {
    auto range = number(*document, "min_range_m", name);
    if (!range) return range.error();
    if (*range < 0.0 || *range > 100.0) return fail(name, "\"min_range_m\" must be in [0, 100]");
    camera.minRangeM = static_cast<float>(*range);
  }
  return camera;
}

std::string formatCameraJson(const CameraDescription& camera) {
  const Intrinsics& k = camera.intrinsics;
  return "{\"version\":" + std::to_string(kSequenceFormatVersion) +
         ",\"width\":" + std::to_string(k.width) + ",\"height\":" + std::to_string(k.height) +
         ",\"fx\":" + shortest(k.fx) + ",\"fy\":" + shortest(k.fy) + ",\"cx\":" + shortest(k.cx) +
         ",\"cy\":" + shortest(k.cy) + ",\"depth_scale\":" + shortest(camera.depthScale) +
         ",\"fps\":" + shortest(camera.framesPerSecond) +
         (camera.minRangeM > 0.0f ? ",\"min_range_m\":" + shortest(camera.minRangeM) : "") + "}\n";
}

Result<CameraDescription> parseIntelCameraJson(std::string_view text, const std::string& name) {
  auto document = parse(text, name);
  if (!document) return document.error();
  const auto it = document->find("dcamera");
  if (it == document->end())
    return fail(name, "missing \"dcamera\" (the depth camera description)");
  if (!it->is_object()) return fail(name, "\"dcamera\" is not an object");
  const std::string where = name + " dcamera";
  const json& d = *it;
  CameraDescription camera;
  auto scale = number(d, "depth_scale", where);
  if (!scale) return scale.error();
  if (auto ok = checkDepthScale(*scale, where); !ok) return ok.error();
  camera.depthScale = static_cast<float>(*scale);
  double values[6] = {};
  const char* keys[3] = {"dims", "focal", "principal"};
  for (int i = 0; i < 6; ++i) {
    auto value = arrayNumber(d, keys[i / 2], static_cast<std::size_t>(i % 2), 2, where);
    if (!value) return value.error();
    values[i] = *value;
  }
  // Their deprojection, x = (u - cx) / fx * z, is ours: pixel centres at integers.
  auto intrinsics = intrinsicsFrom(values, "dims[0]", "dims[1]", where);
  if (!intrinsics) return intrinsics.error();
  camera.intrinsics = *intrinsics;
  return camera;
}

Result<GroundTruthLine> parseGroundTruthLine(std::string_view line, const std::string& where) {
  auto document = parse(line, where);
  if (!document) return document.error();
  auto frame = number(*document, "frame", where);
  if (!frame) return frame.error();
  if (*frame != std::floor(*frame) || *frame < 0.0 || *frame > 1e9) {
    return fail(where, "\"frame\" must be a non-negative whole number");
  }
  GroundTruthLine out;
  out.frame = static_cast<int>(*frame);
  const auto it = document->find("keypoints21");
  if (it == document->end())
    return fail(where, "missing \"keypoints21\" (use null for a frame without a hand)");
  if (it->is_null()) return out;
  if (!it->is_array() || it->size() != 21) {
    return fail(where, "\"keypoints21\" must be null or an array of 21 [x,y,z] points");
  }
  Keypoints21 points;
  for (std::size_t i = 0; i < 21; ++i) {
    const json& p = (*it)[i];
    if (!p.is_array() || p.size() != 3) {
      return fail(where, "keypoints21[" + std::to_string(i) + "] must be an array [x,y,z]");
    }
    for (std::size_t c = 0; c < 3; ++c) {
      if (!p[c].is_number() || !std::isfinite(p[c].get<double>())) {
        return fail(where, "keypoints21[" + std::to_string(i) + "] has a non-numeric coordinate");
      }
      points[i][static_cast<int>(c)] = static_cast<float>(p[c].get<double>());
    }
  }
  out.keypoints = points;
  return out;
}

std::string formatGroundTruthLine(int frame, const std::optional<Keypoints21>& keypoints) {
  std::string line = "{\"frame\":" + std::to_string(frame) + ",\"keypoints21\":";
  if (!keypoints) return line + "null}\n";
  line += '[';
  for (std::size_t i = 0; i < keypoints->size(); ++i) {
    const Vec3& p = (*keypoints)[i];
    if (i > 0) line += ',';
    line += '[' + shortest(p.x()) + ',' + shortest(p.y()) + ',' + shortest(p.z()) + ']';
  }
  return line + "]}\n";
}

}  // namespace dynahand::sensor
