#include "platform/config.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iterator>

#include "core/frames.h"
#include "platform/floor_plan_io.h"

namespace floorpose::platform {
namespace {

namespace pb = google::protobuf;

class ErrorCollector : public pb::io::ErrorCollector {
 public:
  void AddError(int line, pb::io::ColumnNumber column, const std::string& message) override {
    if (text.empty())
      text = "line " + std::to_string(line + 1) + ":" + std::to_string(column + 1) + ": " + message;
  }
  std::string text;
};

// Sets every singular field to its current value, so that defaults are printed too.
void MaterializeDefaults(pb::Message* m) {
  const pb::Descriptor* d = m->GetDescriptor();
  const pb::Reflection* r = m->GetReflection();
  for (int i = 0; i < d->field_count(); ++i) {
    const pb::FieldDescriptor* f = d->field(i);
    if (f->is_repeated()) continue;
    switch (f->cpp_type()) {
      case pb::FieldDescriptor::CPPTYPE_MESSAGE:
        MaterializeDefaults(r->MutableMessage(m, f));
        break;
      case pb::FieldDescriptor::CPPTYPE_INT32: r->SetInt32(m, f, r->GetInt32(*m, f)); break;
      case pb::FieldDescriptor::CPPTYPE_INT64: r->SetInt64(m, f, r->GetInt64(*m, f)); break;
      case pb::FieldDescriptor::CPPTYPE_UINT32: r->SetUInt32(m, f, r->GetUInt32(*m, f)); break;
      case pb::FieldDescriptor::CPPTYPE_UINT64: r->SetUInt64(m, f, r->GetUInt64(*m, f)); break;
      case pb::FieldDescriptor::CPPTYPE_DOUBLE: r->SetDouble(m, f, r->GetDouble(*m, f)); break;
      case pb::FieldDescriptor::CPPTYPE_FLOAT: r->SetFloat(m, f, r->GetFloat(*m, f)); break;
      case pb::FieldDescriptor::CPPTYPE_BOOL: r->SetBool(m, f, r->GetBool(*m, f)); break;
      case pb::FieldDescriptor::CPPTYPE_ENUM: r->SetEnum(m, f, r->GetEnum(*m, f)); break;
      case pb::FieldDescriptor::CPPTYPE_STRING: r->SetString(m, f, r->GetString(*m, f)); break;
    }
  }
}

}  // namespace

bool ParseConfig(const std::string& text, v1::FloorposedConfig* config, std::string* error) {
  pb::TextFormat::Parser parser;
  ErrorCollector errors;
  parser.RecordErrorsTo(&errors);
  if (!parser.ParseFromString(text, config)) {
    *error = errors.text.empty() ? "config syntax error" : errors.text;
    return false;
  }
  const std::string invalid = ValidateConfig(*config);
  if (!invalid.empty()) {
    *error = invalid;
    return false;
  }
  return true;
}

bool LoadConfig(const std::string& path, v1::FloorposedConfig* config, std::string* error) {
  if (path.empty()) {
    config->Clear();
    return true;
  }
  std::string text;
  if (!ReadFile(path, 1u << 20, &text, error)) return false;
  if (!ParseConfig(text, config, error)) {
    *error = path + ": " + *error;
    return false;
  }
  return true;
}

namespace {

std::string ValidateDds(const v1::DdsConfig& d) {
  if (d.domain_id() > 232) return "dds.domain_id must be 0..232";
  const v1::DdsSecurityConfig& s = d.security();
  const std::string files[] = {s.identity_ca(),    s.identity_certificate(), s.private_key(),
                               s.permissions_ca(), s.governance(),           s.permissions()};
  const auto set = std::count_if(std::begin(files), std::end(files),
                                 [](const std::string& f) { return !f.empty(); });
  if (set != 0 && set != 6)
    return "dds.security needs all of identity_ca, identity_certificate, private_key, "
           "permissions_ca, governance and permissions, or none";
  if (d.device_id().empty()) return "dds.device_id must not be empty";
  return {};
}

std::string ValidateTracking(const v1::TrackingConfig& m) {
  for (const auto& [value, name] :
       {std::pair{m.measurement().sigma_m(), "tracking.measurement.sigma_m"},
        std::pair{m.measurement().independent_points(), "tracking.measurement.independent_points"},
        std::pair{m.measurement().window_s(), "tracking.measurement.window_s"},
        std::pair{m.wheel().window_s(), "tracking.wheel.window_s"},
        std::pair{m.measurement().update_interval_s(), "tracking.measurement.update_interval_s"},
        std::pair{m.recovery().pick_sigma_m(), "tracking.recovery.pick_sigma_m"},
        std::pair{m.recovery().pick_sigma_deg(), "tracking.recovery.pick_sigma_deg"},
        std::pair{m.recovery().lost_s(), "tracking.recovery.lost_s"},
        std::pair{m.recovery().search_interval_s(), "tracking.recovery.search_interval_s"},
        std::pair{m.motion().lost_after_s(), "tracking.motion.lost_after_s"}})
    if (!(value > 0 && std::isfinite(value))) return std::string(name) + " must be positive";
  for (const auto& [value, name] :
       {std::pair{m.motion().relocalization_m(), "tracking.motion.relocalization_m"},
        std::pair{m.motion().relocalization_deg(), "tracking.motion.relocalization_deg"},
        std::pair{m.motion().position_m_per_sqrt_m(), "tracking.motion.position_m_per_sqrt_m"},
        std::pair{m.motion().heading_deg_per_sqrt_m(), "tracking.motion.heading_deg_per_sqrt_m"},
        std::pair{m.motion().heading_per_turn(), "tracking.motion.heading_per_turn"},
        std::pair{m.wheel().heading_deg_per_sqrt_m(), "tracking.wheel.heading_deg_per_sqrt_m"},
        std::pair{m.wheel().heading_per_turn(), "tracking.wheel.heading_per_turn"}})
    if (!(value >= 0 && std::isfinite(value))) return std::string(name) + " must be >= 0";
  if (!(m.recovery().start_doubt() > 0 && m.recovery().start_doubt() < 1))
    return "tracking.recovery.start_doubt must be in (0, 1)";
  if (!(m.motion().through_wall() > 0 && m.motion().through_wall() <= 1))
    return "tracking.motion.through_wall must be in (0, 1]";
  if (!(m.measurement().clutter() > 0 && m.measurement().clutter() < 1))
    return "tracking.measurement.clutter must be in (0, 1)";
  if (!(m.samples().min_samples() >= 1 && m.samples().min_samples() <= m.samples().max_samples() &&
        m.samples().max_samples() <= 100000))
    return "tracking.samples must have 1 <= min_samples <= max_samples <= 100000";
  if (!(m.publish().degraded() >= 0 && m.publish().degraded() <= m.publish().reliable() &&
        m.publish().reliable() <= 1))
    return "tracking.publish must have 0 <= degraded <= reliable <= 1";
  return {};
}

// The wall points and the registration of them.
std::string ValidateWallsAndIcp(const v1::WallExtractionConfig& w, const v1::IcpConfig& icp) {
  if (!(w.density_per_m2() > 0 && w.density_per_m2() <= 10000))
    return "walls.density_per_m2 must be in (0, 10000]";
  if (!(w.max_normal_up() > 0 && w.max_normal_up() < 1))
    return "walls.max_normal_up must be in (0, 1)";
  if (!(w.voxel_m() > 0)) return "walls.voxel_m must be positive";
  if (!(icp.max_correspondence_m() > 0)) return "icp.max_correspondence_m must be positive";
  if (icp.levels() > 8) return "icp.levels must be at most 8";
  if (!(icp.degeneracy_ratio() >= 0 && icp.degeneracy_ratio() < 1))
    return "icp.degeneracy_ratio must be in [0, 1)";
  if (!(icp.voxel_m() >= 0 && icp.voxel_m() <= 1)) return "icp.voxel_m must be in [0, 1]";
  return {};
}

// What the daemon serves besides poses: routes, the explored map, alerts.
std::string ValidateServices(const v1::FloorposedConfig& c) {
  for (const auto& [value, name] :
       {std::pair{c.routes().body_radius_m(), "routes.body_radius_m"},
        std::pair{c.routes().cell_m(), "routes.cell_m"},
        std::pair{c.explored().cell_m(), "explored.cell_m"},
        std::pair{c.explored().publish_period_s(), "explored.publish_period_s"},
        std::pair{c.explored().max_ray_m(), "explored.max_ray_m"},
        std::pair{c.explored().max_door_m(), "explored.max_door_m"}})
    if (!(value > 0 && value <= 1000)) return std::string(name) + " must be in (0, 1000]";
  for (const auto& [value, name] : {std::pair{c.alerts().motion_m(), "alerts.motion_m"},
                                    std::pair{c.alerts().no_motion_s(), "alerts.no_motion_s"},
                                    std::pair{c.alerts().pre_alert_s(), "alerts.pre_alert_s"}})
    if (!(value > 0 && value <= 3600)) return std::string(name) + " must be in (0, 3600]";
  if (c.alerts().pre_alert_s() > c.alerts().no_motion_s())
    return "alerts.pre_alert_s must not be longer than alerts.no_motion_s";
  if (!(c.routes().snap_m() >= 0 && c.routes().snap_m() <= 100))
    return "routes.snap_m must be in [0, 100]";
  if (c.routes().cell_m() < 0.01 || c.explored().cell_m() < 0.01)
    return "routes.cell_m and explored.cell_m must be at least 0.01";
  return {};
}

}  // namespace

std::string ValidateConfig(const v1::FloorposedConfig& c) {
  if (!ParseHeadsetFrame(c.headset_frame()))
    return "headset_frame must be \"unity\" or \"zup\", not \"" + c.headset_frame() + "\"";
  if (!(c.floors().change_margin_m() > 0 && c.floors().change_margin_m() <= 10 &&
        c.floors().change_hold_s() >= 0 && c.floors().change_hold_s() <= 600))
    return "floors.change_margin_m must be in (0, 10] and floors.change_hold_s in [0, 600]";
  if (!(c.status_period_s() > 0)) return "status_period_s must be positive";
  if (!(c.snapshot_period_s() > 0)) return "snapshot_period_s must be positive";
  if (!(c.limits().search_cpu() >= 0 && c.limits().search_cpu() <= 1))
    return "limits.search_cpu must be in [0, 1] (a share of one core; 0: no plan searches)";
  const std::string& l = c.log_level();
  if (l != "trace" && l != "debug" && l != "info" && l != "warn" && l != "error")
    return "log_level must be trace, debug, info, warn or error";
  for (const std::string& invalid : {ValidateDds(c.dds()), ValidateTracking(c.tracking()),
                                     ValidateWallsAndIcp(c.walls(), c.icp()), ValidateServices(c)})
    if (!invalid.empty()) return invalid;
  return {};
}

std::string ResolvedConfigText(const v1::FloorposedConfig& config) {
  v1::FloorposedConfig copy = config;
  MaterializeDefaults(&copy);
  std::string out;
  pb::TextFormat::PrintToString(copy, &out);
  return out;
}

tracking::MclOptions ToMclOptions(const v1::FloorposedConfig& c) {
  const v1::TrackingConfig& m = c.tracking();
  tracking::MclOptions o;
  o.motion.position_m_per_sqrt_m = m.motion().position_m_per_sqrt_m();
  o.motion.heading_rad_per_sqrt_m = m.motion().heading_deg_per_sqrt_m() * M_PI / 180;
  o.motion.heading_per_turn = m.motion().heading_per_turn();
  o.motion.lost_after_s = m.motion().lost_after_s();
  o.motion.relocalization_m = m.motion().relocalization_m();
  o.motion.relocalization_rad = m.motion().relocalization_deg() * M_PI / 180;
  o.motion.through_wall = m.motion().through_wall();
  o.measurement.sigma_m = m.measurement().sigma_m();
  o.measurement.clutter = m.measurement().clutter();
  o.measurement.independent_points = m.measurement().independent_points();
  o.window_s = m.measurement().window_s();
  o.update_interval_s = m.measurement().update_interval_s();
  o.samples.min_samples = m.samples().min_samples();
  o.samples.max_samples = m.samples().max_samples();
  o.pick_sigma_m = m.recovery().pick_sigma_m();
  o.pick_sigma_rad = m.recovery().pick_sigma_deg() * M_PI / 180;
  o.recovery.lost_s = m.recovery().lost_s();
  o.recovery.start_doubt = m.recovery().start_doubt();
  o.recovery.search_share = m.recovery().search_share();
  o.recovery.search_interval_s = m.recovery().search_interval_s();
  o.publish.reliable = m.publish().reliable();
  o.publish.degraded = m.publish().degraded();
  const auto& i = c.icp();
  o.icp.max_iterations = i.max_iterations();
  o.icp.levels = i.levels();
  o.icp.reject_sigma = i.reject_sigma();
  o.icp.max_correspondence_m = i.max_correspondence_m();
  o.icp.converge_translation_m = i.converge_translation_m();
  o.icp.converge_rotation_rad = i.converge_rotation_rad();
  o.icp.cauchy_scale_factor = i.cauchy_scale_factor();
  o.icp.inlier_threshold_m = i.inlier_threshold_m();
  o.icp.degeneracy_ratio = i.degeneracy_ratio();
  o.icp.coarsest_points = i.coarsest_points();
  o.icp.voxel_m = i.voxel_m();
  return o;
}

std::string LoopbackDdsConfigText(uint32_t domain, const std::string& device_id,
                                  const std::string& extra) {
  std::string text = "dds { domain_id: " + std::to_string(domain);
  if (!device_id.empty()) text += " device_id: \"" + device_id + "\"";
  text += " cyclonedds_uri: '" + LoopbackCycloneConfig() + "'";
  if (!extra.empty()) text += " " + extra;
  return text + " }\n";
}

v1::FloorposedConfig ForOdometry(v1::FloorposedConfig config, v1::HeadsetPose::Odometry odometry) {
  if (odometry == v1::HeadsetPose::WHEEL) {
    v1::TrackingConfig& m = *config.mutable_tracking();
    m.mutable_motion()->set_heading_deg_per_sqrt_m(m.wheel().heading_deg_per_sqrt_m());
    m.mutable_motion()->set_heading_per_turn(m.wheel().heading_per_turn());
    m.mutable_measurement()->set_window_s(m.wheel().window_s());
  }
  return config;
}

WallExtractionOptions ToWallExtractionOptions(const v1::FloorposedConfig& c) {
  WallExtractionOptions w;
  w.max_normal_up = c.walls().max_normal_up();
  w.density_per_m2 = c.walls().density_per_m2();
  w.seed = c.walls().seed();
  w.max_edge_m = c.walls().max_edge_m();
  w.max_points = c.limits().max_wall_points_per_mesh();
  return w;
}

std::optional<DdsSecurity> ToDdsSecurity(const v1::FloorposedConfig& config) {
  const v1::DdsSecurityConfig& s = config.dds().security();
  if (s.identity_certificate().empty()) return std::nullopt;
  // systemd's LoadCredential= hands the private key to the service's transient user in
  // $CREDENTIALS_DIRECTORY (docs/security.md); the config names it there.
  auto path = [](const std::string& p) {
    static const std::string kVar = "$CREDENTIALS_DIRECTORY";
    const char* dir = std::getenv("CREDENTIALS_DIRECTORY");
    return p.rfind(kVar, 0) == 0 && dir ? dir + p.substr(kVar.size()) : p;
  };
  DdsSecurity out;
  out.identity_ca = path(s.identity_ca());
  out.identity_certificate = path(s.identity_certificate());
  out.private_key = path(s.private_key());
  out.permissions_ca = path(s.permissions_ca());
  out.governance = path(s.governance());
  out.permissions = path(s.permissions());
  return out;
}

}  // namespace floorpose::platform
