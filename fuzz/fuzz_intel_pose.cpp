// libFuzzer target: the original authors' .pose files (one frame per line, 7 numbers per
// body), read by model::loadIntelPoses (a path: the bytes go to a scratch file) against a
// 17-body hand, as `synth --pose-file X.pose` does. It must return poses or an Error, never
// crash or hang; every pose it returns has one finite body pose with a unit quaternion per
// model body.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "dynahand/model_intel.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The default hand has the authors' 17 bodies in their order; the conversion only needs
  // each body's hull centroid.
  static const dynahand::model::ArticulatedModel hand = dynahand::model::makeDefaultHand();
  const auto file = dynahand::fuzz::scratchFile("fuzz.pose", {data, size});
  const auto poses = dynahand::model::loadIntelPoses(file, hand);
  if (!poses) return 0;
  FUZZ_CHECK(!poses->empty());
  for (const dynahand::model::ModelPose& pose : *poses) {
    FUZZ_CHECK(pose.bodies.size() == hand.bodies().size());
    for (const dynahand::Pose& p : pose.bodies) {
      FUZZ_CHECK(p.p.allFinite());
      FUZZ_CHECK(std::abs(p.q.norm() - 1.0f) < 1e-3f);
    }
  }
  return 0;
}
