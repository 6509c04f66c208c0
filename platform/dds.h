// Cyclone DDS (C API) carrying protobuf payloads in the floorpose Envelope.
// One participant per process, one topic per message kind, QoS per topic fixed here and
// documented in docs/protocol.md. No work happens on Cyclone's threads: readers are
// drained on the owner's thread, woken by a WaitSet.
#pragma once

#include <dds/dds.h>
#include <google/protobuf/message_lite.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace floorpose::platform {

// Topic names and their QoS.
enum class Topic {
  kMeshDelta,     // headset -> daemon: reliable, keep-all (bounded), volatile
  kHeadsetPose,   // headset -> daemon: reliable, keep-last 64, volatile
  kCommand,       // app -> daemon: reliable, keep-all (bounded), volatile
  kPlanPose,      // daemon -> all: reliable, transient-local, keep-last 1 per device
  kAlignment,     // daemon -> all: reliable, transient-local, keep-last 1 per device
  kStatus,        // daemon -> all: reliable, transient-local, keep-last 1 per device
  kPlanTrack,     // daemon -> all: reliable, transient-local, keep-last 1 per device
  kCommandReply,  // daemon -> app: reliable, keep-all (bounded), volatile
  kExplored,      // daemon -> all: reliable, transient-local, keep-last 1 per device
  kAlert,         // daemon -> all: reliable, transient-local, keep-last 1 per device
  kMarker,        // all -> all: reliable, transient-local, keep-last 1 per marker id
};
inline constexpr Topic kAllTopics[] = {Topic::kMeshDelta, Topic::kHeadsetPose,  Topic::kCommand,
                                       Topic::kPlanPose,  Topic::kAlignment,    Topic::kStatus,
                                       Topic::kPlanTrack, Topic::kCommandReply, Topic::kExplored,
                                       Topic::kAlert,     Topic::kMarker};
const char* TopicName(Topic topic);
std::optional<Topic> TopicFromName(std::string_view name);

// One received or sent envelope.
struct Envelope {
  std::string device_id;
  uint64_t seq = 0;
  int64_t stamp_ns = 0;
  std::string payload;  // serialized protobuf
  // Received ones: when the writer wrote it, on the writer's CLOCK_REALTIME (DDS source
  // timestamp); comparable across the processes of one machine.
  int64_t source_timestamp_ns = 0;
};

class Participant;

// The DDS partition a headset's inputs travel in: "device/<device id>". floorposed reads
// its own device's partition and the default one; with DDS Security a headset identity
// is granted only its own device's partition (tools/make-dds-security.sh), so it cannot
// feed another wearer's daemon.
std::string DevicePartition(const std::string& device_id);

class Writer {
 public:
  // In `partitions` (none: the default partition).
  Writer(const Participant& participant, Topic topic,
         const std::vector<std::string>& partitions = {});
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;
  // Returns false (and says why in *error) when DDS refuses the sample.
  bool Write(const Envelope& envelope, std::string* error = nullptr);
  // `message` in an envelope keyed by `key` (the device id; a marker's id on the marker
  // topic), with this writer's next seq and `stamp_ns`.
  bool WriteMessage(const std::string& key, const google::protobuf::MessageLite& message,
                    int64_t stamp_ns, std::string* error = nullptr);
  // The next sequence number of this writer (envelope seq counts per writer, from 1).
  uint64_t NextSeq() { return ++seq_; }
  // Number of matched readers (for start-up synchronisation in tools and tests).
  int MatchedReaders() const;
  // Blocks until matched reliable readers acknowledged everything written, or timeout.
  bool WaitForAcks(std::chrono::milliseconds timeout);
  Topic topic() const { return topic_; }

 private:
  Topic topic_;
  dds_entity_t publisher_ = 0;  // its own, when it has partitions
  dds_entity_t writer_ = 0;
  uint64_t seq_ = 0;
};

class Reader {
 public:
  // In `partitions` (none: the default partition; wildcards allowed).
  Reader(const Participant& participant, Topic topic,
         const std::vector<std::string>& partitions = {});
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;
  // Takes up to max samples now available; invalid samples (disposals) are skipped.
  std::vector<Envelope> Take(size_t max = 64);
  int MatchedWriters() const;
  // Samples DDS lost (never delivered whole: a gap in a writer's sequence, a sample too
  // large to reassemble) or rejected (over this reader's resource limits) since the last
  // call.
  struct Losses {
    uint64_t lost = 0, rejected = 0;
  };
  Losses TakeLosses();
  Topic topic() const { return topic_; }
  dds_entity_t entity() const { return reader_; }

 private:
  Topic topic_;
  dds_entity_t subscriber_ = 0;  // its own, when it has partitions
  dds_entity_t reader_ = 0;
};

// A WaitSet over readers plus a guard condition to wake it (for shutdown).
class Waiter {
 public:
  explicit Waiter(const Participant& participant);
  ~Waiter();
  Waiter(const Waiter&) = delete;
  Waiter& operator=(const Waiter&) = delete;
  void Attach(const Reader& reader);
  // Blocks until data arrives, Wake() is called, or the timeout passes. Returns true when
  // woken by Wake() (the flag is cleared).
  bool Wait(std::chrono::nanoseconds timeout);
  void Wake();  // thread-safe

 private:
  dds_entity_t waitset_ = 0;
  dds_entity_t guard_ = 0;
  std::vector<dds_entity_t> conditions_;
};

// DDS Security (OMG DDS-Security 1.1, Cyclone's built-in plugins): PEM files and the two
// signed access-control documents (S/MIME, .p7s), as tools/make-dds-security.sh makes
// them. Paths; the plugins read them when the participant is created.
struct DdsSecurity {
  std::string identity_ca, identity_certificate, private_key;
  std::string permissions_ca, governance, permissions;
  std::string plugin_dir;  // where libdds_security_*.so are; empty: Debian's libddsc0debian
};

// The files tools/make-dds-security.sh writes to `dir` for participant `name`.
DdsSecurity SecurityFilesIn(const std::string& dir, const std::string& name);

class Participant {
 public:
  // `cyclone_config` is Cyclone XML (or a file:// URI); empty uses CYCLONEDDS_URI. With
  // `security`, the participant authenticates, is access-controlled and encrypts as the
  // governance says; one that cannot (a missing file, a bad signature) fails to start.
  // Throws std::runtime_error when DDS cannot start. A second participant of a domain in
  // one process joins the first one's domain (and configuration); the first must outlive it.
  Participant(uint32_t domain_id, const std::string& cyclone_config,
              const DdsSecurity* security = nullptr);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;
  dds_entity_t entity() const { return participant_; }
  dds_entity_t topic(Topic t) const { return topics_[static_cast<size_t>(t)]; }

 private:
  dds_entity_t domain_ = 0;
  dds_entity_t participant_ = 0;
  std::vector<dds_entity_t> topics_;
};

// Cyclone XML that keeps all traffic on the loopback interface with unicast discovery:
// for tests, the demo and benchmarks (a unique domain id each keeps them apart).
std::string LoopbackCycloneConfig();

}  // namespace floorpose::platform
