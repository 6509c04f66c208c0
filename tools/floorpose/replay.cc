// `floorpose replay`: publishes a recording's envelopes over DDS, byte for byte, at the
// recorded pace (or faster).
#include <spdlog/spdlog.h>

#include <csignal>
#include <map>
#include <memory>
#include <thread>

#include "platform/clock.h"
#include "platform/recording.h"
#include "tools/floorpose/commands.h"
#include "tools/floorpose/dds_options.h"
#include "tools/lib/progress.h"

namespace floorpose::tools {
namespace {

using platform::Topic;

struct ReplayOptions {
  std::string recording;
  double rate = 1.0;
  DdsOptions dds;
  bool all_topics = false;
  double wait_s = 10.0;
};

int RunReplay(const ReplayOptions& o) {
  if (!(o.rate > 0)) {
    spdlog::error("--rate must be positive");
    return 2;
  }
  platform::RecordingReader reader(o.recording);
  if (!reader.ok()) {
    spdlog::error("{}", reader.error());
    return 1;
  }
  std::unique_ptr<platform::Participant> participant;
  try {
    participant = std::make_unique<platform::Participant>(o.dds.domain_id, o.dds.Config());
  } catch (const std::exception& e) {
    spdlog::error("DDS: {}", e.what());
    return 1;
  }
  // Inputs only by default: replaying a daemon's outputs would impersonate it.
  std::map<Topic, std::unique_ptr<platform::Writer>> writers;
  for (Topic t : platform::kAllTopics) {
    const bool input = t == Topic::kMeshDelta || t == Topic::kHeadsetPose || t == Topic::kCommand;
    if (input || o.all_topics) writers[t] = std::make_unique<platform::Writer>(*participant, t);
  }
  // Give subscribers a chance to match, so the first records are not lost.
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::milliseconds(static_cast<int64_t>(o.wait_s * 1000));
  while (writers.begin()->second->MatchedReaders() == 0 &&
         std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  if (writers.begin()->second->MatchedReaders() == 0)
    spdlog::warn("no subscriber matched within {:.0f} s; publishing anyway", o.wait_s);

  v1::RecordingRecord record;
  size_t total = 0;  // on a terminal: the records, counted first, for the progress line
  if (Progress::OnTerminal())
    for (platform::RecordingReader count(o.recording); count.Next(&record);) ++total;
  Progress progress("replay", total, "records");
  int64_t first_stamp = 0;
  const auto start = std::chrono::steady_clock::now();
  size_t sent = 0, skipped = 0;
  while (reader.Next(&record)) {
    const auto topic = platform::TopicFromName(record.topic());
    auto it = topic ? writers.find(*topic) : writers.end();
    if (it == writers.end()) {
      ++skipped;
      continue;
    }
    if (sent == 0) first_stamp = record.receive_stamp_ns();
    const double offset_s =
        static_cast<double>(record.receive_stamp_ns() - first_stamp) * 1e-9 / o.rate;
    std::this_thread::sleep_until(start +
                                  std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                      std::chrono::duration<double>(std::max(0.0, offset_s))));
    std::string error;
    if (!it->second->Write(platform::FromProto(record.envelope()), &error))
      spdlog::warn("record {}: publish failed: {}", reader.records_read(), error);
    ++sent;
    progress.Update(reader.records_read());
  }
  if (!reader.error().empty()) {
    spdlog::error("{}: {}; {} records published before it", o.recording, reader.error(), sent);
    return 1;
  }
  // Let reliable delivery finish before the participant goes away.
  for (auto& [t, w] : writers) w->WaitForAcks(std::chrono::seconds(5));
  spdlog::info("replayed {} records ({} of other topics skipped)", sent, skipped);
  return 0;
}

}  // namespace

Run AddReplayCommand(CLI::App& app) {
  auto o = std::make_shared<ReplayOptions>();
  app.add_option("--recording", o->recording, "recording file")->required();
  app.add_option("--rate", o->rate, "playback speed, times real time")->capture_default_str();
  app.add_flag("--all-topics", o->all_topics, "also publish recorded daemon outputs");
  app.add_option("--wait", o->wait_s, "seconds to wait for a subscriber")->capture_default_str();
  o->dds.Add(app);
  return [o] { return RunReplay(*o); };
}

}  // namespace floorpose::tools
