#include "hameritt/cop/tak_proto.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

namespace hameritt::cop {
namespace {

constexpr unsigned char kMagic = 0xbf;

enum WireType : unsigned { kVarint = 0, kFixed64 = 1, kLengthDelimited = 2 };

void tag(std::string& out, unsigned field, WireType type) {
  appendVarint(out, (static_cast<std::uint64_t>(field) << 3) | type);
}

// proto3: a field at its default value (empty, zero) is not written.
void putString(std::string& out, unsigned field, std::string_view s) {
  if (s.empty()) return;
  tag(out, field, kLengthDelimited);
  appendVarint(out, s.size());
  out.append(s.data(), s.size());
}

void putUint(std::string& out, unsigned field, std::uint64_t v) {
  if (v == 0) return;
  tag(out, field, kVarint);
  appendVarint(out, v);
}

void putDouble(std::string& out, unsigned field, double v) {
  if (v == 0.0 && !std::signbit(v)) return;
  tag(out, field, kFixed64);
  std::uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  for (int i = 0; i < 8; ++i) out += static_cast<char>((bits >> (8 * i)) & 0xff);  // little-endian
}

void putMessage(std::string& out, unsigned field, const std::string& body, bool always) {
  if (body.empty() && !always) return;
  tag(out, field, kLengthDelimited);
  appendVarint(out, body.size());
  out += body;
}

std::uint64_t millis(double unix_seconds) {
  return unix_seconds <= 0 ? 0 : static_cast<std::uint64_t>(std::llround(unix_seconds * 1000.0));
}

}  // namespace

TakEncoding parseTakEncoding(const std::string& value, const std::string& what) {
  if (value == "xml") return TakEncoding::kXml;
  if (value == "protobuf") return TakEncoding::kProtobuf;
  throw std::invalid_argument(what + " = '" + value +
                              "' (expected xml or protobuf, TAK Protocol Version 1)");
}

const char* toString(TakEncoding encoding) {
  return encoding == TakEncoding::kXml ? "xml" : "protobuf";
}

void appendVarint(std::string& out, std::uint64_t value) {
  while (value >= 0x80) {
    out += static_cast<char>((value & 0x7f) | 0x80);
    value >>= 7;
  }
  out += static_cast<char>(value);
}

bool readVarint(std::string_view in, std::size_t& pos, std::uint64_t& value) {
  value = 0;
  for (int i = 0; i < 10; ++i) {
    if (pos >= in.size()) return false;
    const auto byte = static_cast<unsigned char>(in[pos++]);
    value |= static_cast<std::uint64_t>(byte & 0x7f) << (7 * i);
    if (!(byte & 0x80)) return true;
  }
  return false;
}

std::string toTakProto(const CotEvent& e) {
  std::string detail;
  putString(detail, 1, detailXml(e, false));
  if (!e.callsign.empty()) {
    std::string contact;
    putString(contact, 2, e.callsign);
    putMessage(detail, 2, contact, true);
  }
  if (e.track) {
    std::string track;
    putDouble(track, 1, e.track->second);  // speed m/s
    putDouble(track, 2, e.track->first);   // course degrees
    putMessage(detail, 7, track, true);
  }
  std::string event;
  putString(event, 1, e.type);
  putString(event, 5, e.uid);
  putUint(event, 6, millis(e.time));
  putUint(event, 7, millis(e.start));
  putUint(event, 8, millis(e.stale));
  putString(event, 9, e.how);
  putDouble(event, 10, e.point.lat);
  putDouble(event, 11, e.point.lon);
  putDouble(event, 12, e.point.hae);
  putDouble(event, 13, e.point.ce);
  putDouble(event, 14, e.point.le);
  putMessage(event, 15, detail, true);
  std::string message;
  putMessage(message, 2, event, true);
  return message;
}

std::string frameMesh(std::string_view payload) {
  std::string out;
  out.reserve(payload.size() + 3);
  out += static_cast<char>(kMagic);
  appendVarint(out, 1);  // TAK Protocol Version 1
  out += static_cast<char>(kMagic);
  out.append(payload.data(), payload.size());
  return out;
}

std::string frameStream(std::string_view payload) {
  std::string out;
  out.reserve(payload.size() + 6);
  out += static_cast<char>(kMagic);
  appendVarint(out, payload.size());
  out.append(payload.data(), payload.size());
  return out;
}

bool takeStreamFrame(std::string& buffer, std::string& payload) {
  if (buffer.empty()) return false;
  if (static_cast<unsigned char>(buffer[0]) != kMagic) {
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%02x", static_cast<unsigned char>(buffer[0]));
    throw TakFrameError(std::string("TAK Protocol stream: byte ") + hex +
                        " where the magic byte 0xbf was expected");
  }
  std::size_t pos = 1;
  std::uint64_t length = 0;
  if (!readVarint(buffer, pos, length)) {
    if (buffer.size() >= 11)
      throw TakFrameError("TAK Protocol stream: length varint longer than 10 bytes");
    return false;
  }
  if (buffer.size() - pos < length) return false;
  payload.assign(buffer, pos, length);
  buffer.erase(0, pos + length);
  return true;
}

namespace {

// The value of attribute `name` in `element` (either quote), or "".
std::string attribute(std::string_view element, std::string_view name) {
  for (std::size_t at = element.find(name); at != std::string_view::npos;
       at = element.find(name, at + 1)) {
    std::size_t i = at + name.size();
    const bool starts = at > 0 && (element[at - 1] == ' ' || element[at - 1] == '\t' ||
                                   element[at - 1] == '\n' || element[at - 1] == '\r');
    while (i < element.size() && element[i] == ' ') ++i;
    if (!starts || i >= element.size() || element[i] != '=') continue;
    ++i;
    while (i < element.size() && element[i] == ' ') ++i;
    if (i >= element.size() || (element[i] != '"' && element[i] != '\'')) continue;
    const std::size_t end = element.find(element[i], i + 1);
    if (end == std::string_view::npos) return "";
    return std::string(element.substr(i + 1, end - i - 1));
  }
  return "";
}

// Each <tag .../> element's text in `event`.
std::vector<std::string_view> elements(std::string_view event, std::string_view tag) {
  std::vector<std::string_view> out;
  const std::string open = "<" + std::string(tag);
  for (std::size_t at = event.find(open); at != std::string_view::npos;
       at = event.find(open, at + 1)) {
    const std::size_t end = event.find('>', at);
    if (end == std::string_view::npos) break;
    out.push_back(event.substr(at, end - at + 1));
  }
  return out;
}

}  // namespace

std::string takProtocolRequest(double now) {
  CotEvent e;
  e.uid = "protouid";
  e.type = "t-x-takp-q";
  e.time = e.start = now;
  e.stale = now + 60.0;
  e.point.ce = e.point.le = 999999.0;
  std::string xml = toXml(e);
  const std::string detail = "<detail></detail>";
  xml.replace(xml.find(detail), detail.size(),
              "<detail><TakControl><TakRequest version=\"1\"/></TakControl></detail>");
  return xml;
}

TakNegotiation scanNegotiation(std::string& buffer) {
  TakNegotiation result = TakNegotiation::kNothing;
  static const std::string kEnd = "</event>";
  for (std::size_t end = buffer.find(kEnd); end != std::string::npos; end = buffer.find(kEnd)) {
    const std::string event = buffer.substr(0, end + kEnd.size());
    buffer.erase(0, end + kEnd.size());
    const auto heads = elements(event, "event");
    if (heads.empty()) continue;
    const std::string type = attribute(heads.front(), "type");
    if (type == "t-x-takp-r") {
      for (const auto& r : elements(event, "TakResponse"))
        result =
            attribute(r, "status") == "true" ? TakNegotiation::kAccepted : TakNegotiation::kDenied;
    } else if (type == "t-x-takp-v" && result == TakNegotiation::kNothing) {
      for (const auto& v : elements(event, "TakProtocolSupport"))
        if (attribute(v, "version") == "1") result = TakNegotiation::kOffered;
    }
  }
  return result;
}

}  // namespace hameritt::cop
