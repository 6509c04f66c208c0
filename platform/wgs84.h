// WGS84 longitude/latitude to a local east-north plane in metres, through PROJ: an
// azimuthal equidistant projection on the WGS84 ellipsoid centred on an origin, which
// over a building (hundreds of metres) is a tangent plane to well under a millimetre. Floor plans
// published as RFC 7946 GeoJSON come in longitude/latitude; the tracker works in metres.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/floor_plan.h"

namespace floorpose::platform {

// Longitude and latitude (degrees) of `lon_lat` (in place) become x east, y north in
// metres about `origin` (longitude, latitude). False with a message when PROJ cannot
// build the transformation or a point does not project.
bool ProjectToLocalMetres(const Eigen::Vector2d& origin, std::vector<Eigen::Vector2d>* lon_lat,
                          std::string* error);

// The inverse for a georeferenced plan: plan metres (in place) become longitude, latitude
// (degrees) through the plan's rotation and the projection about its origin. False with a
// message when PROJ cannot.
bool PlanToLonLat(const Georeference& georeference, std::vector<Eigen::Vector2d>* points,
                  std::string* error);

// Whether coordinates with this bounding box can be longitude/latitude of one building:
// longitudes within +-180, latitudes within +-90 and the whole box under 0.1 degrees
// (about 11 km) across. A plan in metres that passes this would be under 0.1 m across.
bool CouldBeLonLat(const Eigen::Vector2d& min, const Eigen::Vector2d& max);

}  // namespace floorpose::platform
