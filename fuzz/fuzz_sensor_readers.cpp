// libFuzzer target: every reader of untrusted sensor files (PNG depth, NYU PNG,
// camera.json, the authors' NAME.json + NAME.rs, groundtruth.jsonl) must return a
// value or an Error, never crash, hang or read out of bounds. Input layout: fuzz_input.h.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "dynahand/sequence.h"
#include "fuzz_input.h"
#include "sensor/camera_json.h"
#include "sensor/png_depth.h"

namespace {

namespace fs = std::filesystem;
using dynahand::fuzz::FuzzMode;

std::string_view text(std::span<const std::uint8_t> bytes) {
  return {reinterpret_cast<const char*>(bytes.data()), bytes.size()};
}

void writeFile(const fs::path& file, std::span<const std::uint8_t> bytes) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

// A scratch folder per fuzzing process, reused by every input.
const fs::path& scratch() {
  static const fs::path dir = [] {
    fs::path d = fs::temp_directory_path() / ("dynahand-fuzz-" + std::to_string(::getpid()));
    fs::create_directories(d / "seq" / "depth");
    return d;
  }();
  return dir;
}

// Reads every frame the way a caller would, checking the reader's own promises.
void readAll(const dynahand::SequenceReader& reader) {
  const int count = reader.frameCount();
  if (count < 0) std::abort();
  for (int i = 0; i < count && i < 4; ++i) {
    auto frame = reader.frame(i);
    if (frame && !frame->consistent()) std::abort();
    (void)reader.groundTruth(i);
  }
  if (reader.frame(count)) std::abort();  // past the end must be an Error
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto in = dynahand::fuzz::splitFuzzInput({data, size});
  switch (in.mode) {
    case FuzzMode::DepthPng16: {
      auto frame = dynahand::sensor::decodeDepthPng16(in.whole, "fuzz.png");
      if (frame && !frame->consistent()) std::abort();
      break;
    }
    case FuzzMode::NyuPng: {
      auto frame = dynahand::sensor::decodeNyuPng(in.whole, "fuzz.png");
      if (frame && !frame->consistent()) std::abort();
      break;
    }
    case FuzzMode::CameraJson: {
      auto camera = dynahand::sensor::parseCameraJson(text(in.whole), "camera.json");
      if (camera && !camera->intrinsics.valid()) std::abort();
      break;
    }
    case FuzzMode::IntelJson: {
      auto camera = dynahand::sensor::parseIntelCameraJson(text(in.whole), "fuzz.json");
      if (camera && !camera->intrinsics.valid()) std::abort();
      break;
    }
    case FuzzMode::GroundTruthLine:
      (void)dynahand::sensor::parseGroundTruthLine(text(in.whole), "groundtruth.jsonl line 1");
      break;
    case FuzzMode::CanonicalFolder: {
      const fs::path seq = scratch() / "seq";
      writeFile(seq / "camera.json", in.a);
      writeFile(seq / "depth" / "000000.png", in.b);
      if (auto reader = dynahand::SequenceReader::open(seq)) readAll(*reader);
      break;
    }
    case FuzzMode::IntelRecording: {
      writeFile(scratch() / "rec.json", in.a);
      writeFile(scratch() / "rec.rs", in.b);
      if (auto reader = dynahand::SequenceReader::open(scratch() / "rec.rs")) readAll(*reader);
      break;
    }
    case FuzzMode::Count:
      break;
  }
  return 0;
}
