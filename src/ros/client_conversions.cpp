#include "hameritt/ros/client_conversions.h"

#include <ros/console.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "hameritt/ros/log_throttle.h"
#include "hameritt/ros/mission_conversions.h"
#include "hameritt/scenario/error.h"

namespace hameritt::ros_wrappers {

namespace {

void checkSize(const sensor_msgs::Image& msg, int bytes_per_pixel) {
  if (msg.width == 0 || msg.height == 0 ||
      msg.step < msg.width * static_cast<unsigned>(bytes_per_pixel) ||
      msg.data.size() < static_cast<std::size_t>(msg.step) * msg.height) {
    throw scenario::ConfigError("image: " + std::to_string(msg.width) + "x" +
                                std::to_string(msg.height) + " " + msg.encoding + ", step " +
                                std::to_string(msg.step) + ", " + std::to_string(msg.data.size()) +
                                " bytes: inconsistent size");
  }
  if (msg.is_bigendian && bytes_per_pixel > 1 && msg.encoding != "rgb8" && msg.encoding != "bgr8") {
    throw scenario::ConfigError("image: big-endian " + msg.encoding + " is not supported");
  }
}

}  // namespace

cv::Mat rgbFromMsg(const sensor_msgs::Image& msg) {
  if (msg.encoding != "rgb8" && msg.encoding != "bgr8") {
    throw scenario::ConfigError("image: expected rgb8 or bgr8, got '" + msg.encoding + "'");
  }
  checkSize(msg, 3);
  const cv::Mat view(static_cast<int>(msg.height), static_cast<int>(msg.width), CV_8UC3,
                     const_cast<std::uint8_t*>(msg.data.data()), msg.step);
  cv::Mat out;
  if (msg.encoding == "bgr8") {
    cv::cvtColor(view, out, cv::COLOR_BGR2RGB);
  } else {
    out = view.clone();
  }
  return out;
}

cv::Mat depthFromMsg(const sensor_msgs::Image& msg) {
  const float inf = std::numeric_limits<float>::infinity();
  if (msg.encoding == "32FC1") {
    checkSize(msg, 4);
    return cv::Mat(static_cast<int>(msg.height), static_cast<int>(msg.width), CV_32FC1,
                   const_cast<std::uint8_t*>(msg.data.data()), msg.step)
        .clone();
  }
  if (msg.encoding == "16UC1") {
    checkSize(msg, 2);
    cv::Mat out(static_cast<int>(msg.height), static_cast<int>(msg.width), CV_32FC1);
    for (int v = 0; v < out.rows; ++v) {
      const auto* row = reinterpret_cast<const std::uint16_t*>(msg.data.data() + v * msg.step);
      float* o = out.ptr<float>(v);
      for (int u = 0; u < out.cols; ++u) o[u] = row[u] == 0 ? inf : 0.001f * row[u];
    }
    return out;
  }
  throw scenario::ConfigError("depth image: expected 32FC1 or 16UC1, got '" + msg.encoding + "'");
}

clients::PinholeCamera fromMsg(const sensor_msgs::CameraInfo& msg) {
  clients::PinholeCamera c;
  c.width = static_cast<int>(msg.width);
  c.height = static_cast<int>(msg.height);
  c.fx = msg.K[0];
  c.cx = msg.K[2];
  c.fy = msg.K[4];
  c.cy = msg.K[5];
  if (!(c.fx > 0 && c.fy > 0)) {
    throw scenario::ConfigError("camera_info: K: expected fx, fy > 0, got " +
                                scenario::formatNumber(c.fx) + ", " + scenario::formatNumber(c.fy));
  }
  return c;
}

clients::Observation toObservation(const hameritt::PerceivedEntity& e) {
  clients::Observation o;
  o.entity_class = e.entity_class;
  for (const auto& kv : e.attributes) o.attributes.emplace_back(kv.key, kv.value);
  return o;
}

namespace {

// The description's attributes (the empty ones left out).
std::vector<hameritt::KeyValue> descriptionAttributes(const scenario::TargetDescription& target) {
  std::vector<hameritt::KeyValue> out;
  const std::pair<const char*, const std::string*> fields[] = {
      {"vehicle_class", &target.vehicle_class},
      {"make", &target.make},
      {"model", &target.model},
      {"color", &target.color}};
  for (const auto& [key, value] : fields) {
    if (value->empty()) continue;
    hameritt::KeyValue kv;
    kv.key = key;
    kv.value = *value;
    out.push_back(kv);
  }
  return out;
}

}  // namespace

hameritt::PerceivedEntity toPerceivedBlob(const scenario::TargetDescription& target,
                                          const clients::CarCandidate& blob) {
  hameritt::PerceivedEntity e;
  e.entity_class = target.cls;
  e.attributes = descriptionAttributes(target);
  e.position.x = blob.position.x();
  e.position.y = blob.position.y();
  e.position.z = blob.position.z();
  e.yaw = blob.yaw;
  e.box.entity_class = target.cls;
  e.box.x_min = blob.box.x;
  e.box.y_min = blob.box.y;
  e.box.x_max = blob.box.x + blob.box.width - 1;
  e.box.y_max = blob.box.y + blob.box.height - 1;
  e.box.visible_pixels = static_cast<std::uint32_t>(std::max(0, blob.pixels));
  return e;
}

clients::VehicleState toVehicleState(const hameritt::EntityState& e, double t) {
  clients::VehicleState v;
  v.t = t;
  v.position = geometry::Vec3(e.pose.position.x, e.pose.position.y, e.pose.position.z);
  const auto& q = e.pose.orientation;
  v.yaw = std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
  const double vx = e.velocity.linear.x, vy = e.velocity.linear.y;
  v.speed = std::max(0.0, vx * std::cos(v.yaw) + vy * std::sin(v.yaw));
  return v;
}

hameritt::Detection makeDetection(const std::string& client,
                                  const scenario::TargetDescription& target,
                                  const geometry::Vec3& position, double confidence,
                                  const ros::Time& stamp) {
  hameritt::Detection d;
  d.header.stamp = stamp;
  d.header.frame_id = "map";
  d.client = client;
  d.description = clients::describe(target);
  d.entity_class = target.cls;
  d.attributes = descriptionAttributes(target);
  d.position.x = position.x();
  d.position.y = position.y();
  d.position.z = position.z();
  d.confidence = static_cast<float>(confidence);
  return d;
}

std::optional<clients::MissionStateReading> readMissionState(const topic_tools::ShapeShifter& msg) {
  std::vector<std::uint8_t> bytes(msg.size());
  ros::serialization::OStream out(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  msg.write(out);
  return clients::readMissionState(msg.getMessageDefinition(), bytes.data(), bytes.size());
}

std::optional<scenario::Mission> acceptMission(const hameritt::Mission& msg,
                                               const std::string& scenario_id, const char* client) {
  scenario::Mission m;
  try {
    m = fromMsg(msg);
  } catch (const std::exception& e) {
    HAMERITT_ERROR_THROTTLE(5.0, "%s: /mission: ignored: %s", client, e.what());
    return std::nullopt;
  }
  if (m.scenario_id != scenario_id) {
    HAMERITT_ERROR_THROTTLE(
        5.0, "%s: /mission: scenario_id: expected '%s' (the sim_config's), got '%s'; ignored",
        client, scenario_id.c_str(), m.scenario_id.c_str());
    return std::nullopt;
  }
  return m;
}

}  // namespace hameritt::ros_wrappers
