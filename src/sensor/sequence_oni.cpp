// OpenNI .oni recordings through OpenNI2's file driver (built when OpenNI2 was
// found at configure time; otherwise opening an .oni says how to get support).
#include "sensor/frame_source.h"

#ifdef DYNAHAND_HAVE_OPENNI2
#include <OpenNI.h>

#include <mutex>

#include "sensor/camera_backends.h"
#include "sensor/openni2_support.h"
#endif

namespace dynahand::sensor {

#ifdef DYNAHAND_HAVE_OPENNI2
namespace {

// OpenNI's player has one read position per stream: frame(i) reads on when i is the
// next frame and seeks otherwise, under a lock so a const reader stays safe to share.
class OniSource final : public FrameSource {
 public:
  ~OniSource() override {
    stream_.stop();
    stream_.destroy();
    device_.close();
  }

  Status start(const std::filesystem::path& file, SequenceInfo& info) {
    name_ = file.string();
    if (device_.open(name_.c_str()) != openni::STATUS_OK) {
      return Error{name_ + ": not a readable OpenNI recording (" + openniError() + ")"};
    }
    playback_ = device_.getPlaybackControl();
    if (playback_ == nullptr) return Error{name_ + ": OpenNI did not open it as a recording"};
    if (!device_.hasSensor(openni::SENSOR_DEPTH))
      return Error{name_ + ": the recording has no depth stream"};
    if (stream_.create(device_, openni::SENSOR_DEPTH) != openni::STATUS_OK) {
      return Error{name_ + ": cannot create the depth stream (" + openniError() + ")"};
    }
    playback_->setRepeatEnabled(false);
    playback_->setSpeed(-1.0f);  // manual stepping: each read delivers the next frame
    if (stream_.start() != openni::STATUS_OK) {
      return Error{name_ + ": cannot start the depth stream (" + openniError() + ")"};
    }
    const openni::VideoMode mode = stream_.getVideoMode();
    depthScale_ = openniDepthScale(mode.getPixelFormat());
    if (depthScale_ <= 0.0f) return Error{name_ + ": the depth stream does not hold depth pixels"};
    const int frames = playback_->getNumberOfFrames(stream_);
    if (frames < 0) return Error{name_ + ": cannot count the frames (" + openniError() + ")"};
    info.intrinsics = openniIntrinsics(stream_, name_);
    info.depthScale = depthScale_;
    info.frameCount = frames;
    info.framesPerSecond = mode.getFps() > 0 ? static_cast<float>(mode.getFps()) : 30.0f;
    info.format = "oni";
    info.path = file;
    framesPerSecond_ = info.framesPerSecond;
    return Ok{};
  }

  Result<DepthFrame> read(int index) const override {
    const std::lock_guard<std::mutex> lock(mutex_);
    const std::string where = name_ + " frame " + std::to_string(index);
    if (index != nextIndex_ && playback_->seek(stream_, index) != openni::STATUS_OK) {
      nextIndex_ = -1;  // position unknown: seek next time
      return Error{where + ": seek failed (" + openniError() + ")"};
    }
    nextIndex_ = -1;
    openni::VideoStream* streams[] = {&stream_};
    int ready = -1;
    constexpr int kTimeoutMs = 2000;
    if (openni::OpenNI::waitForAnyStream(streams, 1, &ready, kTimeoutMs) != openni::STATUS_OK) {
      return Error{where + ": OpenNI delivered no frame within 2 s (" + openniError() + ")"};
    }
    openni::VideoFrameRef source;
    if (stream_.readFrame(&source) != openni::STATUS_OK) {
      return Error{where + ": read failed (" + openniError() + ")"};
    }
    nextIndex_ = index + 1;
    DepthFrame frame;
    if (auto ok = copyOpenNIFrame(source, depthScale_, frame, where); !ok) return ok.error();
    frame.timestamp = index / static_cast<double>(framesPerSecond_);
    return frame;
  }

 private:
  // OpenNI's stream and playback calls are not const; the lock serialises them.
  mutable std::mutex mutex_;
  mutable openni::Device device_;
  mutable openni::VideoStream stream_;
  openni::PlaybackControl* playback_ = nullptr;  // owned by device_
  mutable int nextIndex_ = 0;  // frame the player delivers without seeking, -1 unknown
  std::string name_;
  float depthScale_ = 0.001f;
  float framesPerSecond_ = 30.0f;
};

}  // namespace

bool oniSupported() {
  return true;
}

Result<OpenedSource> openOni(const std::filesystem::path& file) {
  if (auto ok = initializeOpenNI(); !ok) return Error{file.string() + ": " + ok.message()};
  auto source = std::make_unique<OniSource>();
  OpenedSource opened;
  if (auto ok = source->start(file, opened.info); !ok) return ok.error();
  opened.source = std::move(source);
  return opened;
}

#else

bool oniSupported() {
  return false;
}

Result<OpenedSource> openOni(const std::filesystem::path& file) {
  return Error{file.string() +
               ": this dynahand was built without OpenNI2, so .oni recordings cannot be read "
               "(install libopenni2-dev and reconfigure)"};
}

#endif

}  // namespace dynahand::sensor
