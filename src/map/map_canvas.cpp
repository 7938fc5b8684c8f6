// MapPainter's drawing primitives: projection, fills, outlines, dashes, hatching, labels.
#include "map_internal.h"

namespace hameritt::map::map_internal {

MapPainter::MapPainter(const MapFrame& frame, const MapStyle& style)
    : frame_(frame),
      style_(style),
      img_(frame.map_rect.height, frame.map_rect.width, CV_8UC3, kGround) {}

cv::Point2d MapPainter::px(const Vec2& p) const {
  return {(p.x() - frame_.region.min.x()) * frame_.px_per_m,
          (frame_.region.max.y() - p.y()) * frame_.px_per_m};
}

cv::Point MapPainter::fx(const cv::Point2d& p) const {
  return {static_cast<int>(std::lround(p.x * kOne)), static_cast<int>(std::lround(p.y * kOne))};
}

std::vector<cv::Point> MapPainter::fx(const std::vector<Vec2>& pts) const {
  std::vector<cv::Point> out;
  out.reserve(pts.size());
  for (const auto& p : pts) out.push_back(fx(p));
  return out;
}

bool MapPainter::visible(const Aabb2& b) const {
  Aabb2 r = frame_.region;
  return r.overlaps(b);
}

void MapPainter::fill(const std::vector<Vec2>& poly, const cv::Scalar& c, cv::Mat* target,
                      int line_type) {
  const std::vector<std::vector<cv::Point>> pts = {fx(poly)};
  cv::fillPoly(target ? *target : img_, pts, c, line_type, kShift);
}

void MapPainter::outline(const std::vector<Vec2>& pts, bool closed, const cv::Scalar& c,
                         int thickness, int line_type) {
  cv::polylines(img_, fx(pts), closed, c, thickness, line_type, kShift);
}

void MapPainter::dashed(std::vector<Vec2> pts, bool closed, const cv::Scalar& c, int thickness,
                        double dash_px, double gap_px) {
  if (closed && !pts.empty()) pts.push_back(pts.front());
  double phase = 0.0;  // distance into the current dash+gap period
  const double period = dash_px + gap_px;
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
    const cv::Point2d a = px(pts[i]), b = px(pts[i + 1]);
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    if (len <= 0.0) continue;
    const cv::Point2d u = (b - a) * (1.0 / len);
    double s = 0.0;
    while (s < len) {
      const double in_period = std::fmod(phase + s, period);
      if (in_period < dash_px) {
        const double e = std::min(len, s + dash_px - in_period);
        cv::line(img_, fx(a + u * s), fx(a + u * e), c, thickness, cv::LINE_AA, kShift);
        s = e;
      } else {
        s += period - in_period;
      }
    }
    phase = std::fmod(phase + len, period);
  }
}

void MapPainter::translucent(
    const std::vector<std::pair<const std::vector<Vec2>*, cv::Scalar>>& shapes, double alpha) {
  cv::Mat layer = img_.clone();
  cv::Mat mask = cv::Mat::zeros(img_.size(), CV_8UC1);
  for (const auto& [poly, color] : shapes) {
    fill(*poly, color, &layer, cv::LINE_8);
    fill(*poly, cv::Scalar(255), &mask, cv::LINE_8);
  }
  blend(layer, mask, alpha);
}

void MapPainter::blend(const cv::Mat& layer, const cv::Mat& mask, double alpha) {
  cv::Mat mixed;
  cv::addWeighted(img_, 1.0 - alpha, layer, alpha, 0.0, mixed);
  mixed.copyTo(img_, mask);
}

void MapPainter::hatch(const std::vector<Vec2>& poly, const cv::Scalar& c, int spacing) {
  cv::Rect box = cv::boundingRect(fx(poly));
  box = cv::Rect(box.x >> kShift, box.y >> kShift, (box.width >> kShift) + 2,
                 (box.height >> kShift) + 2) &
        cv::Rect(0, 0, img_.cols, img_.rows);
  if (box.area() <= 0) return;
  cv::Mat roi = img_(box);
  cv::Mat mask = cv::Mat::zeros(box.size(), CV_8UC1);
  std::vector<cv::Point> local;
  for (const auto& p : poly) {
    const cv::Point2d q = px(p) - cv::Point2d(box.x, box.y);
    local.push_back(fx(q));
  }
  cv::fillPoly(mask, std::vector<std::vector<cv::Point>>{local}, 255, cv::LINE_8, kShift);
  cv::Mat lines = roi.clone();
  // Phase the lines on absolute pixel coordinates so that neighbouring zones line up.
  const int start = -((box.x + box.y) % spacing) - box.height;
  for (int k = start; k < box.width; k += spacing) {
    cv::line(lines, cv::Point(k, box.height), cv::Point(k + box.height, 0), c, 1, cv::LINE_AA);
  }
  lines.copyTo(roi, mask);
}

void MapPainter::placeLabel(const std::vector<std::string>& lines, cv::Point2d anchor, double gap,
                            double scale, int thickness, const cv::Scalar& color) {
  // Nothing to label when the feature itself lies outside the map.
  if (anchor.x < 0 || anchor.y < 0 || anchor.x >= img_.cols || anchor.y >= img_.rows) return;
  int w = 0, line_h = 0;
  for (const auto& s : lines) {
    int base = 0;
    const cv::Size ts = cv::getTextSize(s, kFont, scale, thickness, &base);
    w = std::max(w, ts.width);
    line_h = std::max(line_h, ts.height + base);
  }
  line_h += 2;
  const int h = line_h * static_cast<int>(lines.size());
  // Candidate offsets of the label's top-left corner: the four diagonal corners, above,
  // below and beside the anchor, first close, then further out.
  std::vector<cv::Point2d> offsets;
  for (double g : {gap, 2.5 * gap + 6.0, 4.0 * gap + 14.0}) {
    const cv::Point2d ring[] = {
        {g, -g - h},        {g, g},        {-g - w, -g - h}, {-g - w, g},
        {-0.5 * w, -g - h}, {-0.5 * w, g}, {g, -0.5 * h},    {-g - w, -0.5 * h}};
    offsets.insert(offsets.end(), std::begin(ring), std::end(ring));
  }
  const cv::Rect bounds(0, 0, img_.cols, img_.rows);
  // The first candidate that overlaps nothing, else the one that overlaps least.
  std::optional<cv::Rect> chosen;
  int least = 0;
  for (const auto& o : offsets) {
    const cv::Rect r(static_cast<int>(std::lround(anchor.x + o.x)) - 2,
                     static_cast<int>(std::lround(anchor.y + o.y)) - 2, w + 4, h + 4);
    if ((r & bounds) != r) continue;
    int overlap = 0;
    for (const auto& q : occupied_) overlap += (q & r).area();
    if (!chosen || overlap < least) {
      chosen = r;
      least = overlap;
    }
    if (overlap == 0) break;
  }
  if (!chosen) return;  // the anchor is too close to the map edge for any placement
  occupied_.push_back(*chosen);
  // A pale box under the text keeps it readable over streets, hatching and prior numbers.
  cv::Mat box = img_(*chosen);
  cv::addWeighted(box, 1.0 - kLabelBoxAlpha, cv::Mat(box.size(), box.type(), kWhite),
                  kLabelBoxAlpha, 0.0, box);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const int base_y = chosen->y + 2 + line_h * static_cast<int>(i + 1) - 4;
    cv::putText(img_, lines[i], cv::Point(chosen->x + 2, base_y), kFont, scale, color, thickness,
                cv::LINE_AA);
  }
}

void MapPainter::reserve(const cv::Point2d& c, int half) {
  occupied_.emplace_back(static_cast<int>(std::lround(c.x)) - half,
                         static_cast<int>(std::lround(c.y)) - half, 2 * half + 1, 2 * half + 1);
}

cv::Point2d MapPainter::topCorner(const std::vector<Vec2>& poly) const {
  cv::Point2d best = px(poly.front());
  for (const auto& p : poly) {
    const cv::Point2d q = px(p);
    if (q.y + q.x < best.y + best.x) best = q;
  }
  return best;
}

}  // namespace hameritt::map::map_internal
