// dynahand synth: writes a synthetic depth sequence with ground truth (docs/synth.md).
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "dynahand/atomic_file.h"
#include "dynahand/command.h"
#include "dynahand/progress.h"
#include "dynahand/synth.h"

namespace dynahand::cli {
namespace {

void listClipsAndProfiles() {
  std::printf("Clips (--motion):\n");
  for (const synth::ClipInfo& c : synth::clips())
    std::printf("  %-17s %4.1f s  %s%s\n", c.name.c_str(), static_cast<double>(c.duration),
                c.description.c_str(), c.handCount == 2 ? " (two hands)" : "");
  std::printf("\nSensor profiles (--profile):\n");
  for (const synth::SensorProfile& p : synth::sensorProfiles())
    std::printf("  %-17s %dx%d, %.2f-%.2f m  %s\n", p.name.c_str(), p.intrinsics.width,
                p.intrinsics.height, static_cast<double>(p.minRange),
                static_cast<double>(p.maxRange), p.device.c_str());
  std::printf("\nDefault clip set: ");
  for (const std::string& name : synth::defaultClipSet()) std::printf("%s ", name.c_str());
  std::printf("\n");
}

// Seeds are unsigned: CLI11 would read -1 as 2^64-1.
const CLI::Validator kNonNegative(
    [](std::string& value) -> std::string {
      if (value.find('-') != std::string::npos)
        return "must be a whole number >= 0 (got " + value + ")";
      return {};
    },
    "", "NONNEGATIVE");

// OUT without a trailing separator (so that OUT.part is its sibling).
std::filesystem::path folderPath(const std::string& out) {
  std::filesystem::path p = std::filesystem::path(out).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  return p;
}

// Moves a finished sequence from `part` into `out` (created if missing): camera.json last, as
// it makes the folder a sequence; `part` is removed once empty.
Status moveInto(const std::filesystem::path& part, const std::filesystem::path& out) {
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) return Error{out.string() + ": cannot create: " + ec.message()};
  std::vector<std::filesystem::path> entries;
  for (const auto& e : std::filesystem::directory_iterator(part, ec))
    if (e.path().filename() != "camera.json") entries.push_back(e.path());
  if (ec) return Error{part.string() + ": " + ec.message()};
  entries.push_back(part / "camera.json");
  for (const auto& e : entries) {
    if (Status s = commitPart(e, out / e.filename()); !s) return s;
  }
  std::filesystem::remove(part, ec);
  return Ok{};
}

// What `dynahand synth` was asked for.
struct SynthFlags {
  synth::SynthOptions options;
  std::string out, contactSheet;
  bool list = false;
  std::string placement = "desk", background = "none", heldObject = "none";
  float proportionSpread = 0.0f;
  std::uint64_t proportionSeed = 1;
  std::vector<float> viewShift;  // pixels: x, y
};

// The command line of `dynahand synth` into `flags`.
void addSynthOptions(CLI::App& sub, const std::shared_ptr<SynthFlags>& flags) {
  synth::SynthOptions& o = flags->options;
  sub.add_option("--motion", o.clip, "clip name (see --list)")->capture_default_str();
  sub.add_option("--pose-file", o.poseFile,
                 "play poses instead of a clip: a pose JSONL (docs/formats/pose.md) or the "
                 "original authors' .pose (e.g. animbank.pose)")
      ->check(CLI::ExistingFile);
  sub.add_option("--pose-start", o.poseStart,
                 "with --pose-file: the first pose played (frame i plays pose N + i, wrapping)")
      ->capture_default_str()
      ->check(kNonNegative);
  sub.add_option("--intel-model", o.intelModelFile,
                 "the authors' model_hand.json for a .pose file (default: beside it)")
      ->check(CLI::ExistingFile);
  sub.add_option("--profile", o.profile,
                 "sensor profile: ideal, tof, structured-light, active-stereo")
      ->capture_default_str();
  sub.add_option("--frames", o.frameCount, "number of frames")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  sub.add_option("--fps", o.framesPerSecond, "frames per second")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1000.0));
  sub.add_option("--speed", o.speed, "clip speed multiplier")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 100.0));
  sub.add_option("--seed", o.seed, "sensor noise seed")->capture_default_str()->check(kNonNegative);
  sub.add_option("--out", flags->out, "output directory (must not hold a sequence)");
  sub.add_option("--placement", flags->placement,
                 "camera placement: desk (facing the user) or head (head-mounted; re-places "
                 "pose files too)")
      ->capture_default_str()
      ->check(CLI::IsMember({"desk", "head"}));
  sub.add_option("--background", flags->background, "background: none, wall or torso")
      ->capture_default_str()
      ->check(CLI::IsMember({"none", "wall", "torso"}));
  sub.add_option("--background-distance", o.scene.backgroundDistance,
                 "background distance behind the hand, m")
      ->capture_default_str()
      ->check(CLI::Range(0.02, 5.0));
  sub.add_flag("--table", o.scene.table, "add a table plane below the hand");
  sub.add_option("--table-drop", o.scene.tableDrop, "distance from the wrist down to the table, m")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 2.0));
  sub.add_flag("--table-below-hand", o.scene.tableBelowHand,
               "lower the table where the motion would take the hand into it (no joint nearer "
               "than 1.5 cm)");
  sub.add_option("--object", flags->heldObject,
                 "an object held against the palm, moving with the hand: none, ball, cylinder "
                 "(rounded ends, across the palm) or box (docs/synth.md)")
      ->capture_default_str()
      ->check(CLI::IsMember({"none", "ball", "cylinder", "box"}));
  sub.add_option("--object-size", o.scene.heldObjectSize,
                 "held object's radius (ball, cylinder) or half-thickness (box), m")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 0.06));
  sub.add_option("--hand-distance", o.scene.handDistance,
                 "camera to hand distance, m (0 = auto per profile)")
      ->capture_default_str();
  sub.add_option("--view-shift", flags->viewShift,
                 "move the scene in the image by DX DY pixels (the principal point moves): a hand "
                 "near a border goes on out of view")
      ->expected(2);
  sub.add_option("--hand-length", o.hand.length, "hand length, wrist crease to middle fingertip, m")
      ->capture_default_str()
      ->check(CLI::Range(0.10, 0.30));
  sub.add_option("--hand-width", o.hand.width, "palm width across the knuckles, m")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 0.13));
  sub.add_option("--proportion-spread", flags->proportionSpread,
                 "hand proportions unlike the tracker's model: each bone length and finger "
                 "and palm thickness factor uniform in [1-F, 1+F] (0 = the model's shape)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.5));
  sub.add_option("--proportion-seed", flags->proportionSeed, "seed of the random hand proportions")
      ->capture_default_str()
      ->check(kNonNegative);
  sub.add_flag("--list", flags->list, "list clips and sensor profiles and exit");
  sub.add_option("--contact-sheet", flags->contactSheet,
                 "write a PNG of every profile x the default clip set (skeleton on top) and exit");
  sub.footer(
      "Examples:\n"
      "  dynahand synth --list\n"
      "  dynahand synth --motion wave --profile tof --frames 300 --out /tmp/wave\n"
      "  dynahand synth --motion two-hands --profile active-stereo --background wall --out "
      "/tmp/two\n"
      "  dynahand synth --motion count --placement head --table --hand-length 0.17 --out "
      "/tmp/count\n"
      "  dynahand synth --motion pinch --proportion-spread 0.15 --proportion-seed 7 --out "
      "/tmp/pinch\n"
      "  dynahand synth --motion grasp-cylinder --object cylinder --out /tmp/grasp\n"
      "  dynahand synth --motion wave --placement head --view-shift 0 -100 --out /tmp/edge\n"
      "  dynahand synth --contact-sheet docs/images/synth_contact_sheet.png\n"
      "Output: camera.json, depth/*.png, groundtruth.jsonl, poses.jsonl, synth.json "
      "(docs/synth.md).");
}

// Lists, writes the contact sheet, or writes the sequence, as the flags ask.
int runSynth(SynthFlags& flags) {
  if (flags.list) {
    listClipsAndProfiles();
    return kExitOk;
  }
  synth::SynthOptions& opts = flags.options;
  opts.scene.placement = flags.placement == "head" ? synth::CameraPlacement::HeadMounted
                                                   : synth::CameraPlacement::DeskFacing;
  const std::map<std::string, synth::Background> backgrounds = {
      {"none", synth::Background::None},
      {"wall", synth::Background::Wall},
      {"torso", synth::Background::Torso}};
  opts.scene.background = backgrounds.at(flags.background);
  const std::map<std::string, synth::HeldObject> objects = {
      {"none", synth::HeldObject::None},
      {"ball", synth::HeldObject::Ball},
      {"cylinder", synth::HeldObject::Cylinder},
      {"box", synth::HeldObject::Box}};
  opts.scene.heldObject = objects.at(flags.heldObject);
  opts.proportions = synth::randomProportions(flags.proportionSeed, flags.proportionSpread);
  if (flags.viewShift.size() == 2)
    opts.scene.viewShift = Vec2(flags.viewShift[0], flags.viewShift[1]);
  if (!flags.contactSheet.empty()) {
    synth::Scene scene = opts.scene;
    if (flags.background == "none") scene.background = synth::Background::Wall;
    if (Status s =
            synth::writeContactSheet(flags.contactSheet, synth::defaultClipSet(), scene, opts.seed);
        !s) {
      std::fprintf(stderr, "dynahand synth: %s\n", s.message().c_str());
      return kExitFailure;
    }
    std::printf("wrote %s\n", flags.contactSheet.c_str());
    return kExitOk;
  }
  if (flags.out.empty()) throw UsageError("--out DIR is required (or --list / --contact-sheet)");
  Result<synth::SyntheticSequence> seq = synth::SyntheticSequence::create(opts);
  if (!seq) throw UsageError(seq.message());
  installInterruptHandler();
  Progress progress("synth", seq->frameCount());
  const auto report = [&progress](int done, int) {
    progress.update(done);
    return !interrupted();
  };
  // Written to OUT.part and moved into OUT at the end (camera.json last): a run that
  // fails part-way leaves OUT.part, never a shorter sequence under OUT.
  const std::filesystem::path out = folderPath(flags.out);
  if (std::filesystem::exists(out / "camera.json") || std::filesystem::exists(out / "depth"))
    throw UsageError(flags.out +
                     ": already holds a sequence (camera.json or depth/); choose a new folder");
  const std::filesystem::path part = partPath(out);
  if (std::filesystem::exists(part) && !std::filesystem::is_empty(part))
    throw UsageError(part.string() +
                     ": left by a synth run that did not finish; delete it or choose "
                     "another --out");
  if (Status s = synth::writeSequence(*seq, part, report); !s) {
    std::fprintf(stderr, "dynahand synth: %s (%s is incomplete; %s not written)\n",
                 s.message().c_str(), part.c_str(), flags.out.c_str());
    return kExitFailure;
  }
  if (Status s = moveInto(part, out); !s) {
    std::fprintf(stderr, "dynahand synth: %s\n", s.message().c_str());
    return kExitFailure;
  }
  progress.finish();
  if (interrupted()) {
    std::fprintf(stderr,
                 "dynahand synth: interrupted; the frames written so far form a valid sequence\n");
    return kExitFailure;
  }
  std::printf("wrote %d frames (%s, %s, %dx%d) to %s\n", seq->frameCount(),
              opts.poseFile.empty() ? opts.clip.c_str() : opts.poseFile.string().c_str(),
              opts.profile.c_str(), seq->intrinsics().width, seq->intrinsics().height,
              flags.out.c_str());
  return kExitOk;
}

const CommandRegistration kSynthCommand{
    Command{"synth", "write a synthetic depth sequence of a moving hand with exact ground truth",
            [](CLI::App& sub) -> std::function<int()> {
              auto flags = std::make_shared<SynthFlags>();
              addSynthOptions(sub, flags);
              return [flags] { return runSynth(*flags); };
            }}};

}  // namespace
}  // namespace dynahand::cli
