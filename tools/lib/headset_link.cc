#include "tools/lib/headset_link.h"

#include <thread>

namespace floorpose::tools {

using platform::Topic;

HeadsetLink::HeadsetLink(uint32_t domain_id, const std::string& cyclone_config,
                         std::string device_id, const platform::DdsSecurity* security)
    : device_id_(std::move(device_id)) {
  participant_ = std::make_unique<platform::Participant>(domain_id, cyclone_config, security);
  // Inputs in the device's own partition (the only one a headset identity is granted).
  const std::vector<std::string> mine = {platform::DevicePartition(device_id_)};
  mesh_ = std::make_unique<platform::Writer>(*participant_, Topic::kMeshDelta, mine);
  pose_ = std::make_unique<platform::Writer>(*participant_, Topic::kHeadsetPose, mine);
  command_ = std::make_unique<platform::Writer>(*participant_, Topic::kCommand, mine);
  plan_pose_ = std::make_unique<platform::Reader>(*participant_, Topic::kPlanPose);
  alignment_ = std::make_unique<platform::Reader>(*participant_, Topic::kAlignment);
  status_ = std::make_unique<platform::Reader>(*participant_, Topic::kStatus);
  reply_ = std::make_unique<platform::Reader>(*participant_, Topic::kCommandReply);
  explored_ = std::make_unique<platform::Reader>(*participant_, Topic::kExplored);
  waiter_ = std::make_unique<platform::Waiter>(*participant_);
  for (const platform::Reader* r :
       {plan_pose_.get(), alignment_.get(), status_.get(), reply_.get(), explored_.get()})
    waiter_->Attach(*r);
}

bool HeadsetLink::WaitForDaemon(std::chrono::milliseconds timeout) {
  return WaitUntil(
      [&] {
        return mesh_->MatchedReaders() > 0 && pose_->MatchedReaders() > 0 &&
               command_->MatchedReaders() > 0 && reply_->MatchedWriters() > 0 &&
               plan_pose_->MatchedWriters() > 0 && alignment_->MatchedWriters() > 0 &&
               status.has_value();
      },
      timeout);
}

bool HeadsetLink::Send(Topic topic, const google::protobuf::Message& msg, int64_t stamp_ns) {
  platform::Writer* w = topic == Topic::kMeshDelta     ? mesh_.get()
                        : topic == Topic::kHeadsetPose ? pose_.get()
                        : topic == Topic::kCommand     ? command_.get()
                                                       : nullptr;
  return w && w->WriteMessage(device_id_, msg, stamp_ns);
}

bool HeadsetLink::SendPoseAndAwaitAnswer(const v1::HeadsetPose& pose, int64_t stamp_ns,
                                         std::chrono::milliseconds timeout) {
  Poll();
  const size_t before = plan_poses.size();
  return Send(Topic::kHeadsetPose, pose, stamp_ns) &&
         WaitUntil([&] { return plan_poses.size() > before; }, timeout);
}

std::optional<v1::CommandReply> HeadsetLink::Request(v1::Command command,
                                                     std::chrono::milliseconds timeout) {
  command.set_request_id(++last_request_id_);
  Poll();
  // Only a reply that comes after the request: a command sent with Send may have used the
  // same id before.
  const size_t before = replies.size();
  if (!Send(Topic::kCommand, command, 0)) return std::nullopt;
  const uint64_t id = command.request_id();
  auto find = [&]() -> const v1::CommandReply* {
    for (size_t i = before; i < replies.size(); ++i)
      if (replies[i].request_id() == id) return &replies[i];
    return nullptr;
  };
  if (!WaitUntil([&] { return find() != nullptr; }, timeout)) return std::nullopt;
  return *find();
}

void HeadsetLink::Poll() {
  // Parses the device's envelopes of one reader into handle(message).
  auto take = [&]<typename Message>(platform::Reader& reader, auto&& handle) {
    for (const platform::Envelope& e : reader.Take(1024)) {
      if (e.device_id != device_id_) {
        ++foreign_envelopes;
        continue;
      }
      Message m;
      if (m.ParseFromString(e.payload))
        handle(std::move(m));
      else
        ++malformed_envelopes;
    }
  };
  take.operator()<v1::PlanPose>(*plan_pose_,
                                [&](v1::PlanPose p) { plan_poses.push_back(std::move(p)); });
  take.operator()<v1::Alignment>(*alignment_,
                                 [&](v1::Alignment a) { alignments.push_back(std::move(a)); });
  take.operator()<v1::DaemonStatus>(*status_, [&](v1::DaemonStatus s) {
    if (!s.message().empty()) status_messages.push_back(s.message());
    status = std::move(s);
  });
  take.operator()<v1::CommandReply>(*reply_,
                                    [&](v1::CommandReply r) { replies.push_back(std::move(r)); });
  take.operator()<v1::ExploredMap>(*explored_, [&](v1::ExploredMap m) { explored = std::move(m); });
}

}  // namespace floorpose::tools
