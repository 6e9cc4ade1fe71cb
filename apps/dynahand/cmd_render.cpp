// dynahand render: pictures of tracked poses over the depth they were tracked in - the
// depth image with the winning simulation's model shaded over it and the losing candidate
// simulations faint behind it (as in the paper's figure), beside a side view of the points
// and the model. PNG frames, an MP4, and/or a contact sheet.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <optional>

#include "dynahand/atomic_file.h"
#include "dynahand/command.h"
#include "dynahand/model.h"
#include "dynahand/progress.h"
#include "dynahand/sequence.h"
#include "dynahand/tools/overlay.h"
#include "dynahand/track_io.h"

#ifdef DYNAHAND_HAVE_VIDEOIO
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <opencv2/videoio/registry.hpp>
#endif

namespace dynahand::cli {
namespace {

struct RenderOptions {
  std::string poses, input, out, sheet;
  HandModelOptions hand;  // as given to track
  float sideAngleDeg = 90.0f, fps = 0.0f;
  int every = 1, sheetTiles = 12, sheetColumns = 4;
  bool candidates = true;
};

// Colours: the turbo depth map never has red and blue both high, so the winner's magenta
// stays readable over it (and tests can find it); the candidates are faint white.
constexpr eval::Rgb kWinnerColour{240, 90, 250};
constexpr eval::Rgb kCandidateColour{235, 235, 235};
constexpr float kWinnerOpacity = 0.7f, kCandidateOpacity = 0.22f;

Vec3 centreOf(const model::ModelPose& pose) {
  Vec3 sum = Vec3::Zero();
  for (const Pose& b : pose.bodies) sum += b.p;
  return sum / static_cast<float>(std::max<std::size_t>(1, pose.bodies.size()));
}

// Writes PNG frames to a folder or an MP4/AVI through OpenCV's video writer. A video goes to
// NAME.part.EXT (the extension picks the codec) and is renamed to NAME by finish(); a run that
// fails before deletes it, so no partial video is left under NAME.
class FrameSink {
 public:
  FrameSink(const std::filesystem::path& out, float fps) : out_(out), fps_(fps) {
    const std::string ext = out.extension().string();
    video_ = ext == ".mp4" || ext == ".avi";
#ifndef DYNAHAND_HAVE_VIDEOIO
    if (video_) {
      throw UsageError(out.string() +
                       ": this build has no OpenCV video writer (install libopencv-videoio-dev "
                       "and rebuild); write PNG frames to a folder instead");
    }
#endif
    if (!video_) {
      std::error_code ec;
      std::filesystem::create_directories(out, ec);
      if (ec) throw std::runtime_error(out.string() + ": " + ec.message());
    } else if (out.has_parent_path()) {
      std::error_code ec;
      std::filesystem::create_directories(out.parent_path(), ec);
    }
  }
  FrameSink(const FrameSink&) = delete;
  FrameSink& operator=(const FrameSink&) = delete;
  ~FrameSink() {
#ifdef DYNAHAND_HAVE_VIDEOIO
    if (video_ && !finished_) {
      writer_.release();
      std::error_code ec;
      std::filesystem::remove(part(), ec);
    }
#endif
  }
  std::filesystem::path part() const {
    return partPath(out_, true);
  }
  void write(const eval::RgbImage& image, int frame) {
    if (!video_) {
      char name[32];
      std::snprintf(name, sizeof name, "frame_%06d.png", frame);
      const Status s = image.savePng(out_ / name);
      if (!s) throw std::runtime_error(s.message());
      ++written_;
      return;
    }
#ifdef DYNAHAND_HAVE_VIDEOIO
    if (!writer_.isOpened()) {
      const int fourcc = out_.extension() == ".avi" ? cv::VideoWriter::fourcc('M', 'J', 'P', 'G')
                                                    : cv::VideoWriter::fourcc('m', 'p', '4', 'v');
      writer_.open(part().string(), fourcc, fps_, cv::Size(image.width, image.height));
      if (!writer_.isOpened()) {
        throw std::runtime_error(out_.string() + ": OpenCV could not open a video writer");
      }
    }
    cv::Mat rgb(image.height, image.width, CV_8UC3, const_cast<std::uint8_t*>(image.pixels.data()));
    cv::Mat bgr;
    cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
    writer_.write(bgr);
    ++written_;
#endif
  }
  // A video: closes it, checks that it reads back whole (OpenCV's writer reports no write
  // errors, e.g. on a full disk) and renames it to its name. PNG frames: nothing to do.
  void finish() {
#ifdef DYNAHAND_HAVE_VIDEOIO
    if (!video_ || finished_) return;
    finished_ = true;
    if (written_ == 0) return;
    writer_.release();
    std::error_code ec;
    const auto size = std::filesystem::file_size(part(), ec);
    bool whole = !ec && size > 0;
    if (whole && cv::videoio_registry::hasBackend(cv::CAP_FFMPEG)) {
      cv::VideoCapture check(part().string(), cv::CAP_FFMPEG);
      whole =
          check.isOpened() && check.get(cv::CAP_PROP_FRAME_COUNT) >= static_cast<double>(written_);
    }
    if (!whole) {
      std::filesystem::remove(part(), ec);
      throw std::runtime_error(out_.string() +
                               ": the video could not be written in full (disk full?)");
    }
    const Status s = commitPart(part(), out_);
    if (!s) throw std::runtime_error(s.message());
#endif
  }
  int written() const {
    return written_;
  }

 private:
  std::filesystem::path out_;
  float fps_;
  bool video_ = false;
  bool finished_ = false;
  int written_ = 0;
#ifdef DYNAHAND_HAVE_VIDEOIO
  cv::VideoWriter writer_;
#endif
};

struct Panels {
  eval::RgbImage front, side;
  std::vector<Vec3> handPoints;  // body positions of the drawn hands (camera frame)
};

Panels drawFrame(const DepthFrame& depth, const Intrinsics& camera, const io::TrackedFrame& frame,
                 const model::ArticulatedModel& right, const model::ArticulatedModel& left,
                 const RenderOptions& o, Vec3& target) {
  for (const auto& hand : frame.hands) {
    if (hand.tracked && !hand.pose.bodies.empty()) {
      target = centreOf(hand.pose);
      break;
    }
  }
  const float nearM = target.z() - 0.12f, farM = target.z() + 0.20f;
  const eval::View front{camera, Pose::identity()};
  const eval::View side =
      eval::orbitView(camera, target, o.sideAngleDeg * std::numbers::pi_v<float> / 180.0f);
  Panels p;
  p.front = eval::shadeDepth(depth, nearM, farM);
  p.side = eval::shadePointsFromView(depth, camera, side, nearM, farM, target, 0.30f);
  for (const auto& hand : frame.hands) {
    const model::ArticulatedModel& m = hand.side == model::Side::Left ? left : right;
    if (o.candidates) {
      for (const auto& c : hand.candidates) {
        if (c.simulation == hand.simulation || c.pose.bodies.empty()) continue;
        eval::drawShadedModel(p.front, front, m, c.pose, kCandidateColour, kCandidateOpacity);
        eval::drawShadedModel(p.side, side, m, c.pose, kCandidateColour, kCandidateOpacity);
      }
    }
    if (!hand.tracked || hand.pose.bodies.empty()) continue;
    eval::drawShadedModel(p.front, front, m, hand.pose, kWinnerColour, kWinnerOpacity);
    eval::drawShadedModel(p.side, side, m, hand.pose, kWinnerColour, kWinnerOpacity);
    for (const Pose& b : hand.pose.bodies) p.handPoints.push_back(b.p);
  }
  char label[128];
  const auto* first = frame.hands.empty() ? nullptr : &frame.hands.front();
  if (first != nullptr && first->tracked) {
    std::snprintf(label, sizeof label, "frame %d  %s  error %.0f mm", frame.frame,
                  first->simulation.c_str(), 1000.0 * static_cast<double>(first->error));
  } else {
    std::snprintf(label, sizeof label, "frame %d  lost", frame.frame);
  }
  eval::drawLabel(p.front, label);
  eval::drawLabel(p.side, "side view");
  return p;
}

int runRender(const RenderOptions& o) {
  if (o.out.empty() && o.sheet.empty()) throw UsageError("give --out and/or --sheet");
  for (const auto* path : {&o.poses, &o.input}) {
    if (!std::filesystem::exists(*path)) throw UsageError("input not found: " + *path);
  }
  auto reader = SequenceReader::open(o.input);
  if (!reader) throw UsageError(reader.message());
  const SequenceInfo& info = reader->info();
  model::ArticulatedModel right = handModel(o.hand);
  auto frames = io::readTrackJsonl(o.poses, right);
  if (!frames) throw UsageError(frames.message());
  // The built-in hand at the size and metacarpals the poses were tracked with (given or
  // estimated, written by track), unless a model is given here; a size given here replaces the
  // recorded one.
  const auto& trackedSize = frames->front().handSize;
  if (trackedSize && o.hand.modelFile.empty()) {
    model::HandDimensions size = trackedSize->dimensions;
    if (o.hand.lengthGiven()) size.length = o.hand.length;
    if (o.hand.widthGiven()) size.width = o.hand.width;
    right = model::makeDefaultHand(size, model::Side::Right, trackedSize->shape());
  }
  const model::ArticulatedModel left = model::mirrorModel(right);

  std::vector<const io::TrackedFrame*> chosen;
  for (std::size_t i = 0; i < frames->size(); i += static_cast<std::size_t>(o.every)) {
    const io::TrackedFrame& f = (*frames)[i];
    if (f.frame < 0 || f.frame >= info.frameCount) {
      throw UsageError(o.poses + ": frame " + std::to_string(f.frame) + " is not in " + o.input +
                       " (" + std::to_string(info.frameCount) + " frames)");
    }
    chosen.push_back(&f);
  }
  // Sheet tiles: evenly spaced over the frames drawn.
  std::vector<std::size_t> sheetAt;
  if (!o.sheet.empty()) {
    const std::size_t n =
        std::min<std::size_t>(static_cast<std::size_t>(o.sheetTiles), chosen.size());
    for (std::size_t t = 0; t < n; ++t) sheetAt.push_back((2 * t + 1) * chosen.size() / (2 * n));
  }

  std::optional<FrameSink> sink;
  if (!o.out.empty()) sink.emplace(o.out, o.fps > 0 ? o.fps : info.framesPerSecond);
  installInterruptHandler();
  Progress progress("render", static_cast<int>(chosen.size()));
  std::vector<eval::RgbImage> tiles;
  Vec3 target(0.0f, 0.0f, 0.5f);  // until a hand is seen
  int done = 0;
  for (std::size_t i = 0; i < chosen.size() && !interrupted(); ++i) {
    auto depth = reader->frame(chosen[i]->frame);
    if (!depth) throw UsageError(depth.message());  // bad input: the partial video is deleted
    Panels p = drawFrame(*depth, info.intrinsics, *chosen[i], right, left, o, target);
    if (sink) sink->write(eval::besideEachOther({p.front, p.side}), chosen[i]->frame);
    if (std::find(sheetAt.begin(), sheetAt.end(), i) != sheetAt.end()) {
      // Cropped around the hand, which is small in a 640x480 view of real data.
      std::vector<Vec3> around = p.handPoints;
      if (around.empty()) around.push_back(target);
      const eval::View side = eval::orbitView(info.intrinsics, target,
                                              o.sideAngleDeg * std::numbers::pi_v<float> / 180.0f);
      std::vector<Vec3> aroundSide;
      for (const Vec3& q : around) aroundSide.push_back(side.fromCamera.transform(q));
      tiles.push_back(eval::besideEachOther(
          {eval::cropAround(p.front, info.intrinsics, around, 30, 240, 240),
           eval::cropAround(p.side, info.intrinsics, aroundSide, 30, 240, 240)}));
      const auto* hand = chosen[i]->hands.empty() ? nullptr : &chosen[i]->hands.front();
      char label[96];
      std::snprintf(label, sizeof label, "frame %d %s", chosen[i]->frame,
                    hand != nullptr && hand->tracked ? hand->simulation.c_str() : "lost");
      eval::drawLabel(tiles.back(), label);
    }
    progress.update(++done);
  }
  progress.finish(interrupted() ? "(interrupted: frames up to here are written)" : "");
  if (sink) sink->finish();
  if (sink) std::printf("wrote %d frames to %s\n", sink->written(), o.out.c_str());
  if (!o.sheet.empty()) {
    const Status s = eval::contactSheet(tiles, o.sheetColumns).savePng(o.sheet);
    if (!s) throw std::runtime_error(s.message());
    std::printf("wrote %s (%zu tiles)\n", o.sheet.c_str(), tiles.size());
  }
  return interrupted() ? 130 : kExitOk;
}

const CommandRegistration kRenderCommand{Command{
    "render", "draw tracked poses over their depth frames (PNG frames, MP4, contact sheet)",
    [](CLI::App& sub) -> std::function<int()> {
      auto o = std::make_shared<RenderOptions>();
      sub.add_option("poses", o->poses, "poses from 'dynahand track' (.jsonl)")->required();
      sub.add_option("input", o->input, "the recording they were tracked from")->required();
      sub.add_option("-o,--out", o->out, "a folder for PNG frames, or a video (.mp4, .avi)");
      sub.add_option("--sheet", o->sheet, "also write a contact sheet PNG of evenly spaced frames");
      sub.add_option("--sheet-tiles", o->sheetTiles, "frames on the contact sheet")
          ->check(CLI::Range(1, 200));
      sub.add_option("--sheet-columns", o->sheetColumns, "contact sheet columns")
          ->check(CLI::Range(1, 20));
      sub.add_option("--every", o->every, "draw every Nth tracked frame")
          ->check(CLI::Range(1, 100000));
      sub.add_option("--fps", o->fps, "video frame rate (default: the recording's)")
          ->check(CLI::Range(1.0f, 240.0f));
      sub.add_option("--side-angle", o->sideAngleDeg,
                     "side view: degrees around the hand about the image's vertical axis")
          ->check(CLI::Range(-180.0f, 180.0f));
      addHandModelOptions(sub, o->hand);  // the model the poses were tracked with
      sub.add_flag("!--no-candidates", o->candidates, "leave out the losing simulations");
      sub.footer(
          "The losing simulations are drawn when the poses were tracked with --candidates.\n"
          "The hand is the built-in one at the size and metacarpals track recorded in the poses\n"
          "(given or --hand-size auto) unless --model, --hand-length or --hand-width says\n"
          "otherwise (a size given here keeps the recorded metacarpals).\n"
          "Examples:\n"
          "  dynahand track clip/ --candidates --out poses.jsonl\n"
          "  dynahand render poses.jsonl clip/ --out frames/\n"
          "  dynahand render poses.jsonl clip/ --out tracked.mp4 --sheet sheet.png");
      return [o] { return runRender(*o); };
    }}};

}  // namespace
}  // namespace dynahand::cli
