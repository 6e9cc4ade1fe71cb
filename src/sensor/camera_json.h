// Camera descriptions in JSON: dynahand's camera.json and the original authors'
// NAME.json. Parsers take the text plus the file name used in error messages.
#pragma once

#include <string>
#include <string_view>

#include "dynahand/core.h"
#include "dynahand/depth_frame.h"
#include "dynahand/sequence.h"

namespace dynahand::sensor {

struct CameraDescription {
  Intrinsics intrinsics;
  float depthScale = 0.001f;      // metres per stored unit
  float framesPerSecond = 30.0f;  // optional "fps" key
  float minRangeM = 0.0f;         // optional "min_range_m" key: the near range; 0 = not known
};

// {"version":1,"width":W,"height":H,"fx":..,"fy":..,"cx":..,"cy":..,"depth_scale":s[,"fps":f]
//  [,"min_range_m":r]}
Result<CameraDescription> parseCameraJson(std::string_view text, const std::string& name);
std::string formatCameraJson(const CameraDescription& camera);

// {"dcamera":{"depth_scale":s,"dims":[w,h],"focal":[fx,fy],"principal":[cx,cy]},...}
Result<CameraDescription> parseIntelCameraJson(std::string_view text, const std::string& name);

// One groundtruth.jsonl line: {"frame":i,"keypoints21":[[x,y,z] x 21] | null}.
struct GroundTruthLine {
  int frame = 0;
  std::optional<Keypoints21> keypoints;
};
Result<GroundTruthLine> parseGroundTruthLine(std::string_view line, const std::string& where);
std::string formatGroundTruthLine(int frame, const std::optional<Keypoints21>& keypoints);

// Checks a depth scale read from a file (finite, positive, at most 1 m per unit).
Status checkDepthScale(double scale, const std::string& name);

}  // namespace dynahand::sensor
