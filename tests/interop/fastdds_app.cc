// The HoloLens app's side of the protocol, written with eProsima Fast DDS from
// docs/protocol.md alone: no floorpose DDS code, only the IDL (through fastddsgen) and the
// protobuf messages. It follows section 7 of the document step by step against a real
// floorposed (Cyclone DDS) and streams a simulated walk from a recording (section 8).
//
//   fastdds_app --domain D --device ID --recording walk.rec --plan-id office [--rate 10]
//
// Prints one JSON object: what it sent, the replies, the plan poses it received and their
// error against the recording's ground truth. Exits 1, saying why on stderr, when a step
// of the document cannot be carried out.
#include <google/protobuf/io/zero_copy_stream_impl.h>
#include <google/protobuf/util/delimited_message_util.h>

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "envelopePubSubTypes.h"
#include "floorpose/v1/floorpose.pb.h"

namespace {

namespace dds = eprosima::fastdds::dds;
using Clock = std::chrono::steady_clock;
using floorpose::v1::Command;
using floorpose::v1::CommandReply;
using floorpose::v1::DaemonStatus;
using floorpose::v1::PlanPose;

struct Options {
  uint32_t domain = 0;
  std::string device = "hololens-1";
  std::string recording;
  std::string plan_id;
  double rate = 10;
};

[[noreturn]] void Fail(const std::string& why) {
  std::fprintf(stderr, "fastdds_app: %s\n", why.c_str());
  std::exit(1);
}

// Section 3: reliable everywhere (1 s blocking), the outputs transient-local.
dds::DataWriterQos WriterQos(bool keep_all, int32_t depth) {
  dds::DataWriterQos q = dds::DATAWRITER_QOS_DEFAULT;
  q.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
  q.reliability().max_blocking_time = {1, 0};
  q.durability().kind = dds::VOLATILE_DURABILITY_QOS;
  q.history().kind = keep_all ? dds::KEEP_ALL_HISTORY_QOS : dds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = depth;
  return q;
}

dds::DataReaderQos ReaderQos(bool transient_local, bool keep_all) {
  dds::DataReaderQos q = dds::DATAREADER_QOS_DEFAULT;
  q.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
  q.durability().kind =
      transient_local ? dds::TRANSIENT_LOCAL_DURABILITY_QOS : dds::VOLATILE_DURABILITY_QOS;
  q.history().kind = keep_all ? dds::KEEP_ALL_HISTORY_QOS : dds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = 64;
  return q;
}

class App {
 public:
  explicit App(const Options& o) : o_(o) {
    // Loopback only (section 10): UDPv4 on 127.0.0.1, unicast discovery to the RTPS
    // well-known ports of the first participants of the domain.
    dds::DomainParticipantQos pq = dds::PARTICIPANT_QOS_DEFAULT;
    pq.name("floorpose-fastdds-app");
    auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
    udp->interfaceWhiteList.emplace_back("127.0.0.1");
    pq.transport().user_transports.push_back(udp);
    pq.transport().use_builtin_transports = false;
    for (uint32_t index = 0; index < 10; ++index) {
      eprosima::fastrtps::rtps::Locator_t peer;
      eprosima::fastrtps::rtps::IPLocator::setIPv4(peer, 127, 0, 0, 1);
      peer.port = 7400 + 250 * o.domain + 10 + 2 * index;
      pq.wire_protocol().builtin.initialPeersList.push_back(peer);
    }
    participant_ = dds::DomainParticipantFactory::get_instance()->create_participant(o.domain, pq);
    if (!participant_) Fail("cannot create a Fast DDS participant");
    // Section 2: the one type, registered under the IDL's name.
    dds::TypeSupport type(new floorpose::EnvelopePubSubType());
    if (type.register_type(participant_) != ReturnCode_t::RETCODE_OK)
      Fail("cannot register floorpose::Envelope");
    publisher_ = participant_->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
    subscriber_ = participant_->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
    mesh_ = Writer("floorpose/v1/mesh_delta", WriterQos(true, 1));
    pose_ = Writer("floorpose/v1/headset_pose", WriterQos(false, 64));
    command_ = Writer("floorpose/v1/command", WriterQos(true, 1));
    plan_pose_reader_ = Reader("floorpose/v1/plan_pose", ReaderQos(true, false));
    status_reader_ = Reader("floorpose/v1/status", ReaderQos(true, false));
    reply_reader_ = Reader("floorpose/v1/command_reply", ReaderQos(false, true));
  }

  ~App() {
    participant_->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }

  // Step 2: a status of ours has arrived and our writers and reply reader matched.
  bool WaitForDaemon(std::chrono::seconds timeout) {
    return WaitUntil(
        [&] {
          return status_seen_ && Matched(mesh_) && Matched(pose_) && Matched(command_) &&
                 MatchedWriters(reply_reader_);
        },
        timeout);
  }

  // Sends a command with the next request id and waits for its reply; without one within
  // two seconds, sends it again with a new id (section 7's resend rule: the daemon's
  // reader may not have matched our writer yet, though ours matched it). The request
  // answered is the one reported.
  CommandReply Request(const Command& command, std::chrono::seconds timeout) {
    const auto end = Clock::now() + timeout;
    std::vector<uint64_t> ids;
    const auto answered = [&]() -> std::optional<uint64_t> {
      for (const uint64_t id : ids)
        if (replies_.count(id)) return id;
      return std::nullopt;
    };
    do {
      ids.push_back(Post(command));
      if (WaitUntil([&] { return answered().has_value(); }, std::chrono::seconds(2))) {
        requests_.push_back(*answered());
        return replies_.at(requests_.back());
      }
    } while (Clock::now() < end);
    Fail("no reply to request " + std::to_string(ids.front()) + " nor to its " +
         std::to_string(ids.size() - 1) + " resends");
  }

  // Sends a command whose reply is waited for at the end of the walk.
  void Send(const Command& command) { requests_.push_back(Post(command)); }

  uint64_t Post(Command command) {
    command.set_request_id(++request_id_);
    Publish(command_, command.SerializeAsString(), 0);
    return command.request_id();
  }

  void Publish(dds::DataWriter* w, const std::string& payload, int64_t stamp_ns) {
    floorpose::Envelope e;
    e.device_id(o_.device);
    e.seq(++seq_);
    e.stamp_ns(stamp_ns);
    e.payload(std::vector<uint8_t>(payload.begin(), payload.end()));
    if (!w->write(&e)) Fail("Fast DDS refused a sample on " + w->get_topic()->get_name());
  }

  // Drains the readers.
  void Poll() {
    Take(plan_pose_reader_, [&](const std::string& bytes) {
      PlanPose p;
      if (p.ParseFromString(bytes)) plan_poses_.push_back(std::move(p));
    });
    Take(status_reader_, [&](const std::string& bytes) {
      if (status_.ParseFromString(bytes)) status_seen_ = true;
    });
    Take(reply_reader_, [&](const std::string& bytes) {
      CommandReply r;
      if (r.ParseFromString(bytes)) replies_[r.request_id()] = std::move(r);
    });
  }

  template <typename Pred>
  bool WaitUntil(Pred pred, std::chrono::milliseconds timeout) {
    const auto end = Clock::now() + timeout;
    while (true) {
      Poll();
      if (pred()) return true;
      if (Clock::now() >= end) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

  dds::DataWriter* mesh_ = nullptr;
  dds::DataWriter* pose_ = nullptr;
  dds::DataWriter* command_ = nullptr;
  std::vector<PlanPose> plan_poses_;
  std::map<uint64_t, CommandReply> replies_;
  std::vector<uint64_t> requests_;
  DaemonStatus status_;
  bool status_seen_ = false;

 private:
  dds::Topic* Topic(const std::string& name) {
    dds::Topic* t = participant_->create_topic(name, "floorpose::Envelope", dds::TOPIC_QOS_DEFAULT);
    if (!t) Fail("cannot create topic " + name);
    return t;
  }
  dds::DataWriter* Writer(const std::string& name, const dds::DataWriterQos& q) {
    dds::DataWriter* w = publisher_->create_datawriter(Topic(name), q);
    if (!w) Fail("cannot create a writer on " + name);
    return w;
  }
  dds::DataReader* Reader(const std::string& name, const dds::DataReaderQos& q) {
    dds::DataReader* r = subscriber_->create_datareader(Topic(name), q);
    if (!r) Fail("cannot create a reader on " + name);
    return r;
  }
  static bool Matched(dds::DataWriter* w) {
    dds::PublicationMatchedStatus s;
    return w->get_publication_matched_status(s) == ReturnCode_t::RETCODE_OK && s.current_count > 0;
  }
  static bool MatchedWriters(dds::DataReader* r) {
    dds::SubscriptionMatchedStatus s;
    return r->get_subscription_matched_status(s) == ReturnCode_t::RETCODE_OK && s.current_count > 0;
  }
  // Hands the payloads of our device's samples to handle.
  void Take(dds::DataReader* r, const std::function<void(const std::string&)>& handle) {
    floorpose::Envelope e;
    dds::SampleInfo info;
    while (r->take_next_sample(&e, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data || e.device_id() != o_.device) continue;
      handle(std::string(e.payload().begin(), e.payload().end()));
    }
  }

  Options o_;
  dds::DomainParticipant* participant_ = nullptr;
  dds::Publisher* publisher_ = nullptr;
  dds::Subscriber* subscriber_ = nullptr;
  dds::DataReader* plan_pose_reader_ = nullptr;
  dds::DataReader* status_reader_ = nullptr;
  dds::DataReader* reply_reader_ = nullptr;
  uint64_t seq_ = 0;
  uint64_t request_id_ = 0;
};

// Section 8: "FPREC01\n", then varint-delimited RecordingRecords.
std::vector<floorpose::v1::RecordingRecord> ReadRecording(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[8];
  if (!in.read(magic, 8) || std::memcmp(magic, "FPREC01\n", 8) != 0)
    Fail(path + ": not a floorpose recording");
  google::protobuf::io::IstreamInputStream stream(&in);
  std::vector<floorpose::v1::RecordingRecord> records;
  floorpose::v1::RecordingRecord r;
  bool clean_eof = false;
  while (google::protobuf::util::ParseDelimitedFromZeroCopyStream(&r, &stream, &clean_eof))
    records.push_back(r);
  if (!clean_eof) Fail(path + ": corrupt record after " + std::to_string(records.size()));
  return records;
}

std::string Quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) >= 0x20) out += c;
  }
  return out + "\"";
}

int Run(const Options& o) {
  const auto records = ReadRecording(o.recording);
  App app(o);

  // 2. Wait for the daemon.
  if (!app.WaitForDaemon(std::chrono::seconds(20)))
    Fail("no daemon: no status of device '" + o.device + "' or no matched reader");

  // 3. The current state, and the plans the daemon can load.
  Command get_state;
  get_state.mutable_get_state();
  const CommandReply state = app.Request(get_state, std::chrono::seconds(5));
  if (!state.ok()) Fail("get_state refused: " + state.message());

  // 4. A plan, by id, when the daemon has none.
  if (state.status().state() == DaemonStatus::WAITING_FOR_PLAN) {
    Command load;
    load.mutable_load_plan()->set_plan_id(o.plan_id);
    const CommandReply loaded = app.Request(load, std::chrono::seconds(5));
    if (!loaded.ok()) Fail("load_plan refused: " + loaded.message());
    if (loaded.status().plan_id() != o.plan_id)
      Fail("load_plan: plan_id not in the reply's status");
  }

  // 5 and 6. Stream poses and meshes at the recorded pace, the wall pick when the
  // recording made it (the wearer picks after looking around); collect the outputs as
  // they come.
  std::map<int64_t, std::pair<double, double>> truth;
  size_t poses_sent = 0, meshes_sent = 0;
  const auto start = Clock::now();
  std::optional<int64_t> first_stamp;
  for (const auto& r : records) {
    const std::string& topic = r.topic();
    if (topic == "floorpose/sim/ground_truth") {
      floorpose::v1::GroundTruthPose g;
      if (g.ParseFromString(r.envelope().payload())) truth[g.stamp_ns()] = {g.x(), g.y()};
      continue;
    }
    if (topic != "floorpose/v1/mesh_delta" && topic != "floorpose/v1/headset_pose" &&
        topic != "floorpose/v1/command")
      continue;
    if (!first_stamp) first_stamp = r.receive_stamp_ns();
    const auto due =
        start + std::chrono::nanoseconds(static_cast<int64_t>(
                    static_cast<double>(r.receive_stamp_ns() - *first_stamp) / o.rate));
    while (Clock::now() < due) {
      app.Poll();
      std::this_thread::sleep_until(std::min(due, Clock::now() + std::chrono::milliseconds(5)));
    }
    if (topic == "floorpose/v1/command") {
      Command c;
      if (!c.ParseFromString(r.envelope().payload())) Fail("recording holds a malformed command");
      app.Send(std::move(c));
    } else if (topic == "floorpose/v1/mesh_delta") {
      app.Publish(app.mesh_, r.envelope().payload(), r.envelope().stamp_ns());
      ++meshes_sent;
    } else {
      app.Publish(app.pose_, r.envelope().payload(), r.envelope().stamp_ns());
      ++poses_sent;
    }
  }

  // 8. Every accepted pose gives exactly one plan pose; every command one reply.
  app.WaitUntil(
      [&] {
        return app.plan_poses_.size() >= poses_sent && app.replies_.size() >= app.requests_.size();
      },
      std::chrono::seconds(30));
  // 7. The state after the walk (the status is periodic).
  app.WaitUntil([&] { return app.status_.state() == DaemonStatus::TRACKING; },
                std::chrono::seconds(3));

  double sum = 0;
  size_t scored = 0, reliable = 0, reliable_within_1m = 0;
  for (const PlanPose& p : app.plan_poses_) {
    const auto t = truth.find(p.source_stamp_ns());
    if (p.alignment_version() == 0 || t == truth.end()) continue;
    const double error = std::hypot(p.x() - t->second.first, p.y() - t->second.second);
    sum += error;
    ++scored;
    if (p.reliability().flag() == floorpose::v1::Reliability::RELIABLE) {
      ++reliable;
      reliable_within_1m += error <= 1.0 ? 1 : 0;
    }
  }
  std::ostringstream json;
  json << "{\"poses_sent\": " << poses_sent << ", \"meshes_sent\": " << meshes_sent
       << ", \"plan_poses\": " << app.plan_poses_.size() << ", \"scored_poses\": " << scored
       << ", \"mean_error_m\": " << (scored ? sum / static_cast<double>(scored) : -1)
       << ", \"reliable_poses\": " << reliable << ", \"reliable_within_1m\": " << reliable_within_1m
       << ", \"final_state\": " << Quote(DaemonStatus::State_Name(app.status_.state()))
       << ", \"plans\": [";
  for (int i = 0; i < state.plans_size(); ++i) json << (i ? ", " : "") << Quote(state.plans(i));
  json << "], \"replies\": [";
  for (size_t i = 0; i < app.requests_.size(); ++i) {
    const auto it = app.replies_.find(app.requests_[i]);
    json << (i ? ", " : "") << "{\"request_id\": " << app.requests_[i];
    if (it != app.replies_.end())
      json << ", \"command\": " << Quote(it->second.command())
           << ", \"ok\": " << (it->second.ok() ? "true" : "false")
           << ", \"message\": " << Quote(it->second.message());
    json << "}";
  }
  json << "]}";
  std::printf("%s\n", json.str().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i], value = argv[i + 1];
    if (flag == "--domain")
      o.domain = static_cast<uint32_t>(std::stoul(value));
    else if (flag == "--device")
      o.device = value;
    else if (flag == "--recording")
      o.recording = value;
    else if (flag == "--plan-id")
      o.plan_id = value;
    else if (flag == "--rate")
      o.rate = std::stod(value);
    else
      Fail("unknown option " + flag);
  }
  if (o.recording.empty() || o.plan_id.empty() || !(o.rate > 0))
    Fail("usage: fastdds_app --domain D --device ID --recording FILE --plan-id ID [--rate R]");
  return Run(o);
}
