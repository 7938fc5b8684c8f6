#include "hameritt/cop/cot.h"

#include <cmath>
#include <cstdio>
#include <ctime>

namespace hameritt::cop {
namespace {

// Shortest text that reads back to the same double (enough for 0.1 mm in degrees).
std::string num(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

void attr(std::string& out, const char* name, const std::string& value) {
  out += ' ';
  out += name;
  out += "=\"";
  out += xmlEscape(value);
  out += '"';
}

}  // namespace

std::string xmlEscape(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (const char ch : s) {
    switch (ch) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      case '\t':
        out += "&#9;";
        break;
      case '\n':
        out += "&#10;";
        break;
      case '\r':
        out += "&#13;";
        break;
      default:
        if (static_cast<unsigned char>(ch) >= 0x20) out += ch;
    }
  }
  return out;
}

std::string isoTime(double unix_seconds) {
  double whole = std::floor(unix_seconds);
  int millis = static_cast<int>(std::lround((unix_seconds - whole) * 1000.0));
  if (millis >= 1000) {
    whole += 1.0;
    millis -= 1000;
  }
  const std::time_t t = static_cast<std::time_t>(whole);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, millis);
  return buf;
}

std::string detailXml(const CotEvent& e, bool contact_and_track) {
  std::string out;
  if (contact_and_track && !e.callsign.empty()) {
    out += "<contact";
    attr(out, "callsign", e.callsign);
    out += "/>";
  }
  if (contact_and_track && e.track) {
    out += "<track";
    attr(out, "course", num(e.track->first, 2));
    attr(out, "speed", num(e.track->second, 2));
    out += "/>";
  }
  if (e.shape) {
    const CotShape& s = *e.shape;
    const size_t n = s.vertices.size() + (s.closed && !s.vertices.empty() ? 1 : 0);
    for (size_t i = 0; i < n; ++i) {
      const auto& [lat, lon] = s.vertices[i % s.vertices.size()];
      out += "<link";
      attr(out, "point", num(lat, 8) + "," + num(lon, 8));
      out += "/>";
    }
    out += "<strokeColor";
    attr(out, "value", std::to_string(s.stroke_argb));
    out += "/><strokeWeight";
    attr(out, "value", num(s.stroke_weight, 1));
    out += "/><fillColor";
    attr(out, "value", std::to_string(s.fill_argb));
    out += "/><labels_on value=\"true\"/>";
  }
  if (!e.remarks.empty()) {
    out += "<remarks>";
    out += xmlEscape(e.remarks);
    out += "</remarks>";
  }
  if (!e.extra.empty()) {
    out += "<hameritt";
    for (const auto& [k, v] : e.extra) attr(out, k.c_str(), v);
    out += "/>";
  }
  return out;
}

std::string toXml(const CotEvent& e) {
  std::string out = "<event version=\"2.0\"";
  attr(out, "uid", e.uid);
  attr(out, "type", e.type);
  attr(out, "how", e.how);
  attr(out, "time", isoTime(e.time));
  attr(out, "start", isoTime(e.start));
  attr(out, "stale", isoTime(e.stale));
  out += "><point";
  attr(out, "lat", num(e.point.lat, 8));
  attr(out, "lon", num(e.point.lon, 8));
  attr(out, "hae", num(e.point.hae, 3));
  attr(out, "ce", num(e.point.ce, 1));
  attr(out, "le", num(e.point.le, 1));
  out += "/><detail>";
  out += detailXml(e, true);
  out += "</detail></event>";
  return out;
}

}  // namespace hameritt::cop
