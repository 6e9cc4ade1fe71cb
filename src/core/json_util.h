// Internal: typed access to parsed JSON with the JSON path in every error. Used by the
// model, pose and scene readers; FormatError is caught at the reader's top level and turned
// into an Error.
#pragma once

#include <charconv>
#include <cmath>
#include <initializer_list>
#include <numbers>
#include <string>

#include <nlohmann/json.hpp>

#include "dynahand/core.h"

namespace dynahand::jsonread {

struct FormatError {
  std::string path;     // e.g. "bodies[5].vertices[2]"
  std::string problem;  // e.g. "expected [x, y, z]"
};

inline std::string childPath(const std::string& path, const char* key) {
  return path.empty() ? std::string(key) : path + "." + key;
}

inline const nlohmann::json& field(const nlohmann::json& object, const std::string& path,
                                   const char* key) {
  const auto it = object.find(key);
  if (it == object.end()) throw FormatError{childPath(path, key), "missing"};
  return *it;
}

inline const nlohmann::json& objectAt(const nlohmann::json& v, const std::string& path) {
  if (!v.is_object()) throw FormatError{path, "expected an object"};
  return v;
}

inline const nlohmann::json& arrayAt(const nlohmann::json& v, const std::string& path) {
  if (!v.is_array()) throw FormatError{path, "expected an array"};
  return v;
}

inline void checkKeys(const nlohmann::json& object, const std::string& path,
                      std::initializer_list<const char*> allowed) {
  for (auto it = object.begin(); it != object.end(); ++it) {
    bool known = false;
    for (const char* key : allowed) known = known || it.key() == key;
    if (!known) throw FormatError{childPath(path, it.key().c_str()), "unknown field"};
  }
}

inline std::string string(const nlohmann::json& v, const std::string& path) {
  if (!v.is_string()) throw FormatError{path, "expected a string"};
  return v.get<std::string>();
}

// A finite number (JSON has no NaN; overflowing literals such as 1e999 are caught here).
inline float number(const nlohmann::json& v, const std::string& path) {
  if (!v.is_number()) throw FormatError{path, "expected a number"};
  const double d = v.get<double>();
  if (!std::isfinite(d) || std::abs(d) > 3.0e38) throw FormatError{path, "not a finite number"};
  return static_cast<float>(d);
}

inline Vec3 vec3(const nlohmann::json& v, const std::string& path) {
  if (!v.is_array() || v.size() != 3) throw FormatError{path, "expected [x, y, z]"};
  return {number(v[0], path + "[0]"), number(v[1], path + "[1]"), number(v[2], path + "[2]")};
}

// Angles are stored in degrees by the model formats and kept in radians inside.
inline constexpr double kDegPerRad = 180.0 / std::numbers::pi;

inline Vec3 degreesToRadians(const Vec3& deg) {
  return Vec3(static_cast<float>(static_cast<double>(deg.x()) / kDegPerRad),
              static_cast<float>(static_cast<double>(deg.y()) / kDegPerRad),
              static_cast<float>(static_cast<double>(deg.z()) / kDegPerRad));
}

// Shortest text that reads back as the same float.
inline std::string num(float v) {
  if (v == 0.0f) v = 0.0f;  // "-0" would read back as the integer 0 and lose its sign
  char buf[32];
  const auto result = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, result.ptr);
}

inline Quat quatWxyz(const nlohmann::json& v, const std::string& path) {
  if (!v.is_array() || v.size() != 4) throw FormatError{path, "expected [w, x, y, z]"};
  return Quat(number(v[0], path + "[0]"), number(v[1], path + "[1]"), number(v[2], path + "[2]"),
              number(v[3], path + "[3]"));
}

}  // namespace dynahand::jsonread
