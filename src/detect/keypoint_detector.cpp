// KeypointDetector: the ONNX network run through OpenCV's DNN module on one thread.
#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>

#include <algorithm>
#include <cstdlib>
#include <mutex>
#include <string>

#include "dynahand/detector.h"

namespace dynahand::detect {

namespace {
constexpr int kOutputCount = kKeypointCount * 4;  // 63 uvd values, then 21 confidences
}  // namespace

struct KeypointDetector::Impl {
  std::filesystem::path file;
  cv::dnn::Net net;
  cv::Mat input;   // 1 x 1 x kCropPixels x kCropPixels, float
  cv::Mat output;  // 1 x kOutputCount
  DetectedKeypoints result;
};

KeypointDetector::KeypointDetector(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
KeypointDetector::~KeypointDetector() = default;

Result<std::unique_ptr<KeypointDetector>> KeypointDetector::load(
    const std::filesystem::path& onnxFile) {
  const std::string name = onnxFile.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(onnxFile, ec))
    return Error{name + ": detector weights not found (an ONNX file; see docs/detector.md)"};
  // One thread, as the rest of the tracker: OpenCV would spread this small network over
  // every core for little gain, and trackers on several threads (bench items, hand-size
  // candidates) would oversubscribe them. OpenCV's thread count is process-wide: set once,
  // before the first network runs (changing it while other threads run OpenCV code crashes).
  static std::once_flag oneThread;
  std::call_once(oneThread, [] { cv::setNumThreads(1); });
  auto impl = std::make_unique<Impl>();
  impl->file = onnxFile;
  try {
    impl->net = cv::dnn::readNetFromONNX(name);
  } catch (const cv::Exception& e) {
    return Error{name + ": not a detector ONNX file OpenCV can read: " + e.msg};
  }
  if (impl->net.empty()) return Error{name + ": not a detector ONNX file (empty network)"};
  impl->net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  impl->net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  const int shape[4] = {1, 1, kCropPixels, kCropPixels};
  impl->input.create(4, shape, CV_32F);
  impl->input.setTo(1.0f);
  try {
    impl->net.setInput(impl->input);
    impl->output = impl->net.forward();
  } catch (const cv::Exception& e) {
    return Error{name + ": the network does not run on a 1x1x64x64 crop: " + e.msg};
  }
  if (impl->output.total() != static_cast<std::size_t>(kOutputCount))
    return Error{name + ": the network returns " + std::to_string(impl->output.total()) +
                 " values, the detector needs " + std::to_string(kOutputCount)};
  return std::unique_ptr<KeypointDetector>(new KeypointDetector(std::move(impl)));
}

std::span<const float> KeypointDetector::run(std::span<const float> pixels) {
  Impl& m = *impl_;
  std::copy(pixels.begin(), pixels.end(), m.input.ptr<float>());
  m.net.setInput(m.input);
  m.net.forward(m.output);
  return {m.output.ptr<float>(), static_cast<std::size_t>(kOutputCount)};
}

const DetectedKeypoints& KeypointDetector::detect(const HandCrop& crop,
                                                  const Intrinsics& intrinsics) {
  DetectedKeypoints& r = impl_->result;
  const std::span<const float> out = run(crop.pixels);
  float sum = 0.0f;
  for (int i = 0; i < kKeypointCount; ++i) {
    const Vec3 uvd(out[static_cast<std::size_t>(3 * i)], out[static_cast<std::size_t>(3 * i + 1)],
                   out[static_cast<std::size_t>(3 * i + 2)]);
    r.points[static_cast<std::size_t>(i)] = crop.frame.toCamera(intrinsics, uvd);
    const float c = std::clamp(out[static_cast<std::size_t>(3 * kKeypointCount + i)], 0.0f, 1.0f);
    r.confidence[static_cast<std::size_t>(i)] = c;
    sum += c;
  }
  r.meanConfidence = sum / static_cast<float>(kKeypointCount);
  r.valid = true;
  return r;
}

const std::filesystem::path& KeypointDetector::file() const {
  return impl_->file;
}

std::filesystem::path defaultDetectorFile() {
  if (const char* env = std::getenv("DYNAHAND_DETECTOR"); env != nullptr && *env != '\0')
    return env;
  std::error_code ec;
  for (const char* root : {DYNAHAND_SOURCE_MODELS_DIR, DYNAHAND_INSTALL_MODELS_DIR}) {
    const std::filesystem::path file = std::filesystem::path(root) / "detector" / "detector.onnx";
    if (std::filesystem::is_regular_file(file, ec)) return file;
  }
  return {};
}

}  // namespace dynahand::detect
