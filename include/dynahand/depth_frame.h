/// @file
/// Depth images and pinhole intrinsics: the data every depth source produces.
/// Camera frame as OpenCV (x right, y down, z forward), metres. Depth 0 = no data.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "dynahand/core.h"

namespace dynahand {

/// Pinhole camera. Pixel (u, v) has its centre at integer coordinates: a point
/// at (x, y, z) projects to u = fx * x / z + cx, v = fy * y / z + cy.
struct Intrinsics {
  int width = 0;    ///< pixels
  int height = 0;   ///< pixels
  float fx = 0.0f;  ///< focal length, pixels
  float fy = 0.0f;  ///< focal length, pixels
  float cx = 0.0f;  ///< principal point, pixels
  float cy = 0.0f;  ///< principal point, pixels

  /// 3D point (m) seen at pixel (u, v) with depth z (m).
  Vec3 deproject(float u, float v, float z) const {
    return {(u - cx) / fx * z, (v - cy) / fy * z, z};
  }
  /// Pixel coordinates of a 3D point (z > 0 assumed).
  Vec2 project(const Vec3& p) const { return {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy}; }
  /// Whether (u, v) lies within the image (its edges are at -0.5 and size - 0.5).
  bool contains(float u, float v) const {
    return u >= -0.5f && v >= -0.5f && u < static_cast<float>(width) - 0.5f &&
           v < static_cast<float>(height) - 0.5f;
  }
  /// A unit ray from the camera centre through pixel (u, v).
  Vec3 ray(float u, float v) const { return deproject(u, v, 1.0f).normalized(); }

  /// Empty when usable: positive size, finite positive focal lengths, finite
  /// principal point. Otherwise the reason, for error messages ("fx is -1").
  std::string problem() const {
    if (width <= 0 || height <= 0) {
      return "image size " + std::to_string(width) + " x " + std::to_string(height) +
             " is not positive";
    }
    if (!std::isfinite(fx) || fx <= 0.0f)
      return "fx " + std::to_string(fx) + " is not a positive number";
    if (!std::isfinite(fy) || fy <= 0.0f)
      return "fy " + std::to_string(fy) + " is not a positive number";
    if (!std::isfinite(cx)) return "cx is not a finite number";
    if (!std::isfinite(cy)) return "cy is not a finite number";
    return {};
  }
  bool valid() const { return problem().empty(); }  ///< True when problem() is empty.
};

/// One depth image: row-major uint16 values, metres = value * depthScale.
struct DepthFrame {
  int width = 0;                     ///< pixels
  int height = 0;                    ///< pixels
  float depthScale = 0.001f;         ///< metres per stored unit
  double timestamp = 0.0;            ///< seconds since the start of the sequence
  std::vector<std::uint16_t> depth;  ///< (height x width), 0 = no data

  DepthFrame() = default;  ///< An empty frame.
  /// A w x h frame with `scale` metres per unit and no data (all 0).
  DepthFrame(int w, int h, float scale)
      : width(w), height(h), depthScale(scale), depth(static_cast<std::size_t>(w) * h, 0) {}

  /// Stored value at column u, row v.
  std::uint16_t at(int u, int v) const { return depth[static_cast<std::size_t>(v) * width + u]; }
  /// Stored value at column u, row v, writable.
  std::uint16_t& at(int u, int v) { return depth[static_cast<std::size_t>(v) * width + u]; }
  /// Depth in metres at (u, v); 0 when there is no data.
  float metres(int u, int v) const { return static_cast<float>(at(u, v)) * depthScale; }
  /// 3D point (m, camera frame) at pixel (u, v); z = 0 when there is no data.
  Vec3 point(const Intrinsics& k, int u, int v) const {
    return k.deproject(static_cast<float>(u), static_cast<float>(v), metres(u, v));
  }
  bool empty() const { return depth.empty(); }  ///< True when there is no pixel buffer.
  /// True when the pixel buffer matches width x height and the scale is usable.
  bool consistent() const {
    return width >= 0 && height >= 0 && depth.size() == static_cast<std::size_t>(width) * height &&
           std::isfinite(depthScale) && depthScale > 0.0f;
  }
};

}  // namespace dynahand
