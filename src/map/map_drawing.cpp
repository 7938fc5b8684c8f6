// Text formatting and wrapping, the prior colour scale and the confuser and UAV glyphs.
#include "map_internal.h"

namespace hameritt::map::map_internal {

// Yellow-green-blue ramp for prior probabilities (u in [0, 1]).
cv::Scalar heatColor(double u) {
  static const double stops[][3] = {
      {255, 255, 217}, {199, 233, 180}, {65, 182, 196}, {34, 94, 168}, {8, 29, 88}};
  u = std::clamp(u, 0.0, 1.0) * 4.0;
  const int i = std::min(3, static_cast<int>(u));
  const double f = u - i;
  double c[3];
  for (int k = 0; k < 3; ++k) c[k] = stops[i][k] + f * (stops[i + 1][k] - stops[i][k]);
  return rgb(static_cast<int>(std::lround(c[0])), static_cast<int>(std::lround(c[1])),
             static_cast<int>(std::lround(c[2])));
}

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

// Shortest of "%.0f" / "%.1f" that keeps a tenth.
std::string compact(double v) {
  return std::abs(v - std::round(v)) < 0.05 ? fixed(v, 0) : fixed(v, 1);
}

std::string windowText(const Window& w) {
  if (w.net && w.nlt) return "[t " + fixed(*w.net, 1) + "-" + fixed(*w.nlt, 1) + " s]";
  if (w.net) return "[t >= " + fixed(*w.net, 1) + " s]";
  if (w.nlt) return "[t <= " + fixed(*w.nlt, 1) + " s]";
  return "";
}

std::string altitudeText(const KozData& k) {
  if (k.alt_min && k.alt_max) {
    return "alt " + compact(*k.alt_min) + "-" + compact(*k.alt_max) + " m";
  }
  if (k.alt_min) return "alt >= " + compact(*k.alt_min) + " m";
  if (k.alt_max) return "alt <= " + compact(*k.alt_max) + " m";
  return "";
}

// Hershey fonts are ASCII only.
std::string ascii(const std::string& s) {
  std::string out;
  for (unsigned char c : s) out += (c >= 32 && c < 127) ? static_cast<char>(c) : '?';
  return out;
}

std::vector<std::string> wrapText(const std::string& text, int font, double scale, int thickness,
                                  int max_width) {
  std::vector<std::string> lines;
  std::string line;
  auto width = [&](const std::string& s) {
    int base = 0;
    return cv::getTextSize(s, font, scale, thickness, &base).width;
  };
  std::size_t pos = 0;
  const std::string t = ascii(text);
  while (pos < t.size()) {
    std::size_t end = t.find(' ', pos);
    if (end == std::string::npos) end = t.size();
    std::string word = t.substr(pos, end - pos);
    pos = end + 1;
    const std::string candidate = line.empty() ? word : line + " " + word;
    if (width(candidate) <= max_width) {
      line = candidate;
      continue;
    }
    if (!line.empty()) lines.push_back(line);
    line.clear();
    // A word wider than a line is broken where it no longer fits.
    while (width(word) > max_width && word.size() > 1) {
      std::size_t n = word.size() - 1;
      while (n > 1 && width(word.substr(0, n)) > max_width) --n;
      lines.push_back(word.substr(0, n));
      word = word.substr(n);
    }
    line = word;
  }
  if (!line.empty() || lines.empty()) lines.push_back(line);
  return lines;
}

bool isTarget(const MoverData& m, const MapData& d) {
  if (m.role == "target") return true;
  return std::any_of(d.targets.begin(), d.targets.end(),
                     [&](const TargetData& t) { return t.id == m.id; });
}

double maxProbability(const MapData& d) {
  double p = 0.0;
  for (const auto& pr : d.priors) {
    for (const auto& c : pr.cells) p = std::max(p, c.probability);
  }
  return p;
}

// Largest round length (metres) whose bar fits in max_px.
double scaleBarLength(double px_per_m, int max_px) {
  static const double lengths[] = {1000, 500, 200, 100, 50, 20, 10, 5, 2, 1};
  for (double l : lengths) {
    if (l * px_per_m <= max_px) return l;
  }
  return 1.0;
}

void confuserGlyph(cv::Mat& img, cv::Point c, int r) {
  std::vector<cv::Point> pts = {
      {c.x, c.y - r - 1}, {c.x + r + 1, c.y}, {c.x, c.y + r + 1}, {c.x - r - 1, c.y}};
  cv::fillConvexPoly(img, pts, kBlack, cv::LINE_AA);
  pts = {{c.x, c.y - r}, {c.x + r, c.y}, {c.x, c.y + r}, {c.x - r, c.y}};
  cv::fillConvexPoly(img, pts, kConfuserColor, cv::LINE_AA);
}

// Triangle pointing along the ENU yaw (image y points south).
void uavGlyph(cv::Mat& img, cv::Point2d c, double yaw, double r) {
  const cv::Point2d f(std::cos(yaw), -std::sin(yaw));
  const cv::Point2d s(-f.y, f.x);
  std::vector<cv::Point> pts;
  for (const cv::Point2d& p :
       {c + f * r, c - f * (0.6 * r) + s * (0.7 * r), c - f * (0.6 * r) - s * (0.7 * r)}) {
    pts.emplace_back(static_cast<int>(std::lround(p.x * kOne)),
                     static_cast<int>(std::lround(p.y * kOne)));
  }
  cv::fillConvexPoly(img, pts, kUav, cv::LINE_AA, kShift);
  cv::polylines(img, pts, true, kWhite, 1, cv::LINE_AA, kShift);
}

}  // namespace hameritt::map::map_internal
