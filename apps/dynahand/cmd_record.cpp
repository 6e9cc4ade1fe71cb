// dynahand record: records a live depth camera to the canonical sequence format
// (docs/formats.md). Ctrl-C stops cleanly: every frame written so far stays readable.
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>

#include "dynahand/camera.h"
#include "dynahand/command.h"
#include "dynahand/sequence.h"

namespace dynahand::cli {
namespace {

volatile std::sig_atomic_t gStopRequested = 0;

extern "C" void requestStop(int /*signal*/) {
  gStopRequested = 1;
}

// Installs the Ctrl-C handler for the duration of a recording, then restores the old one.
class StopOnInterrupt {
 public:
  StopOnInterrupt() {
    gStopRequested = 0;
    previousInt_ = std::signal(SIGINT, requestStop);
    previousTerm_ = std::signal(SIGTERM, requestStop);
  }
  ~StopOnInterrupt() {
    std::signal(SIGINT, previousInt_);
    std::signal(SIGTERM, previousTerm_);
  }
  StopOnInterrupt(const StopOnInterrupt&) = delete;
  StopOnInterrupt& operator=(const StopOnInterrupt&) = delete;
  bool requested() const { return gStopRequested != 0; }

 private:
  void (*previousInt_)(int) = SIG_DFL;
  void (*previousTerm_)(int) = SIG_DFL;
};

struct RecordOptions {
  std::string camera;  // spec, "" = first found
  std::string out;
  int frames = 0;  // 0 = until Ctrl-C
  CameraOptions stream;
};

int record(const RecordOptions& options) {
  auto camera = DepthCamera::open(options.camera, options.stream);
  if (!camera) {
    std::fprintf(stderr, "dynahand record: %s\n", camera.message().c_str());
    return kExitFailure;
  }
  DepthCamera& source = **camera;
  const Intrinsics& k = source.intrinsics();
  auto writer = SequenceWriter::create(options.out, k, source.depthScale(),
                                       static_cast<float>(options.stream.fps));
  if (!writer) {
    std::fprintf(stderr, "dynahand record: %s\n", writer.message().c_str());
    return kExitFailure;
  }
  std::fprintf(stderr, "recording %s (%s, %dx%d) to %s; %s\n", source.info().spec().c_str(),
               source.info().name.c_str(), k.width, k.height, options.out.c_str(),
               options.frames > 0
                   ? ("stops after " + std::to_string(options.frames) + " frames").c_str()
                   : "Ctrl-C stops");
  const StopOnInterrupt interrupt;
  DepthFrame frame;
  int status = kExitOk;
  while (!interrupt.requested() &&
         (options.frames == 0 || writer->framesWritten() < options.frames)) {
    if (auto grabbed = source.grab(frame, 2.0); !grabbed) {
      if (interrupt.requested()) break;  // Ctrl-C during a wait is a stop, not a failure
      std::fprintf(stderr, "dynahand record: %s\n", grabbed.message().c_str());
      status = kExitFailure;
      break;
    }
    if (auto written = writer->write(frame); !written) {
      std::fprintf(stderr, "dynahand record: %s\n", written.message().c_str());
      status = kExitFailure;
      break;
    }
  }
  if (auto closed = writer->close(); !closed) {
    std::fprintf(stderr, "dynahand record: %s\n", closed.message().c_str());
    status = kExitFailure;
  }
  std::fprintf(stderr, "%s: %d frames written to %s\n", interrupt.requested() ? "stopped" : "done",
               writer->framesWritten(), options.out.c_str());
  return status;
}

const CommandRegistration kRecordCommand{Command{
    "record", "record a depth camera to a sequence folder",
    [](CLI::App& sub) -> std::function<int()> {
      auto options = std::make_shared<RecordOptions>();
      sub.add_option("-o,--out", options->out, "new folder for the sequence (camera.json + depth/)")
          ->required();
      sub.add_option("-c,--camera", options->camera,
                     "camera SPEC from 'dynahand cameras' (default: the first camera found)");
      sub.add_option("-n,--frames", options->frames,
                     "stop after this many frames (default: until Ctrl-C)")
          ->check(CLI::NonNegativeNumber);
      sub.add_option("--width", options->stream.width, "requested depth width, pixels")
          ->check(CLI::Range(1, 4096))
          ->capture_default_str();
      sub.add_option("--height", options->stream.height, "requested depth height, pixels")
          ->check(CLI::Range(1, 4096))
          ->capture_default_str();
      sub.add_option("--fps", options->stream.fps, "requested frame rate")
          ->check(CLI::Range(1, 1000))
          ->capture_default_str();
      sub.footer(
          "Writes the canonical sequence format (docs/formats.md); Ctrl-C stops cleanly.\n"
          "Examples:\n"
          "  dynahand record --out takes/pinch\n"
          "  dynahand record --camera openni2:Dummy --frames 30 --out /tmp/dummy");
      return [options] {
        if (std::filesystem::exists(std::filesystem::path(options->out) / "camera.json")) {
          throw UsageError("--out " + options->out +
                           " already holds a sequence; choose a new folder");
        }
        return record(*options);
      };
    }}};

}  // namespace
}  // namespace dynahand::cli
