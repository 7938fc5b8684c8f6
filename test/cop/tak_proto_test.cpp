// TAK Protocol Version 1 framing and negotiation: varints at their byte boundaries (the bytes
// from the protobuf encoding guide), the mesh header 0xbf 0x01 0xbf, stream frames taken off a
// buffer that holds part of one, several, or a bad magic byte, and the server's negotiation
// events. The TakMessage encoding itself is judged by node-cot in test/scripts/test_tak_tls.py.
#include "hameritt/cop/tak_proto.h"

#include <gtest/gtest.h>

namespace hameritt::cop {
namespace {

std::string bytes(std::initializer_list<unsigned> b) {
  std::string s;
  for (const unsigned v : b) s += static_cast<char>(v);
  return s;
}

std::string varint(std::uint64_t v) {
  std::string s;
  appendVarint(s, v);
  return s;
}

TEST(TakProto, VarintsAtTheirByteBoundaries) {
  EXPECT_EQ(varint(0), bytes({0x00}));
  EXPECT_EQ(varint(1), bytes({0x01}));
  EXPECT_EQ(varint(127), bytes({0x7f}));
  EXPECT_EQ(varint(128), bytes({0x80, 0x01}));
  EXPECT_EQ(varint(300), bytes({0xac, 0x02}));  // the protobuf guide's example
  EXPECT_EQ(varint(16383), bytes({0xff, 0x7f}));
  EXPECT_EQ(varint(16384), bytes({0x80, 0x80, 0x01}));
  EXPECT_EQ(varint(UINT64_MAX).size(), 10u);
  for (const std::uint64_t v : {0ull, 127ull, 128ull, 16383ull, 16384ull, 2097151ull, 2097152ull,
                                static_cast<unsigned long long>(UINT64_MAX)}) {
    std::size_t pos = 0;
    std::uint64_t back = 0;
    const std::string s = varint(v);
    ASSERT_TRUE(readVarint(s, pos, back)) << v;
    EXPECT_EQ(back, v);
    EXPECT_EQ(pos, s.size());
    pos = 0;
    EXPECT_EQ(readVarint(s.substr(0, s.size() - 1), pos, back), false) << v;  // cut short
  }
}

TEST(TakProto, MeshHeaderIsMagicVersionMagic) {
  const std::string m = frameMesh("abc");
  EXPECT_EQ(m, bytes({0xbf, 0x01, 0xbf}) + "abc");
}

TEST(TakProto, StreamFramesCarryTheLengthAtEachBoundary) {
  for (const std::size_t n : {0u, 1u, 127u, 128u, 16383u, 16384u}) {
    const std::string payload(n, 'x');
    const std::string f = frameStream(payload);
    EXPECT_EQ(f.substr(0, 1), bytes({0xbf})) << n;
    EXPECT_EQ(f.substr(1, f.size() - 1 - n), varint(n)) << n;
    EXPECT_EQ(f.size(), 1 + varint(n).size() + n);
    // Every cut before the end is "not yet"; the whole frame comes back, nothing else taken.
    std::string out;
    for (const std::size_t cut : {std::size_t{1}, std::size_t{2}, f.size() - 1}) {
      if (cut >= f.size()) continue;
      std::string part = f.substr(0, cut);
      EXPECT_FALSE(takeStreamFrame(part, out)) << n << " cut at " << cut;
      EXPECT_EQ(part.size(), cut);
    }
    std::string buffer = f + frameStream("next");
    ASSERT_TRUE(takeStreamFrame(buffer, out));
    EXPECT_EQ(out, payload);
    ASSERT_TRUE(takeStreamFrame(buffer, out));
    EXPECT_EQ(out, "next");
    EXPECT_TRUE(buffer.empty());
  }
}

TEST(TakProto, StreamWithoutTheMagicByteIsAnError) {
  std::string xml = "<event/>";
  std::string out;
  try {
    takeStreamFrame(xml, out);
    FAIL() << "accepted XML as a frame";
  } catch (const TakFrameError& e) {
    EXPECT_NE(std::string(e.what()).find("0x3c where the magic byte 0xbf"), std::string::npos)
        << e.what();
  }
  std::string endless = bytes({0xbf}) + std::string(11, '\x80');
  EXPECT_THROW(takeStreamFrame(endless, out), TakFrameError);
}

TEST(TakProto, EventCarriesContactAndTrackAsFieldsTheRestAsXmlDetail) {
  CotEvent e;
  e.uid = "u";
  e.type = "a-f-G";
  e.callsign = "CS";
  e.track = std::make_pair(90.0, 1.5);
  e.remarks = "r & s";
  const std::string p = toTakProto(e);
  // TakMessage.cotEvent (field 2, length-delimited) first.
  EXPECT_EQ(p.substr(0, 1), bytes({0x12}));
  EXPECT_NE(p.find("<remarks>r &amp; s</remarks>"), std::string::npos);
  EXPECT_EQ(p.find("<contact"), std::string::npos);  // a field, not XML
  EXPECT_EQ(p.find("<track"), std::string::npos);
  EXPECT_NE(p.find(bytes({0x12, 0x02}) + "CS"), std::string::npos);  // Contact.callsign
}

TEST(TakProto, NegotiationSteps) {
  std::string in =
      "<?xml version='1.0'?>\n<event version='2.0' uid='protouid' type='t-x-takp-v'><detail>"
      "<TakControl><TakProtocolSupport version='1'/></TakControl></detail></event><event";
  EXPECT_EQ(scanNegotiation(in), TakNegotiation::kOffered);
  EXPECT_EQ(in, "<event");  // the partial event stays
  std::string v2 =
      "<event type=\"t-x-takp-v\"><TakControl><TakProtocolSupport version=\"2\"/></TakControl>"
      "</event>";
  EXPECT_EQ(scanNegotiation(v2), TakNegotiation::kNothing);
  std::string yes = "<event type=\"t-x-takp-r\"><TakResponse status=\"true\"/></event>";
  EXPECT_EQ(scanNegotiation(yes), TakNegotiation::kAccepted);
  std::string no = "<event type='t-x-takp-r'><TakResponse status='false'/></event>";
  EXPECT_EQ(scanNegotiation(no), TakNegotiation::kDenied);
  std::string other = "<event type='a-f-G' uid='t-x-takp-r'/></event>";
  EXPECT_EQ(scanNegotiation(other), TakNegotiation::kNothing);
  const std::string q = takProtocolRequest(1.8e9);
  EXPECT_NE(q.find("type=\"t-x-takp-q\""), std::string::npos);
  EXPECT_NE(q.find("<TakControl><TakRequest version=\"1\"/></TakControl>"), std::string::npos);
  EXPECT_EQ(parseTakEncoding("protobuf", "x"), TakEncoding::kProtobuf);
  EXPECT_THROW(parseTakEncoding("proto", "~tak_protocol"), std::invalid_argument);
}

}  // namespace
}  // namespace hameritt::cop
