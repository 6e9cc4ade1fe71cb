#include "dynahand/tools/overlay.h"

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "tools/rgb_mat.h"

namespace dynahand::eval {

namespace {

using detail::wrap;

cv::Scalar scalar(Rgb c) {
  return cv::Scalar(c.r, c.g, c.b);
}  // images are RGB in memory
cv::Point pixel(const Intrinsics& k, const Vec3& p) {
  const Vec2 uv = k.project(p);
  return {static_cast<int>(std::lround(uv.x())), static_cast<int>(std::lround(uv.y()))};
}

// MediaPipe hand connections.
constexpr std::array<std::array<int, 2>, 21> kBones = {
    {{0, 1},   {1, 2},   {2, 3},   {3, 4},   {0, 5},   {5, 6},   {6, 7},
     {7, 8},   {5, 9},   {9, 10},  {10, 11}, {11, 12}, {9, 13},  {13, 14},
     {14, 15}, {15, 16}, {13, 17}, {0, 17},  {17, 18}, {18, 19}, {19, 20}}};

}  // namespace

Status RgbImage::savePng(const std::filesystem::path& path) const {
  cv::Mat bgr;
  cv::cvtColor(wrap(*this), bgr, cv::COLOR_RGB2BGR);
  if (path.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(path.parent_path(), ec);
  }
  try {
    if (!cv::imwrite(path.string(), bgr)) return Error{path.string() + ": cannot write PNG"};
  } catch (const cv::Exception& e) {
    return Error{path.string() + ": " + e.what()};
  }
  return Ok{};
}

RgbImage shadeDepth(const DepthFrame& depth, float nearM, float farM) {
  RgbImage out(depth.width, depth.height);
  cv::Mat grey(depth.height, depth.width, CV_8UC1);
  const float span = std::max(1e-3f, farM - nearM);
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      const float z = depth.metres(u, v);
      grey.at<std::uint8_t>(v, u) =
          z > 0 ? static_cast<std::uint8_t>(255.0f * std::clamp((z - nearM) / span, 0.0f, 1.0f))
                : 0;
    }
  }
  cv::Mat colour;
  cv::applyColorMap(255 - grey, colour, cv::COLORMAP_TURBO);  // near = warm
  cv::Mat rgb = wrap(out);
  cv::cvtColor(colour, rgb, cv::COLOR_BGR2RGB);
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      if (depth.at(u, v) == 0) rgb.at<cv::Vec3b>(v, u) = cv::Vec3b(0, 0, 0);
    }
  }
  return out;
}

void drawSkeleton(RgbImage& image, const Intrinsics& camera, const std::array<Vec3, 21>& k,
                  Rgb colour, int thickness) {
  cv::Mat m = wrap(image);
  for (const auto& bone : kBones) {
    const Vec3& a = k[static_cast<std::size_t>(bone[0])];
    const Vec3& b = k[static_cast<std::size_t>(bone[1])];
    if (a.z() <= 0 || b.z() <= 0) continue;
    cv::line(m, pixel(camera, a), pixel(camera, b), scalar(colour), thickness, cv::LINE_AA);
  }
  for (const Vec3& p : k) {
    if (p.z() > 0) cv::circle(m, pixel(camera, p), thickness + 1, scalar(colour), -1, cv::LINE_AA);
  }
}

void drawModel(RgbImage& image, const Intrinsics& camera, const model::ArticulatedModel& model,
               const model::ModelPose& pose, Rgb colour, float opacity) {
  cv::Mat m = wrap(image);
  cv::Mat layer = m.clone();
  for (int b = 0; b < model.bodyCount(); ++b) {
    const auto& shape = model.bodies()[static_cast<std::size_t>(b)].shape;
    const Pose& p = pose.bodies[static_cast<std::size_t>(b)];
    for (const auto& face : shape.faces()) {
      // Only faces turned toward the camera: the outline a viewer expects.
      const Vec3 centre = p.transform(shape.vertices()[static_cast<std::size_t>(face.vertices[0])]);
      if (p.rotate(face.normal).dot(centre) > 0) continue;
      for (std::size_t i = 0; i < face.vertices.size(); ++i) {
        const Vec3 a = p.transform(shape.vertices()[static_cast<std::size_t>(face.vertices[i])]);
        const Vec3 c = p.transform(shape.vertices()[static_cast<std::size_t>(
            face.vertices[(i + 1) % face.vertices.size()])]);
        if (a.z() <= 0 || c.z() <= 0) continue;
        cv::line(layer, pixel(camera, a), pixel(camera, c), scalar(colour), 1, cv::LINE_AA);
      }
    }
  }
  cv::addWeighted(layer, static_cast<double>(opacity), m, 1.0 - static_cast<double>(opacity), 0.0,
                  m);
}

void drawLabel(RgbImage& image, const std::string& text, int line, Rgb colour) {
  cv::Mat m = wrap(image);
  const double scale = std::max(0.35, image.width / 900.0);
  const int y = static_cast<int>((line + 1) * 16 * scale / 0.4);
  cv::putText(m, text, cv::Point(4, y), cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(0, 0, 0), 3,
              cv::LINE_AA);
  cv::putText(m, text, cv::Point(4, y), cv::FONT_HERSHEY_SIMPLEX, scale, scalar(colour), 1,
              cv::LINE_AA);
}

RgbImage cropAround(const RgbImage& image, const Intrinsics& camera,
                    const std::vector<Vec3>& points, int marginPixels, int tileWidth,
                    int tileHeight) {
  int x0 = image.width, y0 = image.height, x1 = 0, y1 = 0;
  for (const Vec3& p : points) {
    if (p.z() <= 0) continue;
    const cv::Point q = pixel(camera, p);
    x0 = std::min(x0, q.x);
    y0 = std::min(y0, q.y);
    x1 = std::max(x1, q.x);
    y1 = std::max(y1, q.y);
  }
  if (x1 < x0) x0 = 0, y0 = 0, x1 = image.width - 1, y1 = image.height - 1;
  // Grow to the tile's aspect ratio around the centre, then clamp into the image.
  const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
  double w = x1 - x0 + 2.0 * marginPixels, h = y1 - y0 + 2.0 * marginPixels;
  const double aspect = static_cast<double>(tileWidth) / tileHeight;
  if (w / h < aspect)
    w = h * aspect;
  else
    h = w / aspect;
  w = std::min(w, static_cast<double>(image.width));
  h = std::min(h, static_cast<double>(image.height));
  const int rx = std::clamp(static_cast<int>(cx - w / 2), 0, image.width - static_cast<int>(w));
  const int ry = std::clamp(static_cast<int>(cy - h / 2), 0, image.height - static_cast<int>(h));
  RgbImage out(tileWidth, tileHeight);
  cv::Mat dst = wrap(out);
  cv::resize(wrap(image)(cv::Rect(rx, ry, static_cast<int>(w), static_cast<int>(h))), dst,
             cv::Size(tileWidth, tileHeight), 0, 0, cv::INTER_AREA);
  return out;
}

RgbImage contactSheet(const std::vector<RgbImage>& tiles, int columns) {
  if (tiles.empty() || columns <= 0) return {};
  const int tw = tiles.front().width, th = tiles.front().height;
  const int rows = (static_cast<int>(tiles.size()) + columns - 1) / columns;
  RgbImage sheet(tw * std::min(columns, static_cast<int>(tiles.size())), th * rows);
  cv::Mat m = wrap(sheet);
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    const int c = static_cast<int>(i) % columns, r = static_cast<int>(i) / columns;
    wrap(tiles[i]).copyTo(m(cv::Rect(c * tw, r * th, tw, th)));
  }
  return sheet;
}

}  // namespace dynahand::eval
