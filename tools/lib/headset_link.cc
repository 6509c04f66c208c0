#include "tools/lib/headset_link.h"

#include <thread>

namespace floorpose::tools {

using platform::Topic;

HeadsetLink::HeadsetLink(uint32_t domain_id, const std::string& cyclone_config,
                         std::string device_id)
    : device_id_(std::move(device_id)) {
  participant_ = std::make_unique<platform::Participant>(domain_id, cyclone_config);
  mesh_ = std::make_unique<platform::Writer>(*participant_, Topic::kMeshDelta);
  pose_ = std::make_unique<platform::Writer>(*participant_, Topic::kHeadsetPose);
  command_ = std::make_unique<platform::Writer>(*participant_, Topic::kCommand);
  plan_pose_ = std::make_unique<platform::Reader>(*participant_, Topic::kPlanPose);
  alignment_ = std::make_unique<platform::Reader>(*participant_, Topic::kAlignment);
  status_ = std::make_unique<platform::Reader>(*participant_, Topic::kStatus);
  waiter_ = std::make_unique<platform::Waiter>(*participant_);
  waiter_->Attach(*plan_pose_);
  waiter_->Attach(*alignment_);
  waiter_->Attach(*status_);
}

bool HeadsetLink::WaitForDaemon(std::chrono::milliseconds timeout) {
  return WaitUntil(
      [&] {
        return mesh_->MatchedReaders() > 0 && pose_->MatchedReaders() > 0 &&
               command_->MatchedReaders() > 0 && status.has_value();
      },
      timeout);
}

bool HeadsetLink::Send(Topic topic, const google::protobuf::Message& msg, int64_t stamp_ns) {
  platform::Writer* w = topic == Topic::kMeshDelta     ? mesh_.get()
                        : topic == Topic::kHeadsetPose ? pose_.get()
                        : topic == Topic::kCommand     ? command_.get()
                                                       : nullptr;
  if (!w) return false;
  platform::Envelope e;
  e.device_id = device_id_;
  e.seq = w->NextSeq();
  e.stamp_ns = stamp_ns;
  msg.SerializeToString(&e.payload);
  return w->Write(e);
}

void HeadsetLink::Poll() {
  auto take = [&](platform::Reader& reader, auto&& handle) {
    for (const platform::Envelope& e : reader.Take(1024)) {
      if (e.device_id != device_id_) {
        ++foreign_envelopes;
        continue;
      }
      handle(e.payload);
    }
  };
  take(*plan_pose_, [&](const std::string& bytes) {
    v1::PlanPose p;
    if (p.ParseFromString(bytes))
      plan_poses.push_back(std::move(p));
    else
      ++malformed_envelopes;
  });
  take(*alignment_, [&](const std::string& bytes) {
    v1::Alignment a;
    if (a.ParseFromString(bytes))
      alignments.push_back(std::move(a));
    else
      ++malformed_envelopes;
  });
  take(*status_, [&](const std::string& bytes) {
    v1::DaemonStatus s;
    if (!s.ParseFromString(bytes)) {
      ++malformed_envelopes;
      return;
    }
    if (!s.message().empty()) status_messages.push_back(s.message());
    status = std::move(s);
  });
}

}  // namespace floorpose::tools
