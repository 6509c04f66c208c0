// floorposed configuration: protobuf text format (proto/floorpose/v1/config.proto holds
// every option with its unit and default).
#pragma once

#include <optional>
#include <string>

#include "core/tracking/alignment.h"
#include "core/tracking/mcl.h"
#include "core/wall_extractor.h"
#include "floorpose/v1/config.pb.h"
#include "floorpose/v1/floorpose.pb.h"
#include "platform/dds.h"

namespace floorpose::platform {

// Parses text-format config; an empty path gives the defaults. False with a message on
// an unreadable file, a syntax error or an unknown option.
bool LoadConfig(const std::string& path, v1::FloorposedConfig* config, std::string* error);
bool ParseConfig(const std::string& text, v1::FloorposedConfig* config, std::string* error);

// Checks values the schema cannot (ranges, names). Empty when valid.
std::string ValidateConfig(const v1::FloorposedConfig& config);

// The `dds { ... }` block of a floorposed config on `domain`, kept on loopback
// (LoopbackCycloneConfig), for device_id (empty: the default), with `extra` options inside
// the block; one line. For the tools and tests that start a daemon of their own.
std::string LoopbackDdsConfigText(uint32_t domain, const std::string& device_id,
                                  const std::string& extra = "");

// Text format with every option present, defaults included.
std::string ResolvedConfigText(const v1::FloorposedConfig& config);

// The estimator's options (tracking), ICP's from `icp`.
tracking::MclOptions ToMclOptions(const v1::FloorposedConfig& config);
// The configuration a device moving on this odometry is tracked with: for WHEEL,
// tracking.wheel replaces the headset's drift and window.
v1::FloorposedConfig ForOdometry(v1::FloorposedConfig config, v1::HeadsetPose::Odometry odometry);
// The configuration a device is tracked with: as configured, for the odometry its poses
// say (ForOdometry).
class DeviceConfig {
 public:
  explicit DeviceConfig(v1::FloorposedConfig configured)
      : configured_(std::move(configured)), in_use_(configured_) {}
  // The device's poses say `odometry`: false when that is the one in use already.
  bool Use(v1::HeadsetPose::Odometry odometry) {
    if (odometry == odometry_) return false;
    odometry_ = odometry;
    in_use_ = ForOdometry(configured_, odometry);
    return true;
  }
  const v1::FloorposedConfig& get() const { return in_use_; }

 private:
  const v1::FloorposedConfig configured_;
  v1::FloorposedConfig in_use_;
  v1::HeadsetPose::Odometry odometry_ = v1::HeadsetPose::VISUAL_INERTIAL;
};
// The DDS Security files of dds.security, or nothing when it is not set.
std::optional<DdsSecurity> ToDdsSecurity(const v1::FloorposedConfig& config);
WallExtractionOptions ToWallExtractionOptions(const v1::FloorposedConfig& config);

}  // namespace floorpose::platform
