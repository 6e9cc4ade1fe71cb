// The detector's weights: load errors name the file; the shipped weights reproduce the
// figures their model card records.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>

#include <nlohmann/json.hpp>

#include "dynahand/detector.h"
#include "dynahand/detector_data.h"
#include "dynahand/synth_sensor.h"

namespace dynahand::detect {
namespace {

std::filesystem::path shippedDir() {
  return std::filesystem::path(DYNAHAND_SOURCE_DIR) / "models" / "detector";
}

TEST(KeypointDetector, MissingFileIsAnErrorNamingIt) {
  auto d = KeypointDetector::load("/nonexistent/weights.onnx");
  ASSERT_FALSE(d);
  EXPECT_NE(d.message().find("/nonexistent/weights.onnx"), std::string::npos) << d.message();
  EXPECT_NE(d.message().find("not found"), std::string::npos) << d.message();
}

TEST(KeypointDetector, BadFileIsAnErrorNamingIt) {
  const auto file = std::filesystem::temp_directory_path() /
                    ("dynahand-bad-" + std::to_string(::getpid()) + ".onnx");
  std::ofstream(file) << "not a network";
  auto d = KeypointDetector::load(file);
  std::filesystem::remove(file);
  ASSERT_FALSE(d);
  EXPECT_NE(d.message().find(file.string()), std::string::npos) << d.message();
}

TEST(KeypointDetector, ShippedWeightsReproduceTheirModelCard) {
  const auto onnx = shippedDir() / "detector.onnx";
  const auto card = shippedDir() / "detector.json";
  ASSERT_TRUE(std::filesystem::exists(onnx)) << onnx;
  ASSERT_TRUE(std::filesystem::exists(card)) << card;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(card));
  auto detector = KeypointDetector::load(onnx);
  ASSERT_TRUE(detector) << detector.message();
  // The card's figures: `dynahand detector eval` with these arguments.
  const auto& args = j.at("figures").at("eval_args");
  DataOptions o;
  for (std::size_t i = 0; i + 1 < args.size(); i += 2) {
    const std::string key = args[i].get<std::string>(), value = args[i + 1].get<std::string>();
    if (key == "--split") o.split = value == "held-back" ? DataSplit::HeldBack : DataSplit::Train;
    if (key == "--count") o.count = std::stoi(value);
    if (key == "--seed") o.seed = std::stoull(value);
  }
  const DetectorFigures f = evaluateDetector(**detector, o);
  const double mean = j.at("figures").at("mean_mm").get<double>();
  const double p95 = j.at("figures").at("p95_mm").get<double>();
  // Float summation order in OpenCV's kernels differs between CPUs: within 1 %.
  EXPECT_NEAR(f.meanMm, mean, 0.01 * mean);
  EXPECT_NEAR(f.p95Mm, p95, 0.01 * p95);
  EXPECT_EQ(defaultDetectorFile().filename(), "detector.onnx");
}

TEST(KeypointDetector, RunsOnACropIntoTheCameraFrame) {
  auto detector = KeypointDetector::load(shippedDir() / "detector.onnx");
  ASSERT_TRUE(detector) << detector.message();
  DataOptions o;
  o.seed = 11;
  // A few samples: any single one may be a hard view (a fist from the knuckles).
  constexpr int kSamples = 8;
  double sum = 0.0;
  for (int index = 0; index < kSamples; ++index) {
    const DataSample s = makeSample(o, index);
    const Intrinsics k = synth::sensorProfiles()[static_cast<std::size_t>(s.profile)].intrinsics;
    const DetectedKeypoints& d = (*detector)->detect(HandCrop{s.frame, s.pixels}, k);
    ASSERT_TRUE(d.valid);
    for (std::size_t i = 0; i < d.points.size(); ++i) {
      sum += static_cast<double>((d.points[i] - s.keypoints[i]).norm());
      EXPECT_GE(d.confidence[i], 0.0f);
      EXPECT_LE(d.confidence[i], 1.0f);
    }
  }
  const double mean = sum / (21.0 * kSamples);
  std::printf("mean keypoint error over %d samples: %.1f mm\n", kSamples, 1000.0 * mean);
  EXPECT_LT(mean, 0.04);  // m: hands, not noise
}

}  // namespace
}  // namespace dynahand::detect
