// Recordings: magic, then varint-delimited RecordingRecord messages. Replay must get
// back exactly what was written, keep the good records of a damaged file, and refuse
// files that are not recordings.
#include "platform/recording.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/stubs/logging.h>

#include <filesystem>
#include <iterator>

#include "core/random.h"
#include "tests/test_util.h"

namespace floorpose::platform {
namespace {

using ::testing::HasSubstr;

class RecordingTest : public testing::TempDirTest {
 protected:
  // N records on every topic in turn, with binary payloads of varying size (zero bytes
  // included) and increasing receive stamps.
  std::vector<v1::RecordingRecord> MakeRecords(size_t n) {
    SplitMix64 rng(71);
    std::vector<v1::RecordingRecord> out;
    for (size_t i = 0; i < n; ++i) {
      const Topic topic = kAllTopics[i % std::size(kAllTopics)];
      Envelope e;
      e.device_id = "hololens-" + std::to_string(i % 3);
      e.seq = i;
      e.stamp_ns = static_cast<int64_t>(1'000'000 * i) - 5;
      e.payload.resize(rng.Next() % (i == 7 ? 200000 : 300));
      for (char& c : e.payload) c = static_cast<char>(rng.Next() & 0xff);
      v1::RecordingRecord r;
      r.set_receive_stamp_ns(static_cast<int64_t>(2'000'000 * i));
      r.set_topic(TopicName(topic));
      *r.mutable_envelope() = ToProto(e);
      out.push_back(r);
    }
    return out;
  }

  std::string WriteRecording(const std::string& name,
                             const std::vector<v1::RecordingRecord>& records) {
    const std::string path = Path(name);
    RecordingWriter writer(path);
    EXPECT_TRUE(writer.ok()) << writer.error();
    for (const auto& r : records) EXPECT_TRUE(writer.Append(r));
    EXPECT_TRUE(writer.Flush());
    return path;
  }

  // Reads until Next() returns false.
  static std::vector<v1::RecordingRecord> ReadAll(RecordingReader& reader) {
    std::vector<v1::RecordingRecord> out;
    v1::RecordingRecord r;
    while (reader.Next(&r)) out.push_back(r);
    return out;
  }

  static void ExpectSame(const std::vector<v1::RecordingRecord>& got,
                         const std::vector<v1::RecordingRecord>& want, size_t n) {
    ASSERT_GE(got.size(), n);
    ASSERT_GE(want.size(), n);
    for (size_t i = 0; i < n; ++i)
      EXPECT_EQ(got[i].SerializeAsString(), want[i].SerializeAsString()) << "record " << i;
  }
};

TEST_F(RecordingTest, RoundTrip) {
  const auto records = MakeRecords(40);
  const std::string path = WriteRecording("good.rec", records);
  RecordingReader reader(path);
  ASSERT_TRUE(reader.ok()) << reader.error();
  const auto got = ReadAll(reader);
  EXPECT_TRUE(reader.ok()) << reader.error();  // a clean end is not an error
  ASSERT_EQ(got.size(), records.size());
  ExpectSame(got, records, records.size());
  EXPECT_EQ(reader.records_read(), records.size());
  // The topic names map back to topics, and the envelope survives the conversions.
  for (size_t i = 0; i < got.size(); ++i) {
    ASSERT_TRUE(TopicFromName(got[i].topic()).has_value()) << got[i].topic();
    EXPECT_EQ(*TopicFromName(got[i].topic()), kAllTopics[i % std::size(kAllTopics)]);
    const Envelope e = FromProto(got[i].envelope());
    EXPECT_EQ(e.seq, i);
    EXPECT_EQ(e.payload, records[i].envelope().payload());
  }
}

TEST_F(RecordingTest, AppendFromEnvelope) {
  const std::string path = Path("env.rec");
  {
    RecordingWriter writer(path);
    ASSERT_TRUE(writer.ok()) << writer.error();
    ASSERT_TRUE(writer.Append(99, Topic::kHeadsetPose, {"dev", 5, -7, std::string("\0x", 2)}));
  }  // the destructor closes the file
  RecordingReader reader(path);
  v1::RecordingRecord r;
  ASSERT_TRUE(reader.Next(&r)) << reader.error();
  EXPECT_EQ(r.receive_stamp_ns(), 99);
  EXPECT_EQ(r.topic(), TopicName(Topic::kHeadsetPose));
  EXPECT_EQ(r.envelope().device_id(), "dev");
  EXPECT_EQ(r.envelope().seq(), 5u);
  EXPECT_EQ(r.envelope().stamp_ns(), -7);
  EXPECT_EQ(r.envelope().payload(), std::string("\0x", 2));
  EXPECT_FALSE(reader.Next(&r));
}

TEST_F(RecordingTest, EmptyRecordingHasNoRecords) {
  const std::string path = WriteRecording("empty.rec", {});
  EXPECT_EQ(std::filesystem::file_size(path), 8u);  // just the magic
  RecordingReader reader(path);
  ASSERT_TRUE(reader.ok()) << reader.error();
  v1::RecordingRecord r;
  EXPECT_FALSE(reader.Next(&r));
  EXPECT_TRUE(reader.ok());
}

TEST_F(RecordingTest, TruncatedFileKeepsTheGoodRecords) {
  // Cut the file at every byte inside the last record (as a crash while writing
  // would): the reader returns the earlier records, then stops with an error.
  const auto records = MakeRecords(6);
  const std::string full_path = WriteRecording("full.rec", records);
  const std::string full = testing::ReadText(full_path);
  const size_t last_size = records.back().ByteSizeLong();
  const size_t last_start =
      full.size() - last_size -
      google::protobuf::io::CodedOutputStream::VarintSize32(static_cast<uint32_t>(last_size));
  for (size_t cut = last_start + 1; cut < full.size(); ++cut) {
    SCOPED_TRACE("cut at " + std::to_string(cut) + " of " + std::to_string(full.size()));
    // A cut inside the topic string makes protobuf log a UTF-8 complaint before it
    // fails; expected here, so kept out of the test output.
    const google::protobuf::LogSilencer quiet;
    RecordingReader reader(Write("cut.rec", full.substr(0, cut)));
    ASSERT_TRUE(reader.ok()) << reader.error();
    const auto got = ReadAll(reader);
    EXPECT_EQ(got.size(), records.size() - 1);
    ExpectSame(got, records, records.size() - 1);
    EXPECT_FALSE(reader.ok());
    EXPECT_THAT(reader.error(), HasSubstr("corrupt record after 5 records"));
    v1::RecordingRecord r;
    EXPECT_FALSE(reader.Next(&r));  // and stays stopped
  }
}

TEST_F(RecordingTest, CorruptLengthStopsWithError) {
  // A length prefix far beyond the end of the file.
  const auto records = MakeRecords(3);
  std::string bytes = testing::ReadText(WriteRecording("full.rec", records));
  bytes += std::string("\xff\xff\xff\x0f", 4);
  RecordingReader reader(Write("bad_length.rec", bytes));
  const auto got = ReadAll(reader);
  EXPECT_EQ(got.size(), 3u);
  EXPECT_FALSE(reader.ok());
  EXPECT_THAT(reader.error(), HasSubstr("corrupt record after 3 records"));
}

TEST_F(RecordingTest, BadMagicIsRejected) {
  for (const std::string& bytes : {std::string("FPREC02\n"), std::string("FPREC0"), std::string(),
                                   std::string("\x08\x01\x12\x03"
                                               "abc",
                                               7)}) {
    const std::string path = Write("bad.rec", bytes);
    RecordingReader reader(path);
    EXPECT_FALSE(reader.ok());
    EXPECT_THAT(reader.error(), HasSubstr("bad magic"));
    EXPECT_THAT(reader.error(), HasSubstr(path));
    v1::RecordingRecord r;
    EXPECT_FALSE(reader.Next(&r));
  }
}

TEST_F(RecordingTest, UnopenableFiles) {
  RecordingReader reader(Path("missing.rec"));
  EXPECT_FALSE(reader.ok());
  EXPECT_THAT(reader.error(), HasSubstr("missing.rec"));

  RecordingWriter writer(Path("no/such/dir/out.rec"));
  EXPECT_FALSE(writer.ok());
  EXPECT_THAT(writer.error(), HasSubstr("cannot open"));
  EXPECT_FALSE(writer.Append(v1::RecordingRecord()));
}

TEST(TopicTest, NamesRoundTrip) {
  for (Topic t : kAllTopics) {
    ASSERT_NE(TopicName(t), nullptr);
    EXPECT_EQ(TopicFromName(TopicName(t)), t);
  }
  EXPECT_FALSE(TopicFromName("floorpose/NoSuchTopic").has_value());
  EXPECT_FALSE(TopicFromName("").has_value());
}

}  // namespace
}  // namespace floorpose::platform
