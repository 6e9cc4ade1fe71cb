// A deliberately simple renderer for playground pictures: every front-facing hull face is
// projected through a pinhole camera, flat-shaded (ambient + one directional light) and
// painted far to near (painter's algorithm; hulls are convex, so overlaps between faces of
// one body never need sorting beyond back-face culling).
#include <algorithm>
#include <cmath>
#include <numbers>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "dynahand/playground_io.h"

namespace dynahand::playground {
namespace {

constexpr float kNear = 0.01f;  // m, near clipping plane

struct Polygon {
  float depth = 0.0f;  // m from the eye, mean over the face's vertices
  std::vector<cv::Point> points;
  cv::Scalar colour;
};

cv::Scalar bodyColour(const SceneBody& body, int index) {
  if (body.isHand) return {150, 175, 225};  // BGR skin
  if (body.isStatic) return {165, 160, 155};
  static const cv::Scalar kPalette[] = {{70, 110, 220}, {200, 140, 60}, {80, 170, 90},
                                        {170, 90, 170}, {60, 190, 210}, {190, 190, 70}};
  return kPalette[index % 6];
}

}  // namespace

Status renderPng(const Playground& playground, const RenderView& view,
                 const std::filesystem::path& path, const std::string& label) {
  // Camera axes: z forward (eye -> target), x right, y down (OpenCV).
  const Vec3 forward = (view.target - view.eye).normalized();
  const Vec3 right = forward.cross(Vec3::UnitY()).normalized();
  const Vec3 down = forward.cross(right);
  const float f = 0.5f * static_cast<float>(view.height) /
                  std::tan(0.5f * view.fovDeg * std::numbers::pi_v<float> / 180.0f);
  const float cx = 0.5f * static_cast<float>(view.width);
  const float cy = 0.5f * static_cast<float>(view.height);
  const Vec3 light = Vec3(0.3f, 1.0f, 0.5f).normalized();

  std::vector<Polygon> polygons;
  const physics::World& world = playground.world();
  int colourIndex = 0;
  for (const SceneBody& body : playground.bodies()) {
    const Pose pose = world.pose(body.id);
    const physics::ConvexShape& shape = world.bodyShape(body.id);
    const cv::Scalar base = bodyColour(body, body.isHand || body.isStatic ? 0 : colourIndex++);
    for (const physics::Face& face : shape.faces()) {
      const Vec3 normal = pose.rotate(face.normal);
      const Vec3 onFace =
          pose.transform(shape.vertices()[static_cast<std::size_t>(face.vertices[0])]);
      if (normal.dot(onFace - view.eye) >= 0.0f) continue;  // back face
      // Camera coordinates, clipped against the near plane (Sutherland-Hodgman, one plane).
      std::vector<Vec3> cam, clipped;
      for (int v : face.vertices) {
        const Vec3 rel = pose.transform(shape.vertices()[static_cast<std::size_t>(v)]) - view.eye;
        cam.emplace_back(rel.dot(right), rel.dot(down), rel.dot(forward));
      }
      for (std::size_t i = 0; i < cam.size(); ++i) {
        const Vec3& a = cam[i];
        const Vec3& b = cam[(i + 1) % cam.size()];
        if (a.z() >= kNear) clipped.push_back(a);
        if ((a.z() >= kNear) != (b.z() >= kNear))
          clipped.push_back(a + (b - a) * ((kNear - a.z()) / (b.z() - a.z())));
      }
      if (clipped.size() < 3) continue;
      Polygon poly;
      for (const Vec3& c : clipped) {
        poly.depth += c.z();
        poly.points.emplace_back(static_cast<int>(std::lround(cx + f * c.x() / c.z())),
                                 static_cast<int>(std::lround(cy + f * c.y() / c.z())));
      }
      poly.depth /= static_cast<float>(clipped.size());
      const double shade = 0.45 + 0.55 * static_cast<double>(std::max(0.0f, normal.dot(light)));
      poly.colour = base * shade;
      polygons.push_back(std::move(poly));
    }
  }
  std::stable_sort(polygons.begin(), polygons.end(),
                   [](const Polygon& a, const Polygon& b) { return a.depth > b.depth; });

  cv::Mat image(view.height, view.width, CV_8UC3, cv::Scalar(235, 225, 215));
  for (const Polygon& p : polygons) {
    cv::fillConvexPoly(image, p.points, p.colour, cv::LINE_AA);
    cv::polylines(image, p.points, true, p.colour * 0.8, 1, cv::LINE_AA);
  }
  if (!label.empty())
    cv::putText(image, label, {8, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.6, {40, 40, 40}, 1, cv::LINE_AA);
  try {
    if (!cv::imwrite(path.string(), image)) return Error{path.string() + ": cannot write PNG"};
  } catch (const cv::Exception& e) {
    return Error{path.string() + ": cannot write PNG: " + e.what()};
  }
  return Ok{};
}

}  // namespace dynahand::playground
