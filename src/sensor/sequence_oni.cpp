// OpenNI .oni recordings through OpenNI2's file driver (built when OpenNI2 was
// found at configure time; otherwise opening an .oni says how to get support).
#include "sensor/frame_source.h"

namespace dynahand::sensor {

bool oniSupported() {
  return false;
}

Result<OpenedSource> openOni(const std::filesystem::path& file) {
  return Error{file.string() +
               ": this dynahand was built without OpenNI2, so .oni recordings cannot be read "
               "(install libopenni2-dev and reconfigure)"};
}

}  // namespace dynahand::sensor
