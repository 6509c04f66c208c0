# Writes OUT, a C++ file that holds the dashboard's page, script and style as
# floorpose::tools::kDashboardAssets (tools/lib/dashboard.cc serves them).
# Run as: cmake -DOUT=... -DDIR=... -P embed.cmake
set(assets
  "/|text/html|index.html"
  "/dashboard.js|text/javascript|dashboard.js"
  "/dashboard.css|text/css|dashboard.css")
set(body "// Generated from tools/dashboard/ by embed.cmake; do not edit.\n")
string(APPEND body "namespace floorpose::tools {\n")
string(APPEND body "struct DashboardAsset {\n  const char* path;\n  const char* content_type;\n  const char* body;\n};\n")
string(APPEND body "extern const DashboardAsset kDashboardAssets[];\n")
string(APPEND body "const DashboardAsset kDashboardAssets[] = {\n")
foreach(asset IN LISTS assets)
  string(REPLACE "|" ";" parts "${asset}")
  list(GET parts 0 path)
  list(GET parts 1 type)
  list(GET parts 2 file)
  file(READ "${DIR}/${file}" text)
  string(FIND "${text}" ")FPASSET\"" clash)
  if(NOT clash EQUAL -1)
    message(FATAL_ERROR "${file} contains the raw-string delimiter )FPASSET\"")
  endif()
  string(APPEND body "  {\"${path}\", \"${type}; charset=utf-8\", R\"FPASSET(${text})FPASSET\"},\n")
endforeach()
string(APPEND body "  {nullptr, nullptr, nullptr}};\n}  // namespace floorpose::tools\n")
file(WRITE "${OUT}" "${body}")
