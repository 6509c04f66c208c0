#include "platform/version.h"

namespace floorpose::platform {

const char* Version() { return FLOORPOSE_VERSION_STRING; }

}  // namespace floorpose::platform
