#include "platform/recording.h"

#include <google/protobuf/io/zero_copy_stream_impl.h>
#include <google/protobuf/util/delimited_message_util.h>

#include <cstring>

namespace floorpose::platform {

namespace pbu = google::protobuf::util;

v1::Envelope ToProto(const Envelope& e) {
  v1::Envelope p;
  p.set_device_id(e.device_id);
  p.set_seq(e.seq);
  p.set_stamp_ns(e.stamp_ns);
  p.set_payload(e.payload);
  return p;
}

Envelope FromProto(const v1::Envelope& p) {
  return {p.device_id(), p.seq(), p.stamp_ns(), p.payload()};
}

RecordingWriter::RecordingWriter(const std::string& path)
    : out_(path, std::ios::binary | std::ios::trunc) {
  if (!out_) {
    error_ = path + ": cannot open for writing: " + std::strerror(errno);
    return;
  }
  out_.write(kRecordingMagic, sizeof(kRecordingMagic) - 1);
}

bool RecordingWriter::Append(const v1::RecordingRecord& record) {
  if (!ok()) return false;
  if (!pbu::SerializeDelimitedToOstream(record, &out_)) {
    error_ = "write failed";
    return false;
  }
  return true;
}

bool RecordingWriter::Append(int64_t receive_stamp_ns, Topic topic, const Envelope& envelope) {
  v1::RecordingRecord r;
  r.set_receive_stamp_ns(receive_stamp_ns);
  r.set_topic(TopicName(topic));
  *r.mutable_envelope() = ToProto(envelope);
  return Append(r);
}

bool RecordingWriter::Flush() {
  out_.flush();
  return static_cast<bool>(out_);
}

RecordingReader::RecordingReader(const std::string& path) : in_(path, std::ios::binary) {
  if (!in_) {
    error_ = path + ": cannot open: " + std::strerror(errno);
    return;
  }
  char magic[sizeof(kRecordingMagic) - 1] = {};
  in_.read(magic, sizeof(magic));
  if (in_.gcount() != static_cast<std::streamsize>(sizeof(magic)) ||
      std::memcmp(magic, kRecordingMagic, sizeof(magic)) != 0) {
    error_ = path + ": not a floorpose recording (bad magic)";
    return;
  }
  stream_ = std::make_unique<google::protobuf::io::IstreamInputStream>(&in_);
}

RecordingReader::~RecordingReader() = default;

bool RecordingReader::Next(v1::RecordingRecord* record) {
  if (!ok()) return false;
  bool clean_eof = false;
  if (!pbu::ParseDelimitedFromZeroCopyStream(record, stream_.get(), &clean_eof)) {
    if (!clean_eof) error_ = "corrupt record after " + std::to_string(records_) + " records";
    return false;
  }
  ++records_;
  return true;
}

}  // namespace floorpose::platform
