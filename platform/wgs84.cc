#include "platform/wgs84.h"

#include <ogr_spatialref.h>

#include <cmath>
#include <memory>

namespace floorpose::platform {

bool ProjectToLocalMetres(const Eigen::Vector2d& origin, std::vector<Eigen::Vector2d>* lon_lat,
                          std::string* error) {
  OGRSpatialReference geographic, local;
  geographic.SetWellKnownGeogCS("WGS84");
  // Longitude first, as GeoJSON (RFC 7946) orders them, whatever EPSG says.
  geographic.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  local.SetWellKnownGeogCS("WGS84");
  local.SetAE(origin.y(), origin.x(), 0.0, 0.0);
  local.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> transform(
      OGRCreateCoordinateTransformation(&geographic, &local));
  if (!transform) {
    *error = "PROJ could not build the WGS84 to local metres transformation";
    return false;
  }
  const size_t n = lon_lat->size();
  if (n == 0) return true;
  std::vector<double> x(n), y(n);
  for (size_t i = 0; i < n; ++i) x[i] = (*lon_lat)[i].x(), y[i] = (*lon_lat)[i].y();
  std::vector<int> ok(n, 0);
  if (!transform->Transform(n, x.data(), y.data(), nullptr, ok.data())) {
    *error = "PROJ could not project the plan's coordinates";
    return false;
  }
  for (size_t i = 0; i < n; ++i) {
    if (!ok[i] || !std::isfinite(x[i]) || !std::isfinite(y[i])) {
      *error = "PROJ could not project a coordinate of the plan";
      return false;
    }
    (*lon_lat)[i] = {x[i], y[i]};
  }
  return true;
}

bool CouldBeLonLat(const Eigen::Vector2d& min, const Eigen::Vector2d& max) {
  return min.x() >= -180.0 && max.x() <= 180.0 && min.y() >= -90.0 && max.y() <= 90.0 &&
         (max - min).maxCoeff() < 0.1;
}

}  // namespace floorpose::platform
