// Test support: the synthesiser's options for a built-in clip (the designated-initialiser
// form warns about every member left out).
#pragma once

#include <string>

#include "dynahand/synth.h"

namespace dynahand::test {

inline synth::SynthOptions clipOptions(const std::string& clip, const std::string& profile,
                                       int frames) {
  synth::SynthOptions o;
  o.clip = clip;
  o.profile = profile;
  o.frameCount = frames;
  return o;
}

}  // namespace dynahand::test
