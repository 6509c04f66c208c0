// `floorpose import`: a CAD or GIS floor plan as the GeoJSON floorposed loads
// (tools/lib/plan_import.h).
#include <spdlog/spdlog.h>

#include <cstdio>
#include <fstream>
#include <memory>

#include "platform/floor_plan_io.h"
#include "tools/floorpose/commands.h"
#include "tools/lib/plan_import.h"

namespace floorpose::tools {
namespace {

struct ImportOptions {
  std::string from, to;
  PlanImportOptions plan;
};

int RunImport(const ImportOptions& o) {
  FloorPlan plan;
  PlanImportReport report;
  std::string error;
  if (!ImportPlan(o.from, o.plan, &plan, &report, &error)) {
    spdlog::error("{}", error);
    return 1;
  }
  std::ofstream out(o.to);
  out << platform::ToGeoJson(plan, "floorpose import " + o.from);
  if (!out.flush()) {
    spdlog::error("{}: cannot write", o.to);
    return 1;
  }
  std::string layers;
  for (const std::string& l : report.layers_seen) layers += (layers.empty() ? "" : ", ") + l;
  std::printf("floorpose import: %s -> %s\n", o.from.c_str(), o.to.c_str());
  std::printf("  units                %s\n", report.units.c_str());
  std::printf("  layers in the file   %s\n", layers.c_str());
  std::printf("  features             %zu read, %zu skipped (other layers or no lines)\n",
              report.features, report.skipped_features);
  std::printf("  segments             %zu kept, %zu dropped (zero-length or duplicate)\n",
              plan.segments.size(), report.dropped);
  std::printf("  extent               %.2f x %.2f m\n", plan.max.x() - plan.min.x(),
              plan.max.y() - plan.min.y());
  return 0;
}

}  // namespace

Run AddImportCommand(CLI::App& app) {
  auto o = std::make_shared<ImportOptions>();
  app.add_option("--from", o->from, "DXF, GeoJSON, GeoPackage, Shapefile (any GDAL vector file)")
      ->required();
  app.add_option("--to", o->to, "floor plan to write (.geojson)")->required();
  app.add_option("--layer", o->plan.layers, "keep only this layer (repeatable; default: all)");
  app.add_option("--units", o->plan.units, "drawing units (default: the file's, else metres)")
      ->check(CLI::IsMember({"m", "cm", "mm"}));
  return [o] { return RunImport(*o); };
}

}  // namespace floorpose::tools
