// Writes the fuzzer's seed corpus: one valid input per FuzzMode plus a few
// near-misses, so fuzzing starts inside each reader instead of at its first check.
// Usage: make_sensor_seeds OUTPUT_DIR
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "dynahand/sequence.h"
#include "fuzz_input.h"
#include "sensor/camera_json.h"
#include "sensor/png_depth.h"

namespace {

using dynahand::fuzz::FuzzMode;

std::span<const std::uint8_t> bytesOf(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

void save(const std::filesystem::path& dir, const std::string& name,
          const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(dir / name, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_sensor_seeds OUTPUT_DIR\n");
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::filesystem::create_directories(dir);

  dynahand::DepthFrame frame(8, 6, 0.001f);
  for (int i = 0; i < 48; ++i)
    frame.depth[static_cast<std::size_t>(i)] = static_cast<std::uint16_t>(i * 1000);
  const std::vector<std::uint8_t> png16 = *dynahand::sensor::encodeDepthPng16(frame);
  cv::Mat rgb(6, 8, CV_8UC3, cv::Scalar(10, 3, 0));
  std::vector<std::uint8_t> png8;
  cv::imencode(".png", rgb, png8);

  const std::string cameraJson =
      dynahand::sensor::formatCameraJson({{8, 6, 5.0f, 5.0f, 3.5f, 2.5f}, 0.001f, 30.0f});
  const std::string intelJson =
      R"({"camtype":"ivycam","dcamera":{"depth_scale":0.000125,"dims":[8,6],"focal":[5,5],"principal":[3.5,2.5]}})";
  std::optional<dynahand::Keypoints21> keypoints = dynahand::Keypoints21{};
  for (auto& p : *keypoints) p = dynahand::Vec3(0.01f, -0.02f, 0.4f);
  const std::string truthLine = dynahand::sensor::formatGroundTruthLine(3, keypoints);
  std::vector<std::uint8_t> raw(8 * 6 * 2 * 2, 7);

  using dynahand::fuzz::joinFuzzInput;
  using dynahand::fuzz::singleFuzzInput;
  save(dir, "png16", singleFuzzInput(FuzzMode::DepthPng16, png16));
  save(dir, "png16-as-nyu", singleFuzzInput(FuzzMode::NyuPng, png16));
  save(dir, "nyu", singleFuzzInput(FuzzMode::NyuPng, png8));
  save(dir, "nyu-as-png16", singleFuzzInput(FuzzMode::DepthPng16, png8));
  save(dir, "camera-json", singleFuzzInput(FuzzMode::CameraJson, bytesOf(cameraJson)));
  save(dir, "intel-json", singleFuzzInput(FuzzMode::IntelJson, bytesOf(intelJson)));
  save(dir, "truth-line", singleFuzzInput(FuzzMode::GroundTruthLine, bytesOf(truthLine)));
  save(dir, "truth-null",
       singleFuzzInput(FuzzMode::GroundTruthLine, bytesOf("{\"frame\":0,\"keypoints21\":null}")));
  save(dir, "canonical", joinFuzzInput(FuzzMode::CanonicalFolder, bytesOf(cameraJson), png16));
  save(dir, "intel-rs", joinFuzzInput(FuzzMode::IntelRecording, bytesOf(intelJson), raw));
  std::printf("make_sensor_seeds: wrote 10 seeds to %s\n", dir.c_str());
  return 0;
}
