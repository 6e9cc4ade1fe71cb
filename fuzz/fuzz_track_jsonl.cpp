// libFuzzer target: tracked poses as JSON lines (docs/formats/tracked-poses.md) and
// 21-keypoint ground truth lines, the files `dynahand eval`, `render` and `play` read back:
// io::readTrackJsonl (render) and eval::readKeypointsJsonl for both hands (eval --pred and
// --gt) on the same bytes (scratch file). They must return frames or an Error, never crash
// or hang; what they return must be usable as is: finite keypoints and body poses with
// unit quaternions, one per model body, and a hand size the default hand can be built at
// (render does).
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "dynahand/keypoint_io.h"
#include "dynahand/track_io.h"
#include "fuzz_util.h"

namespace {

void checkPose(const dynahand::model::ModelPose& pose, std::size_t bodies) {
  FUZZ_CHECK(pose.bodies.empty() || pose.bodies.size() == bodies);
  for (const dynahand::Pose& p : pose.bodies) {
    FUZZ_CHECK(p.p.allFinite());
    FUZZ_CHECK(std::abs(p.q.norm() - 1.0f) < 1e-3f);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const dynahand::model::ArticulatedModel hand = dynahand::model::makeDefaultHand();
  const auto file = dynahand::fuzz::scratchFile("track.jsonl", {data, size});

  if (const auto frames = dynahand::io::readTrackJsonl(file, hand)) {
    FUZZ_CHECK(!frames->empty());
    for (const dynahand::io::TrackedFrame& frame : *frames) {
      for (const dynahand::io::TrackedHand& h : frame.hands) {
        checkPose(h.pose, hand.bodies().size());
        if (h.tracked) {
          for (const dynahand::Vec3& k : h.keypoints21) FUZZ_CHECK(k.allFinite());
        }
        for (const dynahand::io::TrackedCandidate& c : h.candidates)
          checkPose(c.pose, hand.bodies().size());
      }
    }
    // render: the default hand at the size the poses were tracked with.
    if (const auto& handSize = frames->front().handSize) {
      const auto sized = dynahand::model::makeDefaultHand(handSize->dimensions);
      FUZZ_CHECK(sized.bodyCount() == hand.bodyCount());
      for (const dynahand::model::Body& b : sized.bodies())
        FUZZ_CHECK(std::isfinite(b.mass) && b.mass > 0.0f);
    }
  }

  for (const char* side : {"right", "left"}) {
    const auto keypoints = dynahand::eval::readKeypointsJsonl(file, side);
    if (!keypoints) continue;
    for (const auto& frame : keypoints->frames) {
      if (!frame) continue;
      for (const dynahand::Vec3& k : *frame) FUZZ_CHECK(k.allFinite());
    }
  }
  return 0;
}
