// The headset's (or app's) side of the DDS link to one floorposed: publishes inputs for a
// device and collects that device's outputs. Used by the demo and the integration tests.
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "floorpose/v1/floorpose.pb.h"
#include "platform/dds.h"

namespace floorpose::tools {

class HeadsetLink {
 public:
  // Throws std::runtime_error when DDS cannot start. With `security`, joins a secured
  // domain with that identity (platform::DdsSecurity).
  HeadsetLink(uint32_t domain_id, const std::string& cyclone_config, std::string device_id,
              const platform::DdsSecurity* security = nullptr);

  // Waits until the daemon's readers matched our writers, our readers its writers, and
  // a status arrived.
  bool WaitForDaemon(std::chrono::milliseconds timeout);
  // Polls until pred() holds or the timeout passes; returns pred().
  template <typename Pred>
  bool WaitUntil(Pred pred, std::chrono::milliseconds timeout);

  bool Send(platform::Topic topic, const google::protobuf::Message& msg, int64_t stamp_ns);
  // Sends a pose and waits for its plan pose. A walk's first pose goes this way: the
  // daemon's plan-pose writer keeps only its latest pose for a reader it matches late,
  // so poses sent before the first answer came can be lost to this link.
  bool SendPoseAndAwaitAnswer(const v1::HeadsetPose& pose, int64_t stamp_ns,
                              std::chrono::milliseconds timeout);
  // Sends the command with the next request id and waits for its reply.
  std::optional<v1::CommandReply> Request(v1::Command command, std::chrono::milliseconds timeout);
  void Poll();  // drains the output readers into the fields below

  std::vector<v1::PlanPose> plan_poses;
  std::vector<v1::Alignment> alignments;
  std::optional<v1::DaemonStatus> status;
  std::vector<std::string> status_messages;  // every non-empty DaemonStatus.message
  std::vector<v1::CommandReply> replies;
  std::optional<v1::ExploredMap> explored;  // the latest
  size_t foreign_envelopes = 0;             // outputs of other devices, ignored
  size_t malformed_envelopes = 0;

  platform::Participant& participant() { return *participant_; }
  const std::string& device_id() const { return device_id_; }

 private:
  std::string device_id_;
  std::unique_ptr<platform::Participant> participant_;
  std::unique_ptr<platform::Writer> mesh_, pose_, command_;
  std::unique_ptr<platform::Reader> plan_pose_, alignment_, status_, reply_, explored_;
  uint64_t last_request_id_ = 0;
  std::unique_ptr<platform::Waiter> waiter_;
};

template <typename Pred>
bool HeadsetLink::WaitUntil(Pred pred, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (true) {
    Poll();
    if (pred()) return true;
    if (std::chrono::steady_clock::now() >= end) return false;
    waiter_->Wait(std::chrono::milliseconds(20));
  }
}

}  // namespace floorpose::tools
