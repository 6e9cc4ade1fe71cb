// Free-space pull for fingertips (beyond the paper). A model fingertip whose pixel shows
// background farther than it (or no data) sits where the camera sees empty space: no sample
// is there to pull it back, and the paper's metric only scores it (errOcc). Such a tip gets
// a push-only row towards the nearest segmented pixel, in the plane of constant depth, so a
// finger a few millimetres too long or beside the real one is drawn onto the hand.
#pragma once

#include <optional>

#include "dynahand/cloud.h"

namespace dynahand::track {

struct SilhouettePull {
  Vec3 target = Vec3::Zero();  // the nearest segmented pixel lifted to the point's depth, m
  Vec3 inward = Vec3::Zero();  // unit, from the point towards the target
};

// nullopt when the point projects within tolerancePixels of the segmentation mask, onto a
// pixel whose depth is nearer than the point (it may be hidden there), outside the image,
// or when no segmented pixel lies within maxPixels.
std::optional<SilhouettePull> silhouettePull(const CloudFrame& cloud, const Vec3& point,
                                             int tolerancePixels, int maxPixels);

}  // namespace dynahand::track
