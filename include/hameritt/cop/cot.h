#pragma once
// Cursor-on-Target 2.0 events (MITRE MTR 02W0000037, "Cursor on Target Message Router User's
// Guide"; the event schema CoT_Event.xsd): one <event> with uid, type, how, time/start/stale,
// a <point> and a <detail> that TAK clients (ATAK, WinTAK, iTAK) read: contact, track,
// remarks, and freeform shapes (type u-d-f, one <link point="lat,lon"/> per vertex).

#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hameritt::cop {

// CoT's value for an unknown circular / linear error (metres).
inline constexpr double kCotUnknownError = 9999999.0;

// A CoT <point>: WGS84 degrees, height above the ellipsoid (m), 1-sigma errors (m).
struct CotPoint {
  double lat = 0.0;
  double lon = 0.0;
  double hae = 0.0;
  double ce = kCotUnknownError;
  double le = kCotUnknownError;
};

// A freeform shape (u-d-f) drawn from its vertices; closed repeats the first vertex at the end.
struct CotShape {
  std::vector<std::pair<double, double>> vertices;  // (lat, lon) degrees
  bool closed = true;
  int stroke_argb = -16776961;  // opaque blue, as a signed 32-bit ARGB integer (TAK's encoding)
  int fill_argb = 0;            // transparent
  double stroke_weight = 3.0;
};

// One CoT event. Times are seconds since the Unix epoch (UTC).
struct CotEvent {
  std::string uid;
  std::string type;  // e.g. a-f-A-M-F-Q (friendly air rotary UAV), a-u-G (unknown ground)
  std::string how = "m-g";
  double time = 0.0;
  double start = 0.0;
  double stale = 0.0;
  CotPoint point;
  std::string callsign;  // <contact callsign=...>, empty: no contact element
  std::optional<std::pair<double, double>> track;  // (course deg from true north, speed m/s)
  std::string remarks;
  std::optional<CotShape> shape;
  // Extra attributes of a <hameritt .../> detail element (TAK ignores elements it does not
  // know and passes them on): track id, entity id, target belief, ...
  std::vector<std::pair<std::string, std::string>> extra;
};

// Escapes &, <, >, " and ' for XML text and attribute values; drops control characters XML 1.0
// cannot carry (all below 0x20 but tab, newline and carriage return).
std::string xmlEscape(std::string_view s);

// ISO-8601 UTC with milliseconds: 2026-11-24T21:42:09.123Z.
std::string isoTime(double unix_seconds);

// The event as one XML document (no XML declaration: TAK streams events back to back).
std::string toXml(const CotEvent& e);

// The children of the event's <detail> element; without <contact> and <track> when
// contact_and_track is false (TAK Protocol Version 1 carries those two as protobuf fields).
std::string detailXml(const CotEvent& e, bool contact_and_track);

}  // namespace hameritt::cop
