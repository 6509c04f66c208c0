#include "platform/logging.h"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/sinks/systemd_sink.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace floorpose::platform {
namespace {

// True when stderr is the journal stream systemd gave us (sd_journal_stream_fd docs:
// JOURNAL_STREAM holds "device:inode" of that stream).
bool StderrIsJournal() {
  const char* env = std::getenv("JOURNAL_STREAM");
  if (!env) return false;
  struct stat st {};
  if (fstat(fileno(stderr), &st) != 0) return false;
  return std::string(env) == std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
}

}  // namespace

bool SetUpLogging(const std::string& program, const std::string& level) {
  std::shared_ptr<spdlog::logger> logger;
  if (StderrIsJournal()) {
    logger = std::make_shared<spdlog::logger>(
        program, std::make_shared<spdlog::sinks::systemd_sink_mt>(program));
    logger->set_pattern("%v");  // the journal stamps and tags every line itself
  } else {
    logger = spdlog::stderr_color_mt(program);
    logger->set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%-5l%$ %v");
  }
  spdlog::set_default_logger(logger);
  const auto parsed = spdlog::level::from_str(level);
  const bool known = spdlog::level::to_string_view(parsed) == level ||
                     (level == "warn" && parsed == spdlog::level::warn);
  spdlog::set_level(known ? parsed : spdlog::level::info);
  return known;
}

}  // namespace floorpose::platform
