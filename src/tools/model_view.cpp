// Shaded model drawing and views other than the depth camera's (dynahand render).
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "dynahand/tools/overlay.h"
#include "tools/rgb_mat.h"

namespace dynahand::eval {

namespace {

using detail::wrap;

cv::Point2f pixelf(const Intrinsics& k, const Vec3& p) {
  const Vec2 uv = k.project(p);
  return {uv.x(), uv.y()};
}
constexpr float kNearClipM = 0.01f;  // points closer to the view than this are not drawn

}  // namespace

View orbitView(const Intrinsics& camera, const Vec3& target, float angleRad) {
  // The view camera sits at R * (origin - target) + target with axes R * camera axes, so a
  // camera-frame point x is R^T (x - centre) in the view frame.
  const Quat r(Eigen::AngleAxisf(angleRad, Vec3::UnitY()));
  const Vec3 centre = target - r * target;
  const Quat rt = r.conjugate();
  return View{camera, Pose{rt * (-centre), rt}};
}

RgbImage shadePointsFromView(const DepthFrame& depth, const Intrinsics& camera, const View& view,
                             float nearM, float farM, const Vec3& target, float radiusM) {
  const Intrinsics& k = view.intrinsics;
  std::vector<float> zbuffer(static_cast<std::size_t>(k.width) * k.height,
                             std::numeric_limits<float>::infinity());
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      if (depth.at(u, v) == 0) continue;
      const Vec3 p = depth.point(camera, u, v);
      if (radiusM > 0 && (p - target).norm() > radiusM) continue;
      const Vec3 q = view.fromCamera.transform(p);
      if (q.z() < kNearClipM) continue;
      const Vec2 uv = k.project(q);
      // A 2x2 splat: the side view spreads the points of one image row apart.
      const int u0 = static_cast<int>(std::floor(uv.x())),
                v0 = static_cast<int>(std::floor(uv.y()));
      for (int dv = 0; dv < 2; ++dv) {
        for (int du = 0; du < 2; ++du) {
          const int x = u0 + du, y = v0 + dv;
          if (x < 0 || y < 0 || x >= k.width || y >= k.height) continue;
          float& z = zbuffer[static_cast<std::size_t>(y) * k.width + x];
          z = std::min(z, q.z());
        }
      }
    }
  }
  cv::Mat grey(k.height, k.width, CV_8UC1);
  const float span = std::max(1e-3f, farM - nearM);
  for (int y = 0; y < k.height; ++y) {
    for (int x = 0; x < k.width; ++x) {
      const float z = zbuffer[static_cast<std::size_t>(y) * k.width + x];
      grey.at<std::uint8_t>(y, x) =
          std::isfinite(z)
              ? static_cast<std::uint8_t>(255.0f * std::clamp((z - nearM) / span, 0.0f, 1.0f))
              : 0;
    }
  }
  cv::Mat colour;
  cv::applyColorMap(255 - grey, colour, cv::COLORMAP_TURBO);  // near = warm, as shadeDepth
  RgbImage out(k.width, k.height);
  cv::Mat rgb = wrap(out);
  cv::cvtColor(colour, rgb, cv::COLOR_BGR2RGB);
  for (int y = 0; y < k.height; ++y) {
    for (int x = 0; x < k.width; ++x) {
      if (!std::isfinite(zbuffer[static_cast<std::size_t>(y) * k.width + x])) {
        rgb.at<cv::Vec3b>(y, x) = cv::Vec3b(0, 0, 0);
      }
    }
  }
  return out;
}

void drawShadedModel(RgbImage& image, const View& view, const model::ArticulatedModel& model,
                     const model::ModelPose& pose, Rgb colour, float opacity) {
  if (pose.bodies.size() != model.bodies().size()) return;
  cv::Mat m = wrap(image);
  cv::Mat layer = m.clone();
  // Painter's order over bodies; a convex body's front faces never overlap each other.
  std::vector<std::pair<float, int>> order;
  std::vector<Pose> inView(pose.bodies.size());
  for (int b = 0; b < model.bodyCount(); ++b) {
    inView[static_cast<std::size_t>(b)] =
        view.fromCamera * pose.bodies[static_cast<std::size_t>(b)];
    order.emplace_back(inView[static_cast<std::size_t>(b)].p.z(), b);
  }
  std::sort(order.begin(), order.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  const cv::Scalar outline(colour.r * 0.35, colour.g * 0.35, colour.b * 0.35);
  for (const auto& [depthUnused, b] : order) {
    const auto& shape = model.bodies()[static_cast<std::size_t>(b)].shape;
    const Pose& p = inView[static_cast<std::size_t>(b)];
    std::vector<cv::Point2f> silhouette;
    bool visible = true;
    for (const Vec3& v : shape.vertices()) {
      const Vec3 q = p.transform(v);
      if (q.z() < kNearClipM) visible = false;
      silhouette.push_back(pixelf(view.intrinsics, q));
    }
    if (!visible) continue;
    for (const auto& face : shape.faces()) {
      const Vec3 corner = p.transform(shape.vertices()[static_cast<std::size_t>(face.vertices[0])]);
      const Vec3 normal = p.rotate(face.normal);
      const float facing = -normal.dot(corner.normalized());
      if (facing <= 0) continue;
      const double light = 0.35 + 0.65 * static_cast<double>(facing);  // lit from the viewer
      std::vector<cv::Point> polygon;
      for (int index : face.vertices) {
        const cv::Point2f q = silhouette[static_cast<std::size_t>(index)];
        polygon.emplace_back(static_cast<int>(std::lround(q.x)),
                             static_cast<int>(std::lround(q.y)));
      }
      cv::fillConvexPoly(layer, polygon,
                         cv::Scalar(colour.r * light, colour.g * light, colour.b * light),
                         cv::LINE_AA);
    }
    // A convex body projects to the convex hull of its projected vertices.
    std::vector<cv::Point2f> hull;
    cv::convexHull(silhouette, hull);
    std::vector<cv::Point> outlinePoints;
    for (const auto& q : hull) {
      outlinePoints.emplace_back(static_cast<int>(std::lround(q.x)),
                                 static_cast<int>(std::lround(q.y)));
    }
    cv::polylines(layer, outlinePoints, true, outline, 1, cv::LINE_AA);
  }
  cv::addWeighted(layer, static_cast<double>(opacity), m, 1.0 - static_cast<double>(opacity), 0.0,
                  m);
}

RgbImage besideEachOther(const std::vector<RgbImage>& images) {
  if (images.empty()) return {};
  int width = 0;
  const int height = images.front().height;
  for (const RgbImage& i : images) width += i.width;
  RgbImage out(width, height);
  cv::Mat m = wrap(out);
  int x = 0;
  for (const RgbImage& i : images) {
    if (i.height != height) continue;
    cv::Mat(i.height, i.width, CV_8UC3, const_cast<std::uint8_t*>(i.pixels.data()))
        .copyTo(m(cv::Rect(x, 0, i.width, i.height)));
    x += i.width;
  }
  return out;
}

}  // namespace dynahand::eval
