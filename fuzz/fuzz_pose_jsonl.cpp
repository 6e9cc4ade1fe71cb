// libFuzzer target: pose sequences as JSON lines (docs/formats/pose.md), read by
// model::loadPoseSequence (a path: the bytes go to a scratch file) for `dynahand play`,
// `track --init` and `synth --pose-file`. It must return a sequence or an Error, never
// crash or hang; a sequence it returns has one finite pose with a unit quaternion per body
// in every frame, and one that names the default hand's bodies converts to finite joint
// angles (what synth and play do with it).
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "dynahand/model_pose.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const dynahand::model::ArticulatedModel hand = dynahand::model::makeDefaultHand();
  const auto file = dynahand::fuzz::scratchFile("poses.jsonl", {data, size});
  const auto sequence = dynahand::model::loadPoseSequence(file);
  if (!sequence) return 0;
  FUZZ_CHECK(!sequence->bodyNames.empty());
  for (const dynahand::model::ModelPose& frame : sequence->frames) {
    FUZZ_CHECK(frame.bodies.size() == sequence->bodyNames.size());
    for (const dynahand::Pose& p : frame.bodies) {
      FUZZ_CHECK(p.p.allFinite());
      FUZZ_CHECK(std::abs(p.q.norm() - 1.0f) < 1e-3f);
    }
  }
  if (!dynahand::model::checkPoseSequence(*sequence, hand)) return 0;
  for (std::size_t f = 0; f < sequence->frames.size() && f < 4; ++f) {
    const auto angles = dynahand::model::jointAngles(hand, sequence->frames[f]);
    FUZZ_CHECK(angles.angles.size() == hand.joints().size());
    for (const dynahand::Vec3& a : angles.angles) FUZZ_CHECK(a.allFinite());
  }
  return 0;
}
