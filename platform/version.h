// What `floorposed --version` and `floorpose --version` print (cmake/Version.cmake).
#pragma once

namespace floorpose::platform {

// "0.1.0 (g1a2b3c4)": the project version and, for a build from a git checkout, its
// `git describe`.
const char* Version();

}  // namespace floorpose::platform
