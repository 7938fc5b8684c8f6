#include "hameritt/clients/color_detector.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "hameritt/geometry/oriented_box.h"
#include "hameritt/scenario/error.h"

namespace hameritt::clients {

using geometry::Vec2;
using geometry::Vec3;

namespace {

std::string fmt(double v) { return scenario::formatNumber(v); }

// Union-find over blob indices.
int root(std::vector<int>& parent, int i) {
  while (parent[static_cast<std::size_t>(i)] != i) {
    parent[static_cast<std::size_t>(i)] =
        parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    i = parent[static_cast<std::size_t>(i)];
  }
  return i;
}

struct Blob {
  std::vector<Vec3> points;
  std::vector<float> depths;
  int pixels = 0;
  cv::Rect box;
  bool border = false;
  geometry::OrientedBox footprint;
};

// Minimum-area rectangle of points in the plane: centre, long side, short side, long-axis yaw.
void fitRectangle(const std::vector<Vec3>& pts, Vec2* centre, double* length, double* width,
                  double* yaw) {
  const Vec2 origin = pts.front().head<2>();
  std::vector<cv::Point2f> p;
  p.reserve(pts.size());
  for (const auto& q : pts) {
    p.emplace_back(static_cast<float>(q.x() - origin.x()), static_cast<float>(q.y() - origin.y()));
  }
  const cv::RotatedRect r = cv::minAreaRect(p);
  cv::Point2f c[4];
  r.points(c);
  const Vec2 a(c[1].x - c[0].x, c[1].y - c[0].y), b(c[2].x - c[1].x, c[2].y - c[1].y);
  const Vec2 axis = a.norm() >= b.norm() ? a : b;
  *length = std::max(a.norm(), b.norm());
  *width = std::min(a.norm(), b.norm());
  *centre = origin + Vec2(r.center.x, r.center.y);
  double y = std::atan2(axis.y(), axis.x());
  if (y < 0) y += geometry::kPi;
  if (y >= geometry::kPi) y -= geometry::kPi;
  *yaw = y;
}

geometry::OrientedBox boxOfPoints(const std::vector<Vec3>& pts) {
  Vec2 c;
  double l = 0, w = 0, y = 0;
  fitRectangle(pts, &c, &l, &w, &y);
  geometry::OrientedBox b;
  b.center = Vec3(c.x(), c.y(), 0.5);
  b.size = Vec3(std::max(l, 1e-3), std::max(w, 1e-3), 1.0);
  b.yaw = y;
  return b;
}

}  // namespace

PinholeCamera pinholeFromHfov(int width, int height, double hfov_deg) {
  if (width < 1 || height < 1 || !(hfov_deg > 0 && hfov_deg < 180)) {
    throw scenario::ConfigError(
        "camera: expected a size >= 1 px and a field of view in (0, 180) "
        "degrees, got " +
        std::to_string(width) + "x" + std::to_string(height) + ", " + fmt(hfov_deg));
  }
  PinholeCamera c;
  c.width = width;
  c.height = height;
  c.fx = c.fy = 0.5 * width / std::tan(0.5 * geometry::degToRad(hfov_deg));
  c.cx = 0.5 * (width - 1);
  c.cy = 0.5 * (height - 1);
  return c;
}

Eigen::Isometry3d opticalPose(const Eigen::Isometry3d& world_T_base, const Vec3& mount_xyz,
                              const Vec3& mount_rpy_deg) {
  const Vec3 rpy = mount_rpy_deg * (geometry::kPi / 180.0);
  Eigen::Isometry3d base_T_link = Eigen::Isometry3d::Identity();
  base_T_link.translation() = mount_xyz;
  // Positive pitch about +y (left) turns the forward axis down (as the planner's look-at code).
  base_T_link.linear() =
      (Eigen::AngleAxisd(rpy.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Vec3::UnitY()) *
       Eigen::AngleAxisd(rpy.x(), Vec3::UnitX()))
          .toRotationMatrix();
  // Optical axes in the link frame (x forward, y left, z up): x right = -y, y down = -z,
  // z forward = x.
  Eigen::Isometry3d link_T_optical = Eigen::Isometry3d::Identity();
  link_T_optical.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return world_T_base * base_T_link * link_T_optical;
}

void DetectorSettings::validate() const {
  auto need = [](bool ok, const std::string& field, const std::string& what,
                 const std::string& got) {
    if (!ok)
      throw scenario::ConfigError("detector." + field + ": expected " + what + ", got " + got);
  };
  need(!colors.empty(), "colors", "at least one colour", "none");
  for (const auto& [name, ranges] : colors) {
    need(!ranges.empty(), "colors." + name, "at least one HSV range", "none");
    for (std::size_t i = 0; i < ranges.size(); ++i) {
      const HsvRange& r = ranges[i];
      const std::string f = "colors." + name + "[" + std::to_string(i) + "]";
      auto in = [](int v, int hi) { return v >= 0 && v <= hi; };
      need(in(r.h_min, 179) && in(r.h_max, 179), f + ".h", "hues in [0, 179]",
           std::to_string(r.h_min) + ".." + std::to_string(r.h_max));
      need(in(r.s_min, 255) && in(r.s_max, 255) && r.s_min <= r.s_max, f + ".s",
           "saturations min <= max in [0, 255]",
           std::to_string(r.s_min) + ".." + std::to_string(r.s_max));
      need(in(r.v_min, 255) && in(r.v_max, 255) && r.v_min <= r.v_max, f + ".v",
           "values min <= max in [0, 255]",
           std::to_string(r.v_min) + ".." + std::to_string(r.v_max));
    }
  }
  need(min_blob_pixels >= 1, "min_blob_pixels", "pixels >= 1", std::to_string(min_blob_pixels));
  need(open_kernel >= 0 && open_kernel <= 31, "open_kernel", "pixels in [0, 31]",
       std::to_string(open_kernel));
  need(close_kernel >= 0 && close_kernel <= 31, "close_kernel", "pixels in [0, 31]",
       std::to_string(close_kernel));
  need(std::isfinite(ground_z), "ground_z", "metres", fmt(ground_z));
  need(height_min >= 0 && height_max > height_min, "height_min/height_max",
       "0 <= height_min < height_max", fmt(height_min) + ", " + fmt(height_max));
  need(merge_gap >= 0, "merge_gap", "metres >= 0", fmt(merge_gap));
  need(size_tolerance > 0 && size_tolerance < 1, "size_tolerance", "a fraction in (0, 1)",
       fmt(size_tolerance));
  need(max_range > 0, "max_range", "metres > 0", fmt(max_range));
  need(snow >= 0 && snow <= 1, "snow", "a cover in [0, 1]", fmt(snow));
  need(snow_whitening >= 0 && std::isfinite(snow_whitening), "snow_whitening",
       "a finite factor >= 0", fmt(snow_whitening));
}

DetectorSettings defaultDetectorSettings() {
  DetectorSettings s;
  // Chromatic colours by hue with enough saturation; achromatic ones by value bands at low
  // saturation (silver overlaps white and grey on purpose: the size check decides).
  s.colors["red"] = {{0, 10, 100, 255, 60, 255}, {170, 179, 100, 255, 60, 255}};
  s.colors["yellow"] = {{18, 35, 100, 255, 80, 255}};
  s.colors["green"] = {{36, 85, 80, 255, 40, 255}};
  s.colors["blue"] = {{95, 130, 100, 255, 40, 255}};
  // White: measured on the renderer's images of the default scenario (dawn 6.1 h, rain 0.5,
  // camera noise): a white car is V 60..125 (median ~100) and S 12..90 (noise), nowhere near
  // V 200; silver, grey and beige cars overlap it, so the size check and the context decide.
  s.colors["white"] = {{0, 179, 0, 110, 66, 255}};
  s.colors["silver"] = {{0, 179, 0, 40, 140, 215}};
  s.colors["grey"] = {{0, 179, 0, 40, 70, 150}};
  s.colors["black"] = {{0, 179, 0, 255, 0, 55}};
  return s;
}

ColorShapeDetector::ColorShapeDetector(DetectorSettings settings) : settings_(std::move(settings)) {
  settings_.validate();
}

bool ColorShapeDetector::trackable(const CarCandidate& c, const Vec3& expected) const {
  if (c.reject.empty()) return true;
  const double grow = 1.0 + settings_.size_tolerance;
  return c.cut && c.range <= settings_.max_range && c.length <= grow * expected.x() &&
         c.width <= grow * expected.y();
}

cv::Mat ColorShapeDetector::colorMask(const cv::Mat& rgb, const std::string& color) const {
  const auto it = settings_.colors.find(color);
  if (it == settings_.colors.end()) {
    throw scenario::ConfigError("detector.colors: no HSV ranges for colour '" + color + "'");
  }
  if (rgb.type() != CV_8UC3) {
    throw scenario::ConfigError("detector: expected an 8-bit 3-channel RGB image");
  }
  cv::Mat hsv;
  cv::cvtColor(rgb, hsv, cv::COLOR_RGB2HSV);
  // The snow's white taken out for the chromatic ranges: each channel less k x the least one.
  constexpr int kChromaticSaturation = 60;
  const double k = std::min(0.9, settings_.snow_whitening * settings_.snow);
  cv::Mat unsnowed;
  const bool chromatic = std::any_of(it->second.begin(), it->second.end(), [](const HsvRange& r) {
    return r.s_min >= kChromaticSaturation;
  });
  if (k > 0 && chromatic) {
    std::vector<cv::Mat> ch;
    cv::split(rgb, ch);
    cv::Mat least;
    cv::min(ch[0], ch[1], least);
    cv::min(least, ch[2], least);
    for (cv::Mat& c : ch) cv::addWeighted(c, 1.0, least, -k, 0.0, c);
    cv::Mat rgb2;
    cv::merge(ch, rgb2);
    cv::cvtColor(rgb2, unsnowed, cv::COLOR_RGB2HSV);
  }
  cv::Mat mask = cv::Mat::zeros(rgb.size(), CV_8U), part;
  for (const HsvRange& r : it->second) {
    const cv::Mat& in = !unsnowed.empty() && r.s_min >= kChromaticSaturation ? unsnowed : hsv;
    auto add = [&](int h0, int h1) {
      cv::inRange(in, cv::Scalar(h0, r.s_min, r.v_min), cv::Scalar(h1, r.s_max, r.v_max), part);
      mask |= part;
    };
    if (r.h_min <= r.h_max) {
      add(r.h_min, r.h_max);
    } else {
      add(r.h_min, 179);
      add(0, r.h_max);
    }
  }
  return mask;
}

std::vector<CarCandidate> ColorShapeDetector::detect(const cv::Mat& rgb, const cv::Mat& depth,
                                                     const PinholeCamera& cam,
                                                     const Eigen::Isometry3d& world_T_optical,
                                                     const std::string& color,
                                                     const Vec3& expected) const {
  if (depth.type() != CV_32FC1 || depth.size() != rgb.size()) {
    throw scenario::ConfigError(
        "detector: expected a 32-bit float depth image of the colour "
        "image's size");
  }
  if (!(cam.fx > 0 && cam.fy > 0))
    throw scenario::ConfigError("detector: camera fx, fy must be > 0");
  const DetectorSettings& s = settings_;
  const cv::Mat colour = colorMask(rgb, color);

  // Pixels of the colour at car height, with their map-frame points.
  cv::Mat car = cv::Mat::zeros(rgb.size(), CV_8U);
  cv::Mat points(rgb.size(), CV_64FC3, cv::Scalar(0, 0, 0));
  const Eigen::Matrix3d R = world_T_optical.linear();
  const Vec3 T = world_T_optical.translation();
  for (int v = 0; v < rgb.rows; ++v) {
    const std::uint8_t* m = colour.ptr<std::uint8_t>(v);
    const float* d = depth.ptr<float>(v);
    for (int u = 0; u < rgb.cols; ++u) {
      if (!m[u]) continue;
      const double z = d[u];
      if (!std::isfinite(z) || z <= 0) continue;
      const Vec3 p = R * Vec3((u - cam.cx) / cam.fx * z, (v - cam.cy) / cam.fy * z, z) + T;
      const double h = p.z() - s.ground_z;
      if (h < s.height_min || h > s.height_max) continue;
      car.at<std::uint8_t>(v, u) = 255;
      points.at<cv::Vec3d>(v, u) = cv::Vec3d(p.x(), p.y(), p.z());
    }
  }
  cv::Mat joined = car.clone();
  if (s.open_kernel > 1) {
    cv::morphologyEx(joined, joined, cv::MORPH_OPEN,
                     cv::getStructuringElement(cv::MORPH_RECT, {s.open_kernel, s.open_kernel}));
  }
  if (s.close_kernel > 1) {
    cv::morphologyEx(joined, joined, cv::MORPH_CLOSE,
                     cv::getStructuringElement(cv::MORPH_RECT, {s.close_kernel, s.close_kernel}));
  }
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(joined, labels, stats, centroids, 8, CV_32S);

  std::vector<Blob> blobs(static_cast<std::size_t>(std::max(0, n - 1)));
  for (int v = 0; v < rgb.rows; ++v) {
    const int* l = labels.ptr<int>(v);
    const std::uint8_t* c = car.ptr<std::uint8_t>(v);
    const float* d = depth.ptr<float>(v);
    for (int u = 0; u < rgb.cols; ++u) {
      if (l[u] <= 0 || !c[u]) continue;
      Blob& b = blobs[static_cast<std::size_t>(l[u] - 1)];
      const cv::Vec3d& p = points.at<cv::Vec3d>(v, u);
      b.points.emplace_back(p[0], p[1], p[2]);
      b.depths.push_back(d[u]);
      ++b.pixels;
    }
  }
  for (int k = 1; k < n; ++k) {
    Blob& b = blobs[static_cast<std::size_t>(k - 1)];
    b.box = cv::Rect(stats.at<int>(k, cv::CC_STAT_LEFT), stats.at<int>(k, cv::CC_STAT_TOP),
                     stats.at<int>(k, cv::CC_STAT_WIDTH), stats.at<int>(k, cv::CC_STAT_HEIGHT));
    b.border = b.box.x <= 0 || b.box.y <= 0 || b.box.x + b.box.width >= rgb.cols ||
               b.box.y + b.box.height >= rgb.rows;
  }
  // Small specks take no part (not even in merging).
  std::vector<int> kept;
  for (std::size_t i = 0; i < blobs.size(); ++i) {
    if (blobs[i].pixels >= std::max(3, s.min_blob_pixels / 4)) {
      blobs[i].footprint = boxOfPoints(blobs[i].points);
      kept.push_back(static_cast<int>(i));
    }
  }
  // Pieces of one vehicle (split by its windows) are merged by their ground distance.
  std::vector<int> parent(blobs.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t a = 0; a < kept.size(); ++a) {
    for (std::size_t b = a + 1; b < kept.size(); ++b) {
      const auto& A = blobs[static_cast<std::size_t>(kept[a])];
      const auto& B = blobs[static_cast<std::size_t>(kept[b])];
      if (geometry::footprintDistance(A.footprint, B.footprint) <= s.merge_gap) {
        parent[static_cast<std::size_t>(root(parent, kept[a]))] = root(parent, kept[b]);
      }
    }
  }
  std::map<int, Blob> groups;
  for (int i : kept) {
    Blob& g = groups[root(parent, i)];
    const Blob& b = blobs[static_cast<std::size_t>(i)];
    g.points.insert(g.points.end(), b.points.begin(), b.points.end());
    g.depths.insert(g.depths.end(), b.depths.begin(), b.depths.end());
    g.box = g.pixels == 0 ? b.box : (g.box | b.box);
    g.pixels += b.pixels;
    g.border = g.border || b.border;
  }

  std::vector<CarCandidate> out;
  for (auto& [id, g] : groups) {
    if (g.pixels < s.min_blob_pixels) continue;
    CarCandidate c;
    Vec2 centre;
    fitRectangle(g.points, &centre, &c.length, &c.width, &c.yaw);
    c.position = Vec3(centre.x(), centre.y(), s.ground_z);
    c.pixels = g.pixels;
    c.box = g.box;
    c.top = -1e18;
    for (const auto& p : g.points) c.top = std::max(c.top, p.z());
    std::nth_element(g.depths.begin(), g.depths.begin() + static_cast<long>(g.depths.size() / 2),
                     g.depths.end());
    c.range = g.depths[g.depths.size() / 2];
    const double tol = s.size_tolerance;
    const double el = std::abs(c.length - expected.x()) / (tol * expected.x());
    const double ew = std::abs(c.width - expected.y()) / (tol * expected.y());
    c.size_score = std::clamp(1.0 - std::max(el, ew), 0.0, 1.0);
    char buf[160];
    c.cut = g.border;
    if (g.border && s.reject_border) {
      c.reject = "touches the image border";
    } else if (c.range > s.max_range) {
      std::snprintf(buf, sizeof(buf), "%.0f m away (max_range %.0f m)", c.range, s.max_range);
      c.reject = buf;
    } else if (el > 1.0 || ew > 1.0) {
      std::snprintf(buf, sizeof(buf), "%.2f x %.2f m, expected %.2f x %.2f m +- %.0f%%", c.length,
                    c.width, expected.x(), expected.y(), 100 * tol);
      c.reject = buf;
    }
    out.push_back(c);
  }
  std::stable_sort(out.begin(), out.end(), [](const CarCandidate& a, const CarCandidate& b) {
    if (a.reject.empty() != b.reject.empty()) return a.reject.empty();
    return a.size_score > b.size_score;
  });
  return out;
}

double claimConfidence(double size_score, int relations_checked, int relations_skipped) {
  const int listed = relations_checked + relations_skipped;
  const double context = listed > 0 ? static_cast<double>(relations_checked) / listed : 0.0;
  return std::clamp(0.35 + 0.4 * size_score + 0.25 * context, 0.0, 1.0);
}

}  // namespace hameritt::clients
