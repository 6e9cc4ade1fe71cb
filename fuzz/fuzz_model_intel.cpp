// libFuzzer target: the original authors' hand model (model_hand.json: control cages,
// joints, rest pose) as model::importIntelModel reads it (it only takes a path: the bytes
// go to a scratch file). It must return a model or an Error, never crash or hang; a model
// it returns must be valid (model_checks.h) with one finite rest pose per body.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "dynahand/model_intel.h"
#include "fuzz_util.h"
#include "model_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = dynahand::fuzz::scratchFile("model_hand.json", {data, size});
  const auto intel = dynahand::model::importIntelModel(file);
  if (!intel) return 0;
  dynahand::fuzz::checkModel(intel->model);
  FUZZ_CHECK(intel->restPose.bodies.size() == intel->model.bodies().size());
  for (const dynahand::Pose& p : intel->restPose.bodies) {
    FUZZ_CHECK(p.p.allFinite());
    FUZZ_CHECK(std::abs(p.q.norm() - 1.0f) < 1e-3f);
  }
  return 0;
}
