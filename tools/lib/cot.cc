#include "tools/lib/cot.h"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <regex>

#include "platform/clock.h"
#include "platform/team.h"
#include "platform/wgs84.h"

namespace floorpose::tools {

namespace {

std::string Escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default:
        // XML 1.0 has no place for the other control characters.
        if (static_cast<unsigned char>(c) >= 0x20 || c == '\t' || c == '\n') out += c;
    }
  }
  return out;
}

std::string IsoTime(int64_t unix_ns) {
  const std::time_t seconds = static_cast<std::time_t>(unix_ns / 1'000'000'000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[96];
  std::snprintf(text, sizeof(text), "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", utc.tm_year + 1900,
                utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec,
                static_cast<int>(unix_ns / 1'000'000 % 1000));
  return text;
}

std::string Number(double v, int decimals) {
  char text[48];
  std::snprintf(text, sizeof(text), "%.*f", decimals, v);
  return text;
}

const char* MarkerType(v1::Marker::Kind kind) {
  // A casualty is ATAK's CASEVAC point; the rest are spot map markers, told apart by their
  // callsign and remarks.
  return kind == v1::Marker::VICTIM ? "b-r-f-h-c" : "b-m-p-s-m";
}

}  // namespace

std::string ToCotXml(const CotEvent& e) {
  const std::string time = IsoTime(e.time_unix_ns);
  std::string xml = "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"yes\"?>";
  xml += "<event version=\"2.0\" uid=\"" + Escape(e.uid) + "\" type=\"" + Escape(e.type) +
         "\" how=\"m-g\" time=\"" + time + "\" start=\"" + time + "\" stale=\"" +
         IsoTime(e.time_unix_ns + static_cast<int64_t>(e.stale_s * 1e9)) + "\">";
  xml += "<point lat=\"" + Number(e.lat, 8) + "\" lon=\"" + Number(e.lon, 8) + "\" hae=\"" +
         Number(e.hae, 2) + "\" ce=\"" + Number(e.ce_m, 2) + "\" le=\"9999999.0\"/>";
  xml += "<detail><contact callsign=\"" + Escape(e.callsign) + "\"/>";
  if (e.course_deg) xml += "<track course=\"" + Number(*e.course_deg, 1) + "\" speed=\"0.0\"/>";
  if (!e.remarks.empty()) xml += "<remarks>" + Escape(e.remarks) + "</remarks>";
  xml += "</detail></event>";
  return xml;
}

double CircularErrorM(double p) {
  if (!(p > 1e-6)) return 9999999;
  p = std::min(p, 1 - 1e-9);
  return std::sqrt(-1.0 / (2.0 * std::log(1.0 - p)));
}

std::unique_ptr<CotSink> CotSink::Open(const std::string& to, const std::string& interface,
                                       std::string* error) {
  static const std::regex url(R"(^(udp|tcp)://([^:/]+):(\d{1,5})$)");
  std::smatch m;
  if (!std::regex_match(to, m, url) || std::stoi(m[3]) == 0 || std::stoi(m[3]) > 65535) {
    *error = "'" + to + "' is not udp://HOST:PORT or tcp://HOST:PORT";
    return nullptr;
  }
  std::unique_ptr<CotSink> sink(new CotSink);
  sink->tcp_ = m[1] == "tcp";
  sink->host_ = m[2];
  sink->port_ = std::stoi(m[3]);
  if (sink->tcp_) {
    // A TAK server that is not up yet is no error: the stream connects when it can.
    std::string later;
    if (!sink->Connect(&later)) spdlog::warn("CoT: {} (will retry)", later);
    return sink;
  }
  sink->fd_ = socket(AF_INET, SOCK_DGRAM, 0);
  in_addr group{};
  if (sink->fd_ < 0 || inet_pton(AF_INET, sink->host_.c_str(), &group) != 1) {
    *error = "CoT: " + sink->host_ + " is not an IPv4 address";
    return nullptr;
  }
  if (IN_MULTICAST(ntohl(group.s_addr))) {
    const unsigned char ttl = 1, loop = 1;  // the building's network, and this host's TAK
    setsockopt(sink->fd_, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof(ttl));
    setsockopt(sink->fd_, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof(loop));
    if (!interface.empty()) {
      in_addr out{};
      if (inet_pton(AF_INET, interface.c_str(), &out) != 1 ||
          setsockopt(sink->fd_, IPPROTO_IP, IP_MULTICAST_IF, &out, sizeof(out)) != 0) {
        *error = "CoT: cannot send multicast out of " + interface;
        return nullptr;
      }
    }
  }
  return sink;
}

CotSink::~CotSink() {
  if (fd_ >= 0) close(fd_);
}

bool CotSink::Connect(std::string* error) {
  addrinfo hints{}, *found = nullptr;
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_STREAM;
  next_connect_ns_ = platform::MonotonicNs() + 2'000'000'000;
  if (getaddrinfo(host_.c_str(), std::to_string(port_).c_str(), &hints, &found) != 0 || !found) {
    *error = "cannot resolve " + host_;
    return false;
  }
  fd_ = socket(found->ai_family, found->ai_socktype | SOCK_CLOEXEC, 0);
  const bool ok = fd_ >= 0 && connect(fd_, found->ai_addr, found->ai_addrlen) == 0;
  freeaddrinfo(found);
  if (!ok) {
    *error =
        "cannot connect to " + host_ + ":" + std::to_string(port_) + ": " + std::strerror(errno);
    if (fd_ >= 0) close(fd_);
    fd_ = -1;
  }
  return ok;
}

bool CotSink::Send(const std::string& xml, std::string* error) {
  if (!tcp_) {
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(static_cast<uint16_t>(port_));
    inet_pton(AF_INET, host_.c_str(), &to.sin_addr);
    if (sendto(fd_, xml.data(), xml.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof(to)) < 0) {
      *error = std::strerror(errno);
      return false;
    }
    return true;
  }
  if (fd_ < 0 && (platform::MonotonicNs() < next_connect_ns_ || !Connect(error))) {
    if (error->empty()) *error = "not connected";
    return false;
  }
  size_t done = 0;
  while (done < xml.size()) {
    const ssize_t n = ::send(fd_, xml.data() + done, xml.size() - done, MSG_NOSIGNAL);
    if (n <= 0) {
      *error = std::string("the TAK server dropped the stream: ") + std::strerror(errno);
      close(fd_);
      fd_ = -1;
      return false;
    }
    done += static_cast<size_t>(n);
  }
  return true;
}

CotBridge::CotBridge(std::vector<CotPlan> plans, CotOptions options)
    : options_(std::move(options)) {
  for (CotPlan& p : plans) plans_.emplace(p.id, std::move(p));
}

bool CotBridge::Open(std::string* error) {
  sink_ = CotSink::Open(options_.to, options_.interface, error);
  return sink_ != nullptr;
}

bool CotBridge::Place(const std::string& plan_id, double x, double y, CotEvent* event) const {
  auto plan = plans_.find(plan_id);
  if (plan == plans_.end()) return false;
  std::vector<Eigen::Vector2d> point = {{x, y}};
  std::string error;
  if (!platform::PlanToLonLat(plan->second.georeference, &point, &error)) return false;
  event->lon = point[0].x();
  event->lat = point[0].y();
  event->hae = options_.ground_hae_m + plan->second.floor_height_m;
  event->time_unix_ns = platform::WallClockNs();
  event->stale_s = options_.stale_s;
  return true;
}

void CotBridge::OnStatus(const std::string& device, const v1::DaemonStatus& status) {
  if (plan_of_.size() < 1024 || plan_of_.count(device)) plan_of_[device] = status.plan_id();
}

void CotBridge::OnPlanPose(const std::string& device, const v1::PlanPose& pose) {
  auto plan = plan_of_.find(device);
  if (plan == plan_of_.end() || !std::isfinite(pose.x()) || !std::isfinite(pose.y())) return;
  CotEvent e;
  if (!Place(plan->second, pose.x(), pose.y(), &e)) return;
  e.uid = "floorpose-" + device;
  e.type = "a-f-G-U-C";
  const auto name = options_.names.find(device);
  e.callsign = name == options_.names.end() ? device : name->second;
  e.ce_m = CircularErrorM(pose.reliability().probability());
  if (std::isfinite(pose.heading())) {
    // Heading: counter-clockwise from the plan's +x; course: clockwise from north.
    const double east_ccw = pose.heading() + plans_.at(plan->second).georeference.rotation_rad;
    e.course_deg = std::fmod(450.0 - east_ccw * 180.0 / M_PI, 360.0);
  }
  e.remarks = "floorpose: " +
              std::string(pose.reliability().flag() == v1::Reliability::RELIABLE   ? "reliable"
                          : pose.reliability().flag() == v1::Reliability::DEGRADED ? "degraded"
                                                                                   : "unreliable") +
              ", floor " + pose.floor() +
              (pose.reliability().reason().empty() ? "" : ": " + pose.reliability().reason());
  Send(e);
}

void CotBridge::OnMarker(const v1::Marker& marker) {
  CotEvent e;
  if (!Place(marker.plan_id(), marker.x(), marker.y(), &e)) return;
  e.uid = "floorpose-marker-" + marker.id();
  e.type = MarkerType(marker.kind());
  const std::string kind = platform::MarkerKindName(marker.kind());
  e.callsign = kind + (marker.text().empty() ? "" : ": " + marker.text());
  e.remarks = kind + " marked by " + marker.author() + " on floor " + marker.floor();
  e.ce_m = marker.radius_m() > 0 ? marker.radius_m() : 1.0;
  if (marker.removed()) e.stale_s = 0;  // gone from the receivers' maps at once
  Send(e);
}

void CotBridge::Send(const CotEvent& event) {
  std::string error;
  if (sink_ && sink_->Send(ToCotXml(event), &error)) {
    ++sent_;
    return;
  }
  ++failures_;
  const int64_t now = platform::MonotonicNs();
  if (now >= next_warning_ns_) {
    spdlog::warn("CoT to {}: {} ({} events not sent so far)", options_.to, error, failures_);
    next_warning_ns_ = now + 5'000'000'000;
  }
}

}  // namespace floorpose::tools
