// The JSON messages of the viewer stream (docs/formats/viewer-stream.md, version 1).
// Built here, sent by ViewerServer. Everything in metres, unit quaternions (w, x, y, z),
// camera frame (x right, y down, z forward) unless a scene message says otherwise.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "dynahand/convex_shape.h"
#include "dynahand/depth_frame.h"
#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "dynahand/tracker.h"

namespace dynahand::viewer {

inline constexpr int kStreamFormatVersion = 1;

// "hello": sent once to each client on connect. Carries every body's hull (vertices and
// polygon faces, body frame) so frames only need poses.
struct HelloInfo {
  std::string source;  // what is being tracked, e.g. "synth:wave" or a folder
  float framesPerSecond = 30.0f;
  int frameCount = 0;  // frames per loop; 0 = live (a camera)
  Intrinsics intrinsics;
  bool groundTruth = false;                            // frames carry "truth"
  std::vector<const model::ArticulatedModel*> models;  // one per hand, right first
};
std::string helloMessage(const HelloInfo& info);

// Ground truth of one hand (synthetic sequences; recordings may have keypoints only).
struct TruthHand {
  model::Side side = model::Side::Right;
  std::optional<track::Keypoints21> keypoints;
  model::ModelPose pose;  // empty when unknown
};

struct FrameInfo {
  int index = 0;             // frame of the source
  int loop = 0;              // how many times the source wrapped around
  double trackingFps = 0.0;  // frames tracked per second, measured over the last second
  bool paused = false;
  const track::TrackResult* result = nullptr;      // required
  const model::ArticulatedModel* model = nullptr;  // required (body names)
  const DepthFrame* depth = nullptr;               // optional: the scene cloud
  const Intrinsics* intrinsics = nullptr;          // required with depth
  const std::vector<Vec3>* samples = nullptr;      // optional: the tracker's points
  std::vector<TruthHand> truth;
  int maxCloudPoints = 3000;  // the scene cloud is subsampled on a pixel grid to fit
  int maxSamplePoints = 1500;
};
// "frame": {"type":"frame",...,"track":<the same object as a line of `track --out`>,...}
std::string frameMessage(const FrameInfo& info);

// ---- The playground (dynahand play) ----

struct SceneBody {
  std::string name;
  const physics::ConvexShape* shape = nullptr;  // hull in the body frame
  std::string color;                            // "#rrggbb"; empty = the page's default
};
// "scene": the bodies of a physics scene, once (as a welcome message). up: which world
// axis points up: "-y" (camera frame, the default), "y" or "z".
std::string sceneMessage(const std::vector<SceneBody>& bodies, const std::string& up = "-y");
// "scene_poses": the pose of every scene body (same order as the "scene" message).
std::string scenePosesMessage(int step, double timeS, const std::vector<Pose>& poses);

}  // namespace dynahand::viewer
