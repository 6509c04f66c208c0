// `floorpose record`: every floorpose topic, as received, into a recording file.
#include <spdlog/spdlog.h>

#include <cmath>
#include <csignal>
#include <memory>
#include <vector>

#include "platform/clock.h"
#include "platform/recording.h"
#include "tools/floorpose/commands.h"
#include "tools/floorpose/dds_options.h"
#include "tools/lib/progress.h"

namespace floorpose::tools {
namespace {

using platform::Topic;

struct RecordOptions {
  std::string out;
  double duration_s = 0;  // 0 = until SIGINT/SIGTERM
  DdsOptions dds;
};

int RunRecord(const RecordOptions& o) {
  platform::RecordingWriter writer(o.out);
  if (!writer.ok()) {
    spdlog::error("{}", writer.error());
    return 1;
  }
  // Signals are taken synchronously here, between drains of the readers.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  std::unique_ptr<platform::Participant> participant;
  std::vector<std::unique_ptr<platform::Reader>> readers;
  std::unique_ptr<platform::Waiter> waiter;
  try {
    participant = std::make_unique<platform::Participant>(o.dds.domain_id, o.dds.Config());
    waiter = std::make_unique<platform::Waiter>(*participant);
    for (Topic t : platform::kAllTopics) {
      // Every device's inputs: the default partition and each device's own.
      readers.push_back(std::make_unique<platform::Reader>(
          *participant, t, std::vector<std::string>{"", platform::DevicePartition("*")}));
      waiter->Attach(*readers.back());
    }
  } catch (const std::exception& e) {
    spdlog::error("DDS: {}", e.what());
    return 1;
  }
  spdlog::info("recording domain {} to {}", o.dds.domain_id, o.out);
  const int64_t start = platform::MonotonicNs();
  size_t records = 0;
  // With a duration: seconds of it; else records so far.
  Progress progress("record", static_cast<size_t>(std::ceil(o.duration_s)),
                    o.duration_s > 0 ? "s" : "records");
  while (true) {
    waiter->Wait(std::chrono::milliseconds(100));
    const int64_t now = platform::MonotonicNs();
    for (auto& r : readers) {
      for (const platform::Envelope& e : r->Take(1024)) {
        if (!writer.Append(now, r->topic(), e)) {
          spdlog::error("{}: {}", o.out, writer.error());
          return 1;
        }
        ++records;
      }
    }
    timespec zero{0, 0};
    if (sigtimedwait(&signals, nullptr, &zero) > 0) break;
    if (o.duration_s > 0 && static_cast<double>(now - start) * 1e-9 >= o.duration_s) break;
    progress.Update(o.duration_s > 0 ? static_cast<size_t>(static_cast<double>(now - start) * 1e-9)
                                     : records);
  }
  writer.Flush();
  spdlog::info("wrote {} records to {}", records, o.out);
  return writer.ok() ? 0 : 1;
}

}  // namespace

Run AddRecordCommand(CLI::App& app) {
  auto o = std::make_shared<RecordOptions>();
  app.add_option("--out", o->out, "recording file to write")->required();
  app.add_option("--duration", o->duration_s, "stop after this many seconds (0: on SIGINT)")
      ->capture_default_str();
  o->dds.Add(app);
  return [o] { return RunRecord(*o); };
}

}  // namespace floorpose::tools
