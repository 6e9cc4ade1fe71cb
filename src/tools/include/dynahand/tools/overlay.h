/// @file
/// Pictures of what was tracked: depth images shaded in colour with hand skeletons and
/// the model's convex bodies drawn over them, and contact sheets of such tiles.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "dynahand/core.h"
#include "dynahand/depth_frame.h"
#include "dynahand/model.h"
#include "dynahand/model_pose.h"

namespace dynahand::eval {

/// An 8-bit RGB colour.
struct Rgb {
  std::uint8_t r = 0,  ///< red
      g = 0,           ///< green
      b = 0;           ///< blue
};

/// An 8-bit RGB image, row-major, 3 bytes per pixel.
struct RgbImage {
  int width = 0;                     ///< pixels per row
  int height = 0;                    ///< rows
  std::vector<std::uint8_t> pixels;  ///< (height x width x 3)

  RgbImage() = default;  ///< An empty image.
  /// A black w x h image.
  RgbImage(int w, int h) : width(w), height(h), pixels(static_cast<std::size_t>(w) * h * 3, 0) {}
  Status savePng(const std::filesystem::path& path) const;  ///< Writes the image as a PNG file.
};

/// Depth shaded from near (warm) to far (cool) between nearM and farM; no data black.
RgbImage shadeDepth(const DepthFrame& depth, float nearM, float farM);
/// The 21-keypoint skeleton (MediaPipe bones) projected through the camera.
void drawSkeleton(RgbImage& image, const Intrinsics& camera, const std::array<Vec3, 21>& keypoints,
                  Rgb colour, int thickness = 1);
/// Every body's hull edges projected through the camera, blended with `opacity` in [0, 1].
void drawModel(RgbImage& image, const Intrinsics& camera, const model::ArticulatedModel& model,
               const model::ModelPose& pose, Rgb colour, float opacity = 1.0f);
/// A pinhole view of the scene other than the depth camera's own: its intrinsics and the
/// transform from the depth camera's frame into the view's camera frame.
struct View {
  Intrinsics intrinsics;  ///< the view's pinhole camera
  Pose fromCamera;        ///< identity: the depth camera itself
};
/// The depth camera's view rotated by `angleRad` about the image's vertical axis through
/// `target` (m, camera frame), at the same distance: pi/2 looks at the target from the
/// side. The target keeps its pixel position.
View orbitView(const Intrinsics& camera, const Vec3& target, float angleRad);
/// The depth frame's points seen from `view`: nearer points drawn over farther ones, shaded
/// by their depth in the view between nearM and farM; points farther than `radiusM` from
/// `target` are left out (<= 0 keeps all). An image of the view's size, black background.
RgbImage shadePointsFromView(const DepthFrame& depth, const Intrinsics& camera, const View& view,
                             float nearM, float farM, const Vec3& target, float radiusM);
/// Every body as a filled convex polygon lit from the viewer (faces turned away are skipped;
/// bodies drawn far to near) with its silhouette outlined, blended with `opacity`.
void drawShadedModel(RgbImage& image, const View& view, const model::ArticulatedModel& model,
                     const model::ModelPose& pose, Rgb colour, float opacity = 1.0f);
/// Images of equal height side by side.
RgbImage besideEachOther(const std::vector<RgbImage>& images);
/// Text in the top-left corner (or at row `line`).
void drawLabel(RgbImage& image, const std::string& text, int line = 0,
               Rgb colour = {255, 255, 255});
/// The window of `image` around a set of points (with a margin in pixels), scaled to
/// tileWidth x tileHeight, keeping the aspect ratio.
RgbImage cropAround(const RgbImage& image, const Intrinsics& camera,
                    const std::vector<Vec3>& points, int marginPixels, int tileWidth,
                    int tileHeight);
/// Tiles of equal size in rows of `columns`.
RgbImage contactSheet(const std::vector<RgbImage>& tiles, int columns);

}  // namespace dynahand::eval
