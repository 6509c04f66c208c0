#include "platform/wgs84.h"

#include <dlfcn.h>
#include <proj.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

namespace floorpose::platform {

namespace {

// The few PROJ calls used here, from libproj opened on first use: a daemon whose plans are
// in metres never maps PROJ and what it links (curl, TLS, sqlite, TIFF: 6 MB of memory).
struct Proj {
  decltype(&proj_context_create) context_create = nullptr;
  decltype(&proj_context_destroy) context_destroy = nullptr;
  decltype(&proj_create) create = nullptr;
  decltype(&proj_destroy) destroy = nullptr;
  decltype(&proj_trans) trans = nullptr;
  decltype(&proj_errno) errno_of = nullptr;
  std::string error;  // why PROJ could not be opened; empty when it was
};

template <typename F>
bool Bind(void* library, const char* name, F* function) {
  *function = reinterpret_cast<F>(dlsym(library, name));
  return *function != nullptr;
}

const Proj& OpenProj() {
  static const Proj proj = [] {
    Proj p;
    // Never closed: PROJ keeps its own state for the life of the process.
    void* library = dlopen(FLOORPOSE_PROJ_SONAME, RTLD_NOW | RTLD_LOCAL);
    if (!library) {
      const char* why = dlerror();
      p.error = std::string("PROJ (" FLOORPOSE_PROJ_SONAME ") could not be opened: ") +
                (why ? why : "unknown error");
      return p;
    }
    if (!Bind(library, "proj_context_create", &p.context_create) ||
        !Bind(library, "proj_context_destroy", &p.context_destroy) ||
        !Bind(library, "proj_create", &p.create) || !Bind(library, "proj_destroy", &p.destroy) ||
        !Bind(library, "proj_trans", &p.trans) || !Bind(library, "proj_errno", &p.errno_of))
      p.error = "PROJ (" FLOORPOSE_PROJ_SONAME ") lacks a function this build calls";
    return p;
  }();
  return proj;
}

// Runs the degrees <-> local metres pipeline about `origin` over `points`, in place.
bool Transform(const Eigen::Vector2d& origin, PJ_DIRECTION direction,
               std::vector<Eigen::Vector2d>* points, std::string* error) {
  // Degrees in, longitude first (as GeoJSON, RFC 7946, orders them): a pipeline needs no
  // CRS database, so nothing but libproj itself is read.
  char definition[256];
  std::snprintf(definition, sizeof definition,
                "+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad "
                "+step +proj=aeqd +lat_0=%.12f +lon_0=%.12f +x_0=0 +y_0=0 +ellps=WGS84",
                origin.y(), origin.x());
  const Proj& proj = OpenProj();
  if (!proj.error.empty()) {
    *error = proj.error;
    return false;
  }
  const std::unique_ptr<PJ_CONTEXT, decltype(proj.context_destroy)> context(proj.context_create(),
                                                                            proj.context_destroy);
  const std::unique_ptr<PJ, decltype(proj.destroy)> transform(
      context ? proj.create(context.get(), definition) : nullptr, proj.destroy);
  if (!transform) {
    *error = "PROJ could not build the WGS84 to local metres transformation";
    return false;
  }
  for (Eigen::Vector2d& p : *points) {
    PJ_COORD in{};
    in.v[0] = p.x();
    in.v[1] = p.y();
    const PJ_COORD out = proj.trans(transform.get(), direction, in);
    if (proj.errno_of(transform.get()) != 0 || !std::isfinite(out.xy.x) ||
        !std::isfinite(out.xy.y) || out.xy.x == HUGE_VAL) {
      *error = "PROJ could not project a coordinate of the plan";
      return false;
    }
    p = {out.xy.x, out.xy.y};
  }
  return true;
}

}  // namespace

bool ProjectToLocalMetres(const Eigen::Vector2d& origin, std::vector<Eigen::Vector2d>* lon_lat,
                          std::string* error) {
  return Transform(origin, PJ_FWD, lon_lat, error);
}

bool PlanToLonLat(const Georeference& georeference, std::vector<Eigen::Vector2d>* points,
                  std::string* error) {
  const double c = std::cos(georeference.rotation_rad), s = std::sin(georeference.rotation_rad);
  for (Eigen::Vector2d& p : *points)
    p = Eigen::Vector2d(c * p.x() - s * p.y(), s * p.x() + c * p.y());
  return Transform(georeference.origin_lon_lat, PJ_INV, points, error);
}

bool CouldBeLonLat(const Eigen::Vector2d& min, const Eigen::Vector2d& max) {
  return min.x() >= -180.0 && max.x() <= 180.0 && min.y() >= -90.0 && max.y() <= 90.0 &&
         (max - min).maxCoeff() < 0.1;
}

}  // namespace floorpose::platform
