// Cursor-on-Target events as written (tools/lib/cot.h): well-formed whatever a name holds,
// and the circular error from the probability of being within 1 m.
#include <gtest/gtest.h>

#include <cmath>

#include "tools/lib/cot.h"

namespace floorpose::tools {
namespace {

TEST(CotXmlTest, NamesThatAreNotXmlAreEscaped) {
  CotEvent e;
  e.uid = "floorpose-hl\"07";
  e.type = "a-f-G-U-C";
  e.callsign = "A<l>i&ce\x01";
  e.remarks = "it's <b>";
  e.lat = 49.41, e.lon = 8.67, e.hae = 3.5, e.ce_m = 0.47;
  e.course_deg = 12.5;
  e.time_unix_ns = 1'795'000'000'123'000'000;
  e.stale_s = 30;
  const std::string xml = ToCotXml(e);
  EXPECT_NE(xml.find(R"(uid="floorpose-hl&quot;07")"), std::string::npos) << xml;
  EXPECT_NE(xml.find(R"(callsign="A&lt;l&gt;i&amp;ce")"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<remarks>it&apos;s &lt;b&gt;</remarks>"), std::string::npos) << xml;
  EXPECT_NE(xml.find(R"(time="2026-11-18T11:06:40.123Z")"), std::string::npos) << xml;
  EXPECT_NE(xml.find(R"(stale="2026-11-18T11:07:10.123Z")"), std::string::npos) << xml;
  EXPECT_NE(xml.find(R"(lat="49.41000000" lon="8.67000000" hae="3.50" ce="0.47")"),
            std::string::npos)
      << xml;
  EXPECT_NE(xml.find(R"(<track course="12.5")"), std::string::npos) << xml;
}

TEST(CotXmlTest, CircularErrorFollowsTheProbabilityWithinAMetre) {
  // Rayleigh: P(r <= 1) = 1 - exp(-1 / (2 sigma^2)).
  for (double p : {0.1, 0.5, 0.9, 0.99}) {
    const double sigma = CircularErrorM(p);
    EXPECT_NEAR(1 - std::exp(-1 / (2 * sigma * sigma)), p, 1e-9) << p;
  }
  EXPECT_LT(CircularErrorM(0.9), 0.5);
  EXPECT_EQ(CircularErrorM(0.0), 9999999);
  EXPECT_EQ(CircularErrorM(std::nan("")), 9999999);
  EXPECT_GT(CircularErrorM(1.0), 0.0);
}

TEST(CotXmlTest, ADestinationThatIsNotOneIsRefused) {
  std::string error;
  EXPECT_EQ(CotSink::Open("239.2.3.1:6969", "", &error), nullptr);
  EXPECT_NE(error.find("udp://HOST:PORT"), std::string::npos) << error;
  EXPECT_EQ(CotSink::Open("udp://239.2.3.1:0", "", &error), nullptr);
  EXPECT_EQ(CotSink::Open("udp://tak.example:6969", "", &error), nullptr) << "IPv4 for UDP";
  EXPECT_EQ(CotSink::Open("udp://239.2.3.1:6969", "not-an-address", &error), nullptr);
  EXPECT_NE(CotSink::Open("udp://239.2.3.1:6969", "127.0.0.1", &error), nullptr) << error;
}

}  // namespace
}  // namespace floorpose::tools
