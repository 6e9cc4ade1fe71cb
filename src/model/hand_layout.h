// Internal: the hand keypoint layouts (MediaPipe 21, OpenXR 26) resolved on a model's named
// keypoints when it is built.
#pragma once

#include <array>
#include <vector>

#include "dynahand/model.h"

namespace dynahand::model::detail {

// Sets has21 and the indices into keypoints of the 21 MediaPipe names when all are present.
void resolveHandLayout(const std::vector<Keypoint>& keypoints, bool& has21,
                       std::array<int, 21>& indices21);

// The 26 OpenXR joints as frames fixed on bodies, from the keypoints in the model's zero
// pose. False when palm_center or a finger *_cmc keypoint is missing.
bool computeOpenXrFrames(const ArticulatedModel& model, std::array<BodyFrame, 26>& frames);

}  // namespace dynahand::model::detail
