#include "platform/dds.h"

#include <array>
#include <filesystem>
#include <stdexcept>
#include <utility>

#include "envelope.h"

namespace floorpose::platform {
namespace {

struct TopicSpec {
  Topic topic;
  const char* name;
  bool durable;   // transient-local, keep-last 1: late joiners get the latest at once
  int32_t depth;  // keep-last depth; 0 = keep-all
};

constexpr std::array<TopicSpec, 11> kSpecs = {{
    {Topic::kMeshDelta, "floorpose/v1/mesh_delta", false, 0},
    {Topic::kHeadsetPose, "floorpose/v1/headset_pose", false, 64},
    {Topic::kCommand, "floorpose/v1/command", false, 0},
    {Topic::kPlanPose, "floorpose/v1/plan_pose", true, 1},
    {Topic::kAlignment, "floorpose/v1/alignment", true, 1},
    {Topic::kStatus, "floorpose/v1/status", true, 1},
    {Topic::kPlanTrack, "floorpose/v1/plan_track", true, 1},
    // Volatile: a reply is for the app that asked, now; a later app must not get old
    // replies whose request ids it may reuse.
    {Topic::kCommandReply, "floorpose/v1/command_reply", false, 0},
    {Topic::kExplored, "floorpose/v1/explored", true, 1},
    {Topic::kAlert, "floorpose/v1/alert", true, 1},
    // Keyed by the marker's id (the envelope's device_id on this topic): a writer keeps
    // the latest revision of every marker it wrote for the readers that join later.
    {Topic::kMarker, "floorpose/v1/marker", true, 1},
}};

const TopicSpec& Spec(Topic t) { return kSpecs[static_cast<size_t>(t)]; }

// Keep-all inputs are still bounded: a stuck daemon must not grow without limit.
constexpr int32_t kKeepAllMaxSamples = 1024;

dds_qos_t* MakeQos(Topic t, bool for_reader) {
  const TopicSpec& s = Spec(t);
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(q, s.durable ? DDS_DURABILITY_TRANSIENT_LOCAL : DDS_DURABILITY_VOLATILE);
  if (s.depth == 0) {
    dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
    dds_qset_resource_limits(q, kKeepAllMaxSamples, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
  } else {
    // Readers of the durable outputs keep a little more than the writer, so a reader
    // that drains in bursts sees every plan pose.
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, for_reader && s.durable ? 64 : s.depth);
  }
  return q;
}

void Check(dds_return_t rc, const char* what) {
  if (rc < 0) throw std::runtime_error(std::string(what) + ": " + dds_strretcode(rc));
}

// Where the build found the DDS Security plugins (Debian's libddsc0 keeps them in a
// directory of its own, off the loader path).
constexpr const char* kDebianSecurityPluginDir = FLOORPOSE_DDS_SECURITY_DIR;

}  // namespace

const char* TopicName(Topic topic) { return Spec(topic).name; }

std::optional<Topic> TopicFromName(std::string_view name) {
  for (const TopicSpec& s : kSpecs)
    if (name == s.name) return s.topic;
  return std::nullopt;
}

DdsSecurity SecurityFilesIn(const std::string& dir, const std::string& name) {
  const std::filesystem::path d(dir);
  return {(d / "ca.pem").string(),
          (d / (name + ".pem")).string(),
          (d / (name + ".key")).string(),
          (d / "ca.pem").string(),
          (d / "governance.p7s").string(),
          (d / "permissions.p7s").string(),
          ""};
}

std::string LoopbackCycloneConfig() {
  return "<CycloneDDS><Domain Id=\"any\"><General>"
         "<Interfaces><NetworkInterface address=\"127.0.0.1\"/></Interfaces>"
         "<AllowMulticast>false</AllowMulticast></General>"
         "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
         "<MaxAutoParticipantIndex>60</MaxAutoParticipantIndex>"
         "<Peers><Peer Address=\"127.0.0.1\"/></Peers></Discovery>"
         "</Domain></CycloneDDS>";
}

Participant::Participant(uint32_t domain_id, const std::string& cyclone_config,
                         const DdsSecurity* security) {
  if (!cyclone_config.empty()) {
    domain_ = dds_create_domain(domain_id, cyclone_config.c_str());
    // This process has the domain already (another participant made it, with its own
    // configuration): join it. That participant owns the domain and must outlive this one.
    if (domain_ == DDS_RETCODE_PRECONDITION_NOT_MET)
      domain_ = 0;
    else
      Check(domain_, "dds_create_domain");
  }
  dds_qos_t* qos = nullptr;
  if (security) {
    const std::string dir =
        security->plugin_dir.empty() ? kDebianSecurityPluginDir : security->plugin_dir;
    auto file = [](const std::string& path) {
      return "file:" + std::filesystem::absolute(path).string();
    };
    qos = dds_create_qos();
    const std::pair<const char*, std::string> props[] = {
        {"dds.sec.auth.library.path", dir + "/libdds_security_auth.so"},
        {"dds.sec.auth.library.init", "init_authentication"},
        {"dds.sec.auth.library.finalize", "finalize_authentication"},
        {"dds.sec.auth.identity_ca", file(security->identity_ca)},
        {"dds.sec.auth.identity_certificate", file(security->identity_certificate)},
        {"dds.sec.auth.private_key", file(security->private_key)},
        {"dds.sec.crypto.library.path", dir + "/libdds_security_crypto.so"},
        {"dds.sec.crypto.library.init", "init_crypto"},
        {"dds.sec.crypto.library.finalize", "finalize_crypto"},
        {"dds.sec.access.library.path", dir + "/libdds_security_ac.so"},
        {"dds.sec.access.library.init", "init_access_control"},
        {"dds.sec.access.library.finalize", "finalize_access_control"},
        {"dds.sec.access.permissions_ca", file(security->permissions_ca)},
        {"dds.sec.access.governance", file(security->governance)},
        {"dds.sec.access.permissions", file(security->permissions)},
    };
    for (const auto& [name, value] : props) dds_qset_prop(qos, name, value.c_str());
  }
  participant_ = dds_create_participant(domain_id, qos, nullptr);
  if (qos) dds_delete_qos(qos);
  if (participant_ < 0) {
    if (domain_ > 0) dds_delete(domain_);
    Check(participant_, "dds_create_participant");
  }
  for (const TopicSpec& s : kSpecs) {
    dds_qos_t* q = MakeQos(s.topic, false);
    const dds_entity_t topic =
        dds_create_topic(participant_, &floorpose_Envelope_desc, s.name, q, nullptr);
    dds_delete_qos(q);
    // A topic this identity has no grant on at all (a dashboard's inputs) stays unmade:
    // making a reader or writer on it then fails with Cyclone's reason.
    if (topic < 0 && topic != DDS_RETCODE_NOT_ALLOWED_BY_SECURITY) {
      dds_delete(participant_);
      if (domain_ > 0) dds_delete(domain_);
      Check(topic, "dds_create_topic");
    }
    topics_.push_back(topic);
  }
}

Participant::~Participant() {
  dds_delete(participant_);
  if (domain_ > 0) dds_delete(domain_);
}

std::string DevicePartition(const std::string& device_id) { return "device/" + device_id; }

namespace {

// A publisher or subscriber of its own in `partitions`; 0 (the participant's default one)
// when there are none.
dds_entity_t InPartitions(const Participant& participant,
                          const std::vector<std::string>& partitions, bool subscriber) {
  if (partitions.empty()) return 0;
  std::vector<const char*> names;
  for (const std::string& p : partitions) names.push_back(p.c_str());
  dds_qos_t* q = dds_create_qos();
  dds_qset_partition(q, static_cast<uint32_t>(names.size()), names.data());
  const dds_entity_t e = subscriber ? dds_create_subscriber(participant.entity(), q, nullptr)
                                    : dds_create_publisher(participant.entity(), q, nullptr);
  dds_delete_qos(q);
  Check(e, subscriber ? "dds_create_subscriber" : "dds_create_publisher");
  return e;
}

}  // namespace

Writer::Writer(const Participant& participant, Topic topic,
               const std::vector<std::string>& partitions)
    : topic_(topic) {
  Check(participant.topic(topic), (std::string("dds_create_topic ") + TopicName(topic)).c_str());
  publisher_ = InPartitions(participant, partitions, /*subscriber=*/false);
  dds_qos_t* q = MakeQos(topic, false);
  writer_ = dds_create_writer(publisher_ ? publisher_ : participant.entity(),
                              participant.topic(topic), q, nullptr);
  dds_delete_qos(q);
  if (writer_ < 0 && publisher_) dds_delete(publisher_);
  Check(writer_, "dds_create_writer");
}

Writer::~Writer() { dds_delete(publisher_ ? publisher_ : writer_); }

bool Writer::WriteMessage(const std::string& key, const google::protobuf::MessageLite& message,
                          int64_t stamp_ns, std::string* error) {
  Envelope e;
  e.device_id = key;
  e.seq = NextSeq();
  e.stamp_ns = stamp_ns;
  message.SerializeToString(&e.payload);
  return Write(e, error);
}

bool Writer::Write(const Envelope& e, std::string* error) {
  floorpose_Envelope sample{};
  sample.device_id = const_cast<char*>(e.device_id.c_str());
  sample.seq = e.seq;
  sample.stamp_ns = e.stamp_ns;
  sample.payload._length = static_cast<uint32_t>(e.payload.size());
  sample.payload._maximum = sample.payload._length;
  sample.payload._buffer = reinterpret_cast<uint8_t*>(const_cast<char*>(e.payload.data()));
  sample.payload._release = false;
  const dds_return_t rc = dds_write(writer_, &sample);
  if (rc < 0 && error) *error = dds_strretcode(rc);
  return rc >= 0;
}

int Writer::MatchedReaders() const {
  dds_publication_matched_status_t st{};
  if (dds_get_publication_matched_status(writer_, &st) < 0) return 0;
  return static_cast<int>(st.current_count);
}

bool Writer::WaitForAcks(std::chrono::milliseconds timeout) {
  return dds_wait_for_acks(writer_, DDS_MSECS(timeout.count())) == DDS_RETCODE_OK;
}

Reader::Reader(const Participant& participant, Topic topic,
               const std::vector<std::string>& partitions)
    : topic_(topic) {
  Check(participant.topic(topic), (std::string("dds_create_topic ") + TopicName(topic)).c_str());
  subscriber_ = InPartitions(participant, partitions, /*subscriber=*/true);
  dds_qos_t* q = MakeQos(topic, true);
  reader_ = dds_create_reader(subscriber_ ? subscriber_ : participant.entity(),
                              participant.topic(topic), q, nullptr);
  dds_delete_qos(q);
  if (reader_ < 0 && subscriber_) dds_delete(subscriber_);
  Check(reader_, "dds_create_reader");
}

Reader::~Reader() { dds_delete(subscriber_ ? subscriber_ : reader_); }

std::vector<Envelope> Reader::Take(size_t max) {
  constexpr size_t kBatch = 64;
  std::vector<Envelope> out;
  void* samples[kBatch];
  dds_sample_info_t infos[kBatch];
  while (out.size() < max) {
    samples[0] = nullptr;  // let Cyclone loan the buffers
    const size_t want = std::min(kBatch, max - out.size());
    const dds_return_t n = dds_take(reader_, samples, infos, want, static_cast<uint32_t>(want));
    if (n <= 0) break;
    for (dds_return_t i = 0; i < n; ++i) {
      if (!infos[i].valid_data) continue;
      const auto* s = static_cast<const floorpose_Envelope*>(samples[i]);
      Envelope e;
      e.device_id = s->device_id ? s->device_id : "";
      e.seq = s->seq;
      e.stamp_ns = s->stamp_ns;
      e.source_timestamp_ns = infos[i].source_timestamp;
      e.payload.assign(reinterpret_cast<const char*>(s->payload._buffer), s->payload._length);
      out.push_back(std::move(e));
    }
    dds_return_loan(reader_, samples, n);
    if (static_cast<size_t>(n) < want) break;
  }
  return out;
}

int Reader::MatchedWriters() const {
  dds_subscription_matched_status_t st{};
  if (dds_get_subscription_matched_status(reader_, &st) < 0) return 0;
  return static_cast<int>(st.current_count);
}

Reader::Losses Reader::TakeLosses() {
  // Reading a status resets its change counts.
  Losses l;
  dds_sample_lost_status_t lost{};
  if (dds_get_sample_lost_status(reader_, &lost) == DDS_RETCODE_OK)
    l.lost = static_cast<uint64_t>(std::max<int32_t>(0, lost.total_count_change));
  dds_sample_rejected_status_t rejected{};
  if (dds_get_sample_rejected_status(reader_, &rejected) == DDS_RETCODE_OK)
    l.rejected = static_cast<uint64_t>(std::max<int32_t>(0, rejected.total_count_change));
  return l;
}

Waiter::Waiter(const Participant& participant) {
  waitset_ = dds_create_waitset(participant.entity());
  Check(waitset_, "dds_create_waitset");
  guard_ = dds_create_guardcondition(participant.entity());
  Check(guard_, "dds_create_guardcondition");
  Check(dds_waitset_attach(waitset_, guard_, guard_), "dds_waitset_attach");
}

Waiter::~Waiter() {
  for (dds_entity_t c : conditions_) dds_delete(c);
  dds_delete(guard_);
  dds_delete(waitset_);
}

void Waiter::Attach(const Reader& reader) {
  const dds_entity_t cond = dds_create_readcondition(reader.entity(), DDS_ANY_STATE);
  Check(cond, "dds_create_readcondition");
  conditions_.push_back(cond);
  Check(dds_waitset_attach(waitset_, cond, cond), "dds_waitset_attach");
}

bool Waiter::Wait(std::chrono::nanoseconds timeout) {
  dds_attach_t triggered[16];
  const dds_return_t n = dds_waitset_wait(waitset_, triggered, 16, timeout.count());
  bool woken = false;
  for (dds_return_t i = 0; i < n && i < 16; ++i) {
    if (triggered[i] == static_cast<dds_attach_t>(guard_)) {
      bool was = false;
      dds_take_guardcondition(guard_, &was);
      woken = woken || was;
    }
  }
  return woken;
}

void Waiter::Wake() { dds_set_guardcondition(guard_, true); }

}  // namespace floorpose::platform
