// hameritt_render: renders the payload cameras of a scenario at one time with the in-house
// renderer and writes, per camera, the RGB image, a colour-mapped depth image, the semantic
// segmentation, the instance mask, the RGB with the 2D boxes drawn, the camera_info YAML, and
// one boxes.json for all cameras.
//   hameritt_render --sim-config FILE --time T --out DIR [--camera NAME|all]
//                   [--pose x,y,z,yaw] [--set KEY=VALUE ...] [--frame N] [--models DIR]
//                   [--lod PX]
// Exit codes: 0 success, 2 bad input or unwritable output, 1 rendering failure.

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "hameritt/render/renderer.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/scenario_io.h"
#include "hameritt/scenario/sim_config_io.h"

namespace render = hameritt::render;
namespace scenario = hameritt::scenario;
using scenario::ConfigError;
using scenario::OutputError;

namespace {

const char* kUsage =
    "usage: hameritt_render --sim-config FILE --time T --out DIR [--camera NAME|all]\n"
    "                       [--pose x,y,z,yaw] [--set KEY=VALUE ...] [--frame N] [--models DIR]\n"
    "                       [--lod PX]\n"
    "  --sim-config FILE  scenario sim_config.json\n"
    "  --time T           scenario time in seconds, 0..duration\n"
    "  --out DIR          output directory (created if missing)\n"
    "  --camera NAME      payload camera to render, or all (default)\n"
    "  --pose x,y,z,yaw   UAV pose (ENU metres, yaw radians, level); default: the sim_config's\n"
    "                     uav.perception_path at T, else the start pose at altitude min\n"
    "  --set KEY=VALUE    environment: time_of_day (0..24), fog, dust, rain, snow, foliage\n"
    "                     (0..1); camera noise: gaussian_std, salt_pepper (0..1), motion_blur_px\n"
    "                     (>= 0); noise=on|off, weather=on|off\n"
    "  --frame N          frame index (seeds the noise and the particles; default 0)\n"
    "  --models DIR       models directory (default: the package's models/)\n"
    "  --lod PX           far instances drawn with coarse meshes whose deviation projects to at\n"
    "                     most PX pixels (default 0.5; 0: every mesh in full detail)\n"
    "Writes per camera <camera>_{rgb,depth,segmentation,instances,boxes}.png and\n"
    "<camera>_camera_info.yaml, and boxes.json.\n";

double parseNumber(const std::string& what, const std::string& v) {
  double x = 0.0;
  if (!scenario::parseNumber(v, &x)) {
    throw ConfigError(what + ": expected a number, got '" + v + "'");
  }
  return x;
}

double parseRange(const std::string& what, const std::string& v, double lo, double hi) {
  const double x = parseNumber(what, v);
  if (x < lo || x > hi) {
    throw ConfigError(what + ": expected a value in [" + scenario::formatNumber(lo) + ", " +
                      scenario::formatNumber(hi) + "], got " + v);
  }
  return x;
}

bool parseOnOff(const std::string& what, const std::string& v) {
  if (v == "on" || v == "true" || v == "1") return true;
  if (v == "off" || v == "false" || v == "0") return false;
  throw ConfigError(what + ": expected on or off, got '" + v + "'");
}

struct Options {
  std::string sim_config, out, camera = "all", models;
  double time = 0;
  bool have_time = false, have_pose = false;
  double pose[4] = {0, 0, 0, 0};
  std::vector<std::string> sets;
  std::uint64_t frame = 0;
  double lod_px = render::RendererOptions().lod_max_error_px;
};

// Applies one --set KEY=VALUE.
void applySet(const std::string& kv, scenario::SimConfig* cfg, render::RenderRequest* req) {
  const auto eq = kv.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw ConfigError("--set: expected KEY=VALUE, got '" + kv + "'");
  }
  const std::string key = kv.substr(0, eq), value = kv.substr(eq + 1);
  const std::string what = "--set " + key;
  auto& env = cfg->environment;
  auto& pert = cfg->perturbations;
  if (key == "time_of_day") {
    env.time_of_day = parseRange(what, value, 0.0, 24.0);
  } else if (key == "fog") {
    env.fog = parseRange(what, value, 0.0, 1.0);
  } else if (key == "dust") {
    env.dust = parseRange(what, value, 0.0, 1.0);
  } else if (key == "rain") {
    env.rain = parseRange(what, value, 0.0, 1.0);
  } else if (key == "snow") {
    env.snow = parseRange(what, value, 0.0, 1.0);
  } else if (key == "foliage") {
    env.foliage = parseRange(what, value, 0.0, 1.0);
  } else if (key == "gaussian_std") {
    pert.gaussian_noise_std = parseRange(what, value, 0.0, 1.0);
  } else if (key == "salt_pepper") {
    pert.salt_pepper_probability = parseRange(what, value, 0.0, 1.0);
  } else if (key == "motion_blur_px") {
    pert.motion_blur_px = parseRange(what, value, 0.0, 100.0);
  } else if (key == "noise") {
    req->noise = parseOnOff(what, value);
  } else if (key == "weather") {
    req->weather = parseOnOff(what, value);
  } else {
    throw ConfigError("--set: unknown key '" + key +
                      "' (time_of_day, fog, dust, rain, snow, foliage, gaussian_std, salt_pepper, "
                      "motion_blur_px, noise, weather)");
  }
}

Options parseArgs(int argc, char** argv, bool* help) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw ConfigError(a + ": missing value");
      return argv[++i];
    };
    if (a == "--sim-config") {
      o.sim_config = next();
    } else if (a == "--time") {
      o.time = parseNumber("--time", next());
      o.have_time = true;
    } else if (a == "--out") {
      o.out = next();
    } else if (a == "--camera") {
      o.camera = next();
    } else if (a == "--models") {
      o.models = next();
    } else if (a == "--pose") {
      const std::string v = next();
      std::vector<std::string> parts;
      std::size_t start = 0;
      for (std::size_t k = 0; k <= v.size(); ++k) {
        if (k == v.size() || v[k] == ',') {
          parts.push_back(v.substr(start, k - start));
          start = k + 1;
        }
      }
      if (parts.size() != 4) throw ConfigError("--pose: expected x,y,z,yaw, got '" + v + "'");
      for (int k = 0; k < 4; ++k)
        o.pose[k] = parseNumber("--pose", parts[static_cast<std::size_t>(k)]);
      o.have_pose = true;
    } else if (a == "--lod") {
      o.lod_px = parseNumber("--lod", next());
      if (o.lod_px < 0) throw ConfigError("--lod: expected a number of pixels >= 0");
    } else if (a == "--set") {
      o.sets.push_back(next());
    } else if (a == "--frame") {
      const std::string v = next();
      if (v.empty() || v.find_first_not_of("0123456789") != std::string::npos || v.size() > 19) {
        throw ConfigError("--frame: expected a non-negative integer, got '" + v + "'");
      }
      o.frame = std::stoull(v);
    } else if (a == "-h" || a == "--help") {
      *help = true;
      return o;
    } else {
      throw ConfigError("unknown argument '" + a + "'");
    }
  }
  if (o.sim_config.empty()) throw ConfigError("--sim-config is required");
  if (!o.have_time) throw ConfigError("--time is required");
  if (o.out.empty()) throw ConfigError("--out is required");
  return o;
}

// ----------------------------------------------------------------------------- visualisation

cv::Mat rgbToBgr(const render::FrameSet& f) {
  cv::Mat rgb(f.intrinsics.height, f.intrinsics.width, CV_8UC3,
              const_cast<std::uint8_t*>(f.rgb.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  return bgr;
}

// Depth on a logarithmic scale between the nearest and the farthest hit: near red, far blue;
// black where nothing was hit.
cv::Mat depthImage(const render::FrameSet& f) {
  const int w = f.intrinsics.width, h = f.intrinsics.height;
  float lo = std::numeric_limits<float>::infinity(), hi = 0;
  for (float d : f.depth) {
    if (std::isfinite(d)) {
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  }
  cv::Mat gray(h, w, CV_8UC1, cv::Scalar(0));
  if (hi > 0) {
    lo = std::max(lo, 0.1f);
    const float span = std::max(std::log(hi / lo), 1e-3f);
    for (int i = 0; i < w * h; ++i) {
      const float d = f.depth[static_cast<std::size_t>(i)];
      if (!std::isfinite(d)) continue;
      const float t = std::clamp(std::log(std::max(d, lo) / lo) / span, 0.0f, 1.0f);
      gray.data[i] = static_cast<std::uint8_t>(std::lround(255.0f * (1.0f - t)));
    }
  }
  cv::Mat color;
  cv::applyColorMap(gray, color, cv::COLORMAP_TURBO);
  for (int i = 0; i < w * h; ++i) {
    if (!std::isfinite(f.depth[static_cast<std::size_t>(i)])) {
      color.at<cv::Vec3b>(i / w, i % w) = cv::Vec3b(0, 0, 0);
    }
  }
  return color;
}

// Class palette (RGB) by semantic id.
cv::Vec3b semanticColor(int id) {
  static const int kPalette[][3] = {
      {70, 130, 180},   // 0 sky
      {110, 160, 70},   // 1 ground
      {128, 64, 128},   // 2 street
      {170, 150, 120},  // 3 driveway
      {220, 60, 50},    // 4 house
      {250, 170, 30},   // 5 garage
      {190, 153, 153},  // 6 fence
      {40, 120, 40},    // 7 tree
      {0, 60, 230},     // 8 car
      {220, 20, 200},   // 9 pedestrian
      {255, 255, 255},  // 10 uav
      {180, 70, 60},    // 11 building
      {200, 130, 40},   // 12 parking_garage
      {150, 130, 140},  // 13 parking_lot
      {100, 50, 100},   // 14 alley
      {230, 230, 0},    // 15 lamp_post
      {250, 60, 0},     // 16 traffic_light
      {0, 170, 200},    // 17 bus_stop
      {140, 90, 40},    // 18 bench
      {80, 180, 60},    // 19 street_tree
  };
  const int n = static_cast<int>(sizeof(kPalette) / sizeof(kPalette[0]));
  const int* c = kPalette[id >= 0 && id < n ? id : 0];
  return cv::Vec3b(static_cast<std::uint8_t>(c[2]), static_cast<std::uint8_t>(c[1]),
                   static_cast<std::uint8_t>(c[0]));
}

cv::Mat segmentationImage(const render::FrameSet& f) {
  cv::Mat m(f.intrinsics.height, f.intrinsics.width, CV_8UC3);
  for (int i = 0; i < m.rows * m.cols; ++i) {
    m.at<cv::Vec3b>(i / m.cols, i % m.cols) =
        semanticColor(f.semantic[static_cast<std::size_t>(i)]);
  }
  return m;
}

cv::Mat instanceImage(const render::FrameSet& f) {
  cv::Mat m(f.intrinsics.height, f.intrinsics.width, CV_8UC3);
  for (int i = 0; i < m.rows * m.cols; ++i) {
    const std::uint32_t id = f.instance[static_cast<std::size_t>(i)];
    cv::Vec3b c(0, 0, 0);
    if (id != 0) {
      std::uint32_t h = id * 2654435761u;
      h ^= h >> 15;
      h *= 2246822519u;
      h ^= h >> 13;
      c = cv::Vec3b(static_cast<std::uint8_t>(64 + (h & 0xBF)),
                    static_cast<std::uint8_t>(64 + ((h >> 8) & 0xBF)),
                    static_cast<std::uint8_t>(64 + ((h >> 16) & 0xBF)));
    }
    m.at<cv::Vec3b>(i / m.cols, i % m.cols) = c;
  }
  return m;
}

cv::Mat boxesImage(const render::FrameSet& f) {
  cv::Mat m = rgbToBgr(f);
  for (const auto& b : f.boxes) {
    cv::Scalar color(80, 220, 80);  // others: green (BGR)
    if (b.role == "target") color = cv::Scalar(40, 40, 255);
    if (b.role == "confuser") color = cv::Scalar(0, 170, 255);
    if (b.role == "world") color = cv::Scalar(220, 200, 60);
    cv::rectangle(m, cv::Point(b.x_min, b.y_min), cv::Point(b.x_max, b.y_max), color, 1);
    if (b.role == "target" || b.role == "confuser") {
      const std::string text = b.entity_id + " (" + b.role + ")";
      int base = 0;
      const cv::Size ts = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, 0.4, 1, &base);
      const int y = b.y_min - 3 >= ts.height ? b.y_min - 3 : b.y_max + ts.height + 3;
      cv::rectangle(m, cv::Point(b.x_min, y - ts.height - 1), cv::Point(b.x_min + ts.width, y + 2),
                    color, cv::FILLED);
      cv::putText(m, text, cv::Point(b.x_min, y), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                  cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
  }
  return m;
}

std::string png(const cv::Mat& m, const std::string& name) {
  std::vector<unsigned char> buf;
  if (!cv::imencode(".png", m, buf)) throw OutputError(name + ": PNG encoding failed");
  return std::string(buf.begin(), buf.end());
}

std::string cameraInfoYaml(const std::string& name, const render::Intrinsics& k) {
  char buf[1024];
  std::snprintf(
      buf, sizeof(buf),
      "image_width: %d\nimage_height: %d\ncamera_name: %s\n"
      "camera_matrix:\n  rows: 3\n  cols: 3\n  data: [%.9g, 0, %.9g, 0, %.9g, %.9g, 0, 0, 1]\n"
      "distortion_model: plumb_bob\n"
      "distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [0, 0, 0, 0, 0]\n"
      "rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n"
      "projection_matrix:\n  rows: 3\n  cols: 4\n"
      "  data: [%.9g, 0, %.9g, 0, 0, %.9g, %.9g, 0, 0, 0, 1, 0]\n",
      k.width, k.height, name.c_str(), k.fx, k.cx, k.fy, k.cy, k.fx, k.cx, k.fy, k.cy);
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> written;
  bool created_dir = false;
  std::string out_dir;
  auto cleanup = [&]() {
    for (const auto& p : written) std::remove(p.c_str());
    if (created_dir) ::rmdir(out_dir.c_str());
  };
  try {
    bool help = false;
    const Options o = parseArgs(argc, argv, &help);
    if (help) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    out_dir = o.out;
    scenario::SimConfig cfg = scenario::loadSimConfig(o.sim_config);
    if (o.time < 0.0 || o.time > cfg.duration) {
      throw ConfigError("--time: expected a time in [0, " + scenario::formatNumber(cfg.duration) +
                        "] (the scenario's duration), got " + scenario::formatNumber(o.time));
    }
    render::RenderRequest base;
    base.time = o.time;
    base.frame_index = o.frame;
    for (const auto& s : o.sets) applySet(s, &cfg, &base);
    std::vector<const scenario::CameraSpec*> cams;
    for (const auto& c : cfg.uav.cameras) {
      if (o.camera == "all" || o.camera == c.name) cams.push_back(&c);
    }
    if (cams.empty()) {
      std::string names;
      for (const auto& c : cfg.uav.cameras) names += (names.empty() ? "" : ", ") + c.name;
      throw ConfigError("--camera: no camera '" + o.camera + "' in " + o.sim_config +
                        " (cameras: " + names + ", or all)");
    }
    render::RendererOptions ropt;
    ropt.models_dir = o.models.empty() ? render::defaultModelsDir() : o.models;
    ropt.lod_max_error_px = o.lod_px;
    struct stat st {};
    if (::stat((ropt.models_dir + "/meshes").c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
      throw ConfigError("--models: " + ropt.models_dir + "/meshes is not a directory");
    }
    // UAV pose: level, at the given pose or on the perception path.
    double x, y, z, yaw;
    std::string pose_source;
    if (o.have_pose) {
      x = o.pose[0], y = o.pose[1], z = o.pose[2], yaw = o.pose[3];
      pose_source = "--pose";
    } else if (cfg.uav.perception_path && !cfg.uav.perception_path->trajectory.empty()) {
      const auto p = scenario::sampleTrajectory(cfg.uav.perception_path->trajectory, o.time);
      x = p.x, y = p.y, z = p.z, yaw = p.yaw;
      pose_source = "perception_path";
    } else {
      x = cfg.uav.start.x, y = cfg.uav.start.y, z = std::max(cfg.uav.start.z, cfg.uav.altitude_min);
      yaw = cfg.uav.start.yaw;
      pose_source = "start at altitude min";
    }
    Eigen::Isometry3d world_T_base = Eigen::Isometry3d::Identity();
    world_T_base.translation() = Eigen::Vector3d(x, y, z);
    world_T_base.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();

    const scenario::World world = scenario::generateCheckedWorld(cfg, o.sim_config);
    render::Renderer renderer(world, cfg, ropt);

    // Render everything into memory first; files are written only when all succeeded.
    std::vector<std::pair<std::string, std::string>> files;
    nlohmann::ordered_json boxes_json;
    boxes_json["scenario_id"] = cfg.scenario_id;
    boxes_json["time"] = o.time;
    boxes_json["frame_index"] = o.frame;
    boxes_json["uav_pose"] = {{"x", x}, {"y", y}, {"z", z}, {"yaw", yaw}, {"source", pose_source}};
    boxes_json["gl_renderer"] = renderer.glRenderer();
    nlohmann::ordered_json cams_json = nlohmann::ordered_json::object();
    int camera_index = 0;
    for (std::size_t ci = 0; ci < cfg.uav.cameras.size(); ++ci) {
      const auto& c = cfg.uav.cameras[ci];
      if (o.camera != "all" && o.camera != c.name) continue;
      camera_index = static_cast<int>(ci);
      render::RenderRequest req = base;
      req.camera_index = camera_index;
      req.intrinsics = render::intrinsicsFromHfov(c.width, c.height, c.hfov_deg);
      const double d2r = 3.14159265358979323846 / 180.0;
      req.world_T_optical = render::opticalPose(world_T_base, c.mount_xyz, c.mount_rpy * d2r);
      const render::FrameSet f = renderer.render(req);
      const std::string p = o.out + "/" + c.name;
      files.emplace_back(p + "_rgb.png", png(rgbToBgr(f), p + "_rgb.png"));
      files.emplace_back(p + "_depth.png", png(depthImage(f), p + "_depth.png"));
      files.emplace_back(p + "_segmentation.png",
                         png(segmentationImage(f), p + "_segmentation.png"));
      files.emplace_back(p + "_instances.png", png(instanceImage(f), p + "_instances.png"));
      files.emplace_back(p + "_boxes.png", png(boxesImage(f), p + "_boxes.png"));
      files.emplace_back(p + "_camera_info.yaml", cameraInfoYaml(c.name, req.intrinsics));
      nlohmann::ordered_json jb = nlohmann::ordered_json::array();
      for (const auto& b : f.boxes) {
        jb.push_back({{"entity_id", b.entity_id},
                      {"class", scenario::toString(b.cls)},
                      {"role", b.role},
                      {"instance", b.instance},
                      {"x_min", b.x_min},
                      {"y_min", b.y_min},
                      {"x_max", b.x_max},
                      {"y_max", b.y_max},
                      {"visible_pixels", b.visible_pixels},
                      {"total_pixels", b.total_pixels},
                      {"occlusion", b.occlusion}});
      }
      const auto& k = req.intrinsics;
      cams_json[c.name] = {{"width", k.width}, {"height", k.height}, {"fx", k.fx}, {"fy", k.fy},
                           {"cx", k.cx},       {"cy", k.cy},         {"boxes", jb}};
    }
    boxes_json["cameras"] = cams_json;
    files.emplace_back(o.out + "/boxes.json", boxes_json.dump(2) + "\n");

    if (::mkdir(o.out.c_str(), 0755) == 0) {
      created_dir = true;
    } else if (errno != EEXIST || ::stat(o.out.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
      throw OutputError(o.out + ": cannot create output directory: " + std::strerror(errno));
    }
    for (const auto& [path, content] : files) {
      scenario::writeFileAtomic(path, content);
      written.push_back(path);
    }
    std::fprintf(stderr, "hameritt_render: %zu camera(s) at t = %s s (%s) -> %s [%s]\n",
                 cams.size(), scenario::formatNumber(o.time).c_str(), pose_source.c_str(),
                 o.out.c_str(), renderer.glRenderer().c_str());
    return 0;
  } catch (const ConfigError& e) {
    cleanup();
    std::fprintf(stderr, "hameritt_render: error: %s\n", e.what());
    return 2;
  } catch (const OutputError& e) {
    cleanup();
    std::fprintf(stderr, "hameritt_render: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    cleanup();
    std::fprintf(stderr, "hameritt_render: failed: %s\n", e.what());
    return 1;
  }
}
