// systemd/floorposed.conf, the shipped configuration, lists every option of
// floorpose.v1.FloorposedConfig commented out at its default, under a note saying what it
// does and "Default X.". These tests keep that promise as the schema changes: the file
// loads as shipped, the commented-out options parse when enabled (no unknown or removed
// fields), every value and every "Default X." note in it is the schema's default, and no
// option of the schema is missing from it.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <google/protobuf/text_format.h>

#include <filesystem>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "platform/config.h"
#include "tests/test_util.h"

#ifndef FLOORPOSE_SOURCE_DIR
#error "FLOORPOSE_SOURCE_DIR (the source tree) must be defined, see tests/CMakeLists.txt"
#endif

namespace floorpose::platform {
namespace {

using ::testing::IsEmpty;
namespace pb = google::protobuf;

const char kShippedConfig[] = FLOORPOSE_SOURCE_DIR "/systemd/floorposed.conf";

std::string ReadShippedConfig() {
  EXPECT_TRUE(std::filesystem::is_regular_file(kShippedConfig)) << "cannot read " << kShippedConfig;
  return testing::ReadText(kShippedConfig);
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// One line of the file: an option (`name: value`), a section opening (`name {`) or
// closing (`}`), each either live or commented out (`#` and any indentation before it);
// prose (any other comment line); or anything else (blank lines, whatever the parser
// gets to judge). A commented-out option's value must be one text-format token (a quoted
// string, a number or name, or a [list]), so that prose such as "# comments: an option
// left commented out ..." stays prose.
struct Line {
  enum Kind { kOption, kOpen, kClose, kProse, kOther } kind = kOther;
  bool commented = false;
  std::string name;   // of the option or section
  std::string value;  // of the option, as written
  std::string code;   // the line without its comment marker
};

Line Classify(const std::string& text) {
  static const std::regex option(
      R"(^\s*(#\s*)?([a-z_]\w*)\s*:\s*("(?:[^"\\]|\\.)*"|[-+.\w]+|\[[^\]]*\])\s*$)");
  static const std::regex open(R"(^\s*(#\s*)?([a-z_]\w*)\s*\{\s*$)");
  static const std::regex close(R"(^\s*(#\s*)?\}\s*$)");
  static const std::regex prose(R"(^\s*#)");
  Line line;
  std::smatch m;
  if (std::regex_match(text, m, option)) {
    line.kind = Line::kOption;
    line.name = m[2];
    line.value = m[3];
  } else if (std::regex_match(text, m, open)) {
    line.kind = Line::kOpen;
    line.name = m[2];
  } else if (std::regex_match(text, m, close)) {
    line.kind = Line::kClose;
  } else if (std::regex_search(text, prose)) {
    line.kind = Line::kProse;
    return line;
  } else {
    return line;
  }
  line.commented = m[1].matched;
  line.code = text;
  if (line.commented) {  // drop "# " (or "#"), keeping the indentation after it
    const size_t hash = text.find('#');
    const size_t n = hash + 1 < text.size() && text[hash + 1] == ' ' ? 2 : 1;
    line.code.erase(hash, n);
  }
  return line;
}

// The file with every commented-out option and section enabled and the prose blanked
// (line numbers stay those of the file, for the parser's messages).
std::string Uncomment(const std::string& text) {
  std::string out;
  for (const std::string& text_line : Lines(text)) {
    const Line line = Classify(text_line);
    if (line.kind == Line::kProse) {
      out += "\n";
    } else if (line.kind == Line::kOther) {
      out += text_line + "\n";
    } else {
      out += line.code + "\n";
    }
  }
  return out;
}

std::string Join(const std::string& prefix, const std::string& name) {
  return prefix.empty() ? name : prefix + "." + name;
}

std::string ValueText(const pb::Message& m, const pb::FieldDescriptor* f) {
  std::string text;
  pb::TextFormat::PrintFieldValueToString(m, f, -1, &text);
  return text;
}

// The schema's default of a singular scalar field of `m`'s type, as text format.
std::string DefaultText(const pb::Message& m, const pb::FieldDescriptor* f) {
  const std::unique_ptr<pb::Message> empty(m.New());
  return ValueText(*empty, f);
}

// Every singular scalar field `documented` sets (recursively) must hold the schema's
// default, unless the live file sets it too: those are the site's settings (plan_path).
// Values are compared as printed text, which round-trips doubles exactly.
void CheckDefaults(const pb::Message& documented, const pb::Message* live,
                   const std::string& prefix, std::vector<std::string>* failures) {
  const pb::Descriptor* d = documented.GetDescriptor();
  const pb::Reflection* r = documented.GetReflection();
  for (int i = 0; i < d->field_count(); ++i) {
    const pb::FieldDescriptor* f = d->field(i);
    if (f->is_repeated() || !r->HasField(documented, f)) continue;
    const bool set_live = live != nullptr && live->GetReflection()->HasField(*live, f);
    if (f->cpp_type() == pb::FieldDescriptor::CPPTYPE_MESSAGE) {
      CheckDefaults(r->GetMessage(documented, f),
                    set_live ? &live->GetReflection()->GetMessage(*live, f) : nullptr,
                    Join(prefix, f->name()), failures);
      continue;
    }
    if (set_live) continue;
    const std::string value = ValueText(documented, f);
    const std::string want = DefaultText(documented, f);
    if (value != want) {
      failures->push_back(Join(prefix, f->name()) + " (" + f->full_name() + "): the file says " +
                          value + ", the schema's default is " + want);
    }
  }
}

// Every singular field of the schema (recursively) must be present in `m`.
void CheckListed(const pb::Message& m, const std::string& prefix,
                 std::vector<std::string>* failures) {
  const pb::Descriptor* d = m.GetDescriptor();
  const pb::Reflection* r = m.GetReflection();
  for (int i = 0; i < d->field_count(); ++i) {
    const pb::FieldDescriptor* f = d->field(i);
    if (f->is_repeated()) continue;
    if (!r->HasField(m, f)) {
      failures->push_back(Join(prefix, f->name()) + " (" + f->full_name() +
                          ") is not listed in the file");
    }
    if (f->cpp_type() == pb::FieldDescriptor::CPPTYPE_MESSAGE)
      CheckListed(r->GetMessage(m, f), Join(prefix, f->name()), failures);
  }
}

std::string Report(const std::vector<std::string>& failures) {
  std::string out;
  for (const std::string& f : failures) out += "\n  " + f;
  return out;
}

TEST(ShippedConfigTest, ClassifiesOptionsSectionsAndProse) {
  EXPECT_EQ(Uncomment("# walls {\n"
                      "#   # Sampling density, points per square metre. Default 50.0.\n"
                      "#   density_per_m2: 50.0\n"
                      "# }\n"
                      "# comments: an option left commented out takes its default.\n"
                      "dds {\n"
                      "  # cyclonedds_uri: \"\"\n"
                      "  domain_id: 0\n"
                      "}\n"),
            "walls {\n"
            "\n"
            "  density_per_m2: 50.0\n"
            "}\n"
            "\n"
            "dds {\n"
            "  cyclonedds_uri: \"\"\n"
            "  domain_id: 0\n"
            "}\n");
}

TEST(ShippedConfigTest, LoadsAsShipped) {
  v1::FloorposedConfig c;
  std::string error;
  ASSERT_TRUE(LoadConfig(kShippedConfig, &c, &error)) << error;
  EXPECT_THAT(ValidateConfig(c), IsEmpty());
}

TEST(ShippedConfigTest, CommentedOutOptionsParse) {
  v1::FloorposedConfig c;
  std::string error;
  EXPECT_TRUE(ParseConfig(Uncomment(ReadShippedConfig()), &c, &error))
      << kShippedConfig << " with its options enabled: " << error;
}

TEST(ShippedConfigTest, ListedValuesAreTheDefaults) {
  v1::FloorposedConfig documented, live;
  std::string error;
  ASSERT_TRUE(ParseConfig(Uncomment(ReadShippedConfig()), &documented, &error)) << error;
  ASSERT_TRUE(LoadConfig(kShippedConfig, &live, &error)) << error;
  std::vector<std::string> failures;
  CheckDefaults(documented, &live, "", &failures);
  EXPECT_THAT(failures, IsEmpty()) << kShippedConfig << ":" << Report(failures);
}

TEST(ShippedConfigTest, ListsEveryOption) {
  v1::FloorposedConfig documented;
  std::string error;
  ASSERT_TRUE(ParseConfig(Uncomment(ReadShippedConfig()), &documented, &error)) << error;
  std::vector<std::string> failures;
  CheckListed(documented, "", &failures);
  EXPECT_THAT(failures, IsEmpty()) << kShippedConfig << ":" << Report(failures);
}

// The note right above each option, live or commented out, ends in "Default X." with X
// the schema's default (a live option's value may differ from it: plan_path).
TEST(ShippedConfigTest, DefaultNotesAreTheDefaults) {
  static const std::regex default_note(R"(Default (.+)\.\s*$)");
  const std::vector<std::string> lines = Lines(ReadShippedConfig());
  std::vector<std::string> sections;  // the enclosing sections' names
  std::vector<std::string> failures;
  int options = 0;
  for (size_t i = 0; i < lines.size(); ++i) {
    const Line line = Classify(lines[i]);
    const std::string where = "line " + std::to_string(i + 1) + ": ";
    if (line.kind == Line::kOpen) sections.push_back(line.name);
    if (line.kind == Line::kClose && !sections.empty()) sections.pop_back();
    if (line.kind != Line::kOption) continue;
    ++options;
    // The message holding the option, reached through its sections.
    v1::FloorposedConfig scratch;
    pb::Message* m = &scratch;
    std::string path;
    for (const std::string& s : sections) {
      const pb::FieldDescriptor* f = m->GetDescriptor()->FindFieldByName(s);
      if (f == nullptr || f->cpp_type() != pb::FieldDescriptor::CPPTYPE_MESSAGE) {
        m = nullptr;
        break;
      }
      m = m->GetReflection()->MutableMessage(m, f);
      path = Join(path, s);
    }
    const pb::FieldDescriptor* f =
        m != nullptr ? m->GetDescriptor()->FindFieldByName(line.name) : nullptr;
    path = Join(path, line.name);
    if (f == nullptr) {
      failures.push_back(where + path + " is not an option of the schema");
      continue;
    }
    std::smatch note;
    if (i == 0 || Classify(lines[i - 1]).kind != Line::kProse ||
        !std::regex_search(lines[i - 1], note, default_note)) {
      failures.push_back(where + path + ": the line above does not end in \"Default X.\"");
      continue;
    }
    if (!pb::TextFormat::ParseFieldValueFromString(note[1], f, m)) {
      failures.push_back(where + path + ": \"Default " + note[1].str() + ".\" is not a value of " +
                         f->full_name());
      continue;
    }
    const std::string value = ValueText(*m, f);
    const std::string want = DefaultText(*m, f);
    if (value != want) {
      failures.push_back(where + path + " (" + f->full_name() + "): the note says Default " +
                         note[1].str() + ", the schema's default is " + want);
    }
  }
  EXPECT_GT(options, 30);
  EXPECT_THAT(failures, IsEmpty()) << kShippedConfig << ":" << Report(failures);
}

}  // namespace
}  // namespace floorpose::platform
