#include "platform/wgs84.h"

#include <proj.h>

#include <cmath>
#include <cstdio>
#include <memory>

namespace floorpose::platform {

namespace {

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
  const std::unique_ptr<PJ_CONTEXT, decltype(&proj_context_destroy)> context(proj_context_create(),
                                                                             &proj_context_destroy);
  const std::unique_ptr<PJ, decltype(&proj_destroy)> transform(
      context ? proj_create(context.get(), definition) : nullptr, &proj_destroy);
  if (!transform) {
    *error = "PROJ could not build the WGS84 to local metres transformation";
    return false;
  }
  for (Eigen::Vector2d& p : *points) {
    const PJ_COORD out = proj_trans(transform.get(), direction, proj_coord(p.x(), p.y(), 0, 0));
    if (proj_errno(transform.get()) != 0 || !std::isfinite(out.xy.x) || !std::isfinite(out.xy.y) ||
        out.xy.x == HUGE_VAL) {
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
