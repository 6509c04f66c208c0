// Cursor-on-Target (CoT 2.0 XML, as ATAK, WinTAK and TAK Server speak it): every wearer on
// a georeferenced plan as a friendly ground unit (type a-f-G-U-C), and the team's markers
// as points, sent over UDP multicast (the TAK situational-awareness default,
// 239.2.3.1:6969) or a TCP stream to a TAK server. docs/cot.md says how a plan is
// georeferenced and what each field carries.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/floor_plan.h"
#include "floorpose/v1/floorpose.pb.h"

namespace floorpose::tools {

// A plan the bridge can put on the Earth.
struct CotPlan {
  std::string id;
  Georeference georeference;
  double floor_height_m = 0;  // of its floor in a .floors set, above the set's zero
};

struct CotOptions {
  std::string to = "udp://239.2.3.1:6969";   // or tcp://HOST:PORT (a TAK server's input)
  std::string interface;                     // multicast out of this address; empty: the OS's
  std::map<std::string, std::string> names;  // device id -> callsign; default: the id
  double ground_hae_m = 0;  // height above the WGS84 ellipsoid of the plans' zero, metres
  double stale_s = 30;      // how long a receiver keeps showing an event without a new one
};

// One event's content.
struct CotEvent {
  std::string uid, type, callsign, remarks;
  double lat = 0, lon = 0, hae = 0;
  double ce_m = 9999999;             // circular error (1 sigma), metres; 9999999: unknown
  std::optional<double> course_deg;  // clockwise from true north
  int64_t time_unix_ns = 0;
  double stale_s = 30;
};
std::string ToCotXml(const CotEvent& event);

// The 1-sigma circular error of a position that is within 1 m with probability p, for a
// circular normal error (Rayleigh): sigma = sqrt(-1 / (2 ln(1 - p))); 9999999 (CoT's
// "unknown") when p is too small to say.
double CircularErrorM(double probability_within_1m);

// Where events go: a UDP socket (multicast or unicast) or a TCP stream, reconnected when
// it drops.
class CotSink {
 public:
  static std::unique_ptr<CotSink> Open(const std::string& to, const std::string& interface,
                                       std::string* error);
  ~CotSink();
  bool Send(const std::string& xml, std::string* error);

 private:
  CotSink() = default;
  bool Connect(std::string* error);
  bool tcp_ = false;
  std::string host_;
  int port_ = 0;
  int fd_ = -1;
  int64_t next_connect_ns_ = 0;
};

// DDS outputs in, CoT out: remembers each device's plan (from its statuses) and sends an
// event per plan pose of a device on a georeferenced plan, and one per marker.
class CotBridge {
 public:
  CotBridge(std::vector<CotPlan> plans, CotOptions options);
  bool Open(std::string* error);
  void OnStatus(const std::string& device, const v1::DaemonStatus& status);
  void OnPlanPose(const std::string& device, const v1::PlanPose& pose);
  void OnMarker(const v1::Marker& marker);
  uint64_t sent() const { return sent_; }

 private:
  // The plan's event for plan point (x, y); false when the plan is not georeferenced.
  bool Place(const std::string& plan_id, double x, double y, CotEvent* event) const;
  void Send(const CotEvent& event);

  std::map<std::string, CotPlan> plans_;
  CotOptions options_;
  std::unique_ptr<CotSink> sink_;
  std::map<std::string, std::string> plan_of_;  // device -> plan id
  uint64_t sent_ = 0, failures_ = 0;
  int64_t next_warning_ns_ = 0;
};

}  // namespace floorpose::tools
