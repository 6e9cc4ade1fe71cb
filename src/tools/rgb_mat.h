// Internal: an RgbImage seen as an OpenCV 8-bit 3-channel Mat without a copy, so OpenCV can
// draw into it (the pixels stay RGB in memory).
#pragma once

#include <cstdint>

#include <opencv2/core.hpp>

#include "dynahand/tools/overlay.h"

namespace dynahand::eval::detail {

inline cv::Mat wrap(RgbImage& image) {
  return cv::Mat(image.height, image.width, CV_8UC3, image.pixels.data());
}
inline cv::Mat wrap(const RgbImage& image) {
  return cv::Mat(image.height, image.width, CV_8UC3,
                 const_cast<std::uint8_t*>(image.pixels.data()));
}

}  // namespace dynahand::eval::detail
