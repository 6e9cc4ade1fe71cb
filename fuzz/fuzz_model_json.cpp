// libFuzzer target: dynahand model files (docs/formats/model.md), parsed from memory by
// model::parseModel, the reader behind loadModel and every --model option. It must return a
// model or an Error, never crash or hang; a model it returns must be valid and save as a
// file that loads again byte-identically (model_checks.h).
#include <cstddef>
#include <cstdint>
#include <string>

#include "dynahand/model.h"
#include "fuzz_util.h"
#include "model_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string jsonText(dynahand::fuzz::text({data, size}));
  const auto model = dynahand::model::parseModel(jsonText, "fuzz.json");
  if (model) {
    dynahand::fuzz::checkModel(*model);
  } else {
    FUZZ_CHECK(model.message().rfind("fuzz.json: ", 0) == 0);  // errors name the file
  }
  return 0;
}
