// DDS options shared by the subcommands that join a domain.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

#include "platform/dds.h"

namespace floorpose::tools {

struct DdsOptions {
  uint32_t domain_id = 0;
  bool loopback = false;
  std::string Config() const { return loopback ? platform::LoopbackCycloneConfig() : ""; }
  void Add(CLI::App& app) {
    app.add_option("--domain", domain_id, "DDS domain id")->capture_default_str();
    app.add_flag("--loopback", loopback,
                 "keep DDS on 127.0.0.1 with unicast discovery (else CYCLONEDDS_URI applies)");
  }
};

}  // namespace floorpose::tools
