// libFuzzer target: every reader of untrusted sensor files (PNG depth, NYU PNG,
// camera.json, the authors' NAME.json + NAME.rs, groundtruth.jsonl) must return a
// value or an Error, never crash, hang or read out of bounds. Input layout: fuzz_input.h.
#include <cstdlib>
#include <filesystem>

#include "dynahand/sequence.h"
#include "fuzz_input.h"
#include "fuzz_util.h"
#include "sensor/camera_json.h"
#include "sensor/png_depth.h"

namespace {

namespace fs = std::filesystem;
using dynahand::fuzz::FuzzMode;
using dynahand::fuzz::scratch;
using dynahand::fuzz::text;
using dynahand::fuzz::writeFile;

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
      static const fs::path seq = [] {
        fs::create_directories(scratch() / "seq" / "depth");
        return scratch() / "seq";
      }();
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
