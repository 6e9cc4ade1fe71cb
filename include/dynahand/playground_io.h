/// @file
/// Playground output: body poses per frame as JSON lines (docs/formats/scene.md, "Play files") and
/// simple shaded pictures of a scene (perspective, flat-shaded hull faces, painter's order).
#pragma once

#include <filesystem>
#include <string>

#include "dynahand/playground.h"

namespace dynahand::playground {

/// The version written in a play file's header line.
inline constexpr int kPlayFormatVersion = 1;

/// Line 1 of a play file: format, version, scene name and the body names in output order.
std::string playHeaderJson(const Playground& playground);
/// One frame: index, simulated time (s), navigation offset (m, scene) and every body's pose.
std::string playFrameJson(const Playground& playground, int frame);

/// Where the picture is taken from (scene frame, y up).
struct RenderView {
  Vec3 eye = Vec3(0.0f, 0.45f, 0.55f);    ///< m
  Vec3 target = Vec3(0.0f, 0.05f, 0.0f);  ///< m, the point in the image centre
  float fovDeg = 45.0f;                   ///< vertical field of view, degrees
  int width = 640;                        ///< pixels
  int height = 480;                       ///< pixels
};

/// An 8-bit BGR picture of every body (hand skin-coloured, static bodies grey, others in
/// distinct colours), with `label` written in the top-left corner when non-empty.
Status renderPng(const Playground& playground, const RenderView& view,
                 const std::filesystem::path& path, const std::string& label = {});

}  // namespace dynahand::playground
