// Internal: the error every sensor reader returns, "NAME: PROBLEM" (NAME is the file).
#pragma once

#include <string>

#include "dynahand/core.h"

namespace dynahand::sensor::detail {

inline Error fail(const std::string& name, const std::string& problem) {
  return Error{name + ": " + problem};
}

}  // namespace dynahand::sensor::detail
