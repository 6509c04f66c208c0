// Recordings: the envelopes as received, each with its receive stamp and topic. The file
// is the 8-byte magic "FPREC01\n" followed by varint-length-delimited RecordingRecord
// messages, so replay feeds the same bytes through the same decode path as live data.
#pragma once

#include <fstream>
#include <memory>
#include <string>

#include "floorpose/v1/floorpose.pb.h"
#include "platform/dds.h"

namespace google::protobuf::io {
class IstreamInputStream;
}

namespace floorpose::platform {

inline constexpr char kRecordingMagic[] = "FPREC01\n";

class RecordingWriter {
 public:
  // Truncates the file. ok() is false (and error() says why) if it cannot be opened.
  explicit RecordingWriter(const std::string& path);
  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  bool Append(int64_t receive_stamp_ns, Topic topic, const Envelope& envelope);
  bool Append(const v1::RecordingRecord& record);
  bool Flush();

 private:
  std::ofstream out_;
  std::string error_;
};

class RecordingReader {
 public:
  explicit RecordingReader(const std::string& path);
  ~RecordingReader();
  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  // False at the end of the file or on a corrupt record (then error() is set).
  bool Next(v1::RecordingRecord* record);
  size_t records_read() const { return records_; }

 private:
  std::ifstream in_;
  std::unique_ptr<google::protobuf::io::IstreamInputStream> stream_;
  std::string error_;
  size_t records_ = 0;
};

// Conversions between the DDS envelope and its recorded form.
v1::Envelope ToProto(const Envelope& e);
Envelope FromProto(const v1::Envelope& e);

}  // namespace floorpose::platform
