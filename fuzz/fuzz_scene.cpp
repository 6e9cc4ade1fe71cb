// libFuzzer target: playground scene files (docs/formats/scene.md) as `dynahand play` takes
// them: playground::parseScene from memory, then, for a scene it accepts, the playground
// built from it (Playground::create with the default hand) and one input frame simulated
// with the hand lost. Nothing may crash or hang; an accepted scene keeps the reader's
// promises (finite values, positive sizes, unique names).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "dynahand/playground.h"
#include "fuzz_util.h"

namespace {

using dynahand::playground::ObjectSpec;
using dynahand::playground::SceneSpec;

void checkScene(const SceneSpec& s) {
  FUZZ_CHECK(s.gravity.allFinite());
  FUZZ_CHECK(s.camera.p.allFinite() && std::abs(s.camera.q.norm() - 1.0f) < 1e-3f);
  FUZZ_CHECK(std::isfinite(s.stepDt) && s.stepDt > 0.0f);
  FUZZ_CHECK(std::isfinite(s.friction) && s.friction >= 0.0f);
  for (std::size_t i = 0; i < s.objects.size(); ++i) {
    const ObjectSpec& o = s.objects[i];
    FUZZ_CHECK(!o.name.empty() && o.name.find('/') == std::string::npos);
    for (std::size_t k = 0; k < i; ++k) FUZZ_CHECK(s.objects[k].name != o.name);
    FUZZ_CHECK(o.position.allFinite() && std::abs(o.orientation.norm() - 1.0f) < 1e-3f);
    FUZZ_CHECK(o.mass > 0.0f && o.radius > 0.0f && o.length > 0.0f);
    FUZZ_CHECK(o.capRadius > 0.0f && o.capLength > 0.0f && o.size.minCoeff() > 0.0f);
    FUZZ_CHECK(std::abs(o.axis.norm() - 1.0f) < 1e-3f);
    FUZZ_CHECK(o.lowerLimit <= o.upperLimit);
    FUZZ_CHECK(o.links >= 1 && o.links <= 32);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const dynahand::model::ArticulatedModel hand = dynahand::model::makeDefaultHand();
  const std::string jsonText(dynahand::fuzz::text({data, size}));
  const auto scene = dynahand::playground::parseScene(jsonText, "fuzz.json");
  if (!scene) {
    FUZZ_CHECK(scene.message().rfind("fuzz.json: ", 0) == 0);  // errors name the file
    return 0;
  }
  checkScene(*scene);
  auto playground = dynahand::playground::Playground::create(*scene, hand);
  if (!playground) return 0;
  (*playground)->step(std::nullopt, 1.0f / 30.0f);
  FUZZ_CHECK(std::isfinite((*playground)->time()));
  return 0;
}
