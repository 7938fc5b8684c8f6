#include "hameritt/ros/camera_rig.h"

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>

#include <array>
#include <cmath>

#include "hameritt/BoundingBoxArray.h"
#include "hameritt/render/depth_encoding.h"
#include "hameritt/render/renderer.h"
#include "hameritt/ros/conversions.h"
#include "hameritt/ros/image_compression.h"
#include "hameritt/ros/lockstep.h"
#include "hameritt/scenario/error.h"

namespace hameritt::ros_wrappers {

namespace {
constexpr double kDeg = M_PI / 180.0;
}  // namespace

struct CameraRig::Camera {
  int index = 0;
  scenario::CameraSpec spec;
  render::Intrinsics intrinsics;
  std::string frame_id;  // uav/camera_<name>_optical
  int steps_per_frame = 1;
  int frames_per_decimated = 0;  // 0 = no decimated stream
  bool rgb = false, depth = false, segmentation = false, instances = false;
  ros::Publisher rgb_pub, depth_pub, seg_pub, inst_pub, info_pub, boxes_pub;
  ros::Publisher rgb_dec, depth_dec, seg_dec, inst_dec;
  ros::Publisher rgb_png, depth_png, seg_png, inst_png;  // <decimated topic>/compressed

  // Every topic of this camera (unadvertised ones are empty publishers with no subscribers).
  std::array<const ros::Publisher*, 14> publishers() const {
    return {&rgb_pub,   &depth_pub, &seg_pub,  &inst_pub, &info_pub,  &boxes_pub, &rgb_dec,
            &depth_dec, &seg_dec,   &inst_dec, &rgb_png,  &depth_png, &seg_png,   &inst_png};
  }
  // Whether frame `frame` is one of the compact stream's.
  bool decimated(std::uint64_t frame) const {
    return frames_per_decimated > 0 &&
           frame % static_cast<std::uint64_t>(frames_per_decimated) == 0;
  }
  // Whether frame `frame` is one of the compact stream's and someone wants its colour image.
  bool decimatedRgbWanted(std::uint64_t frame) const {
    if (!rgb || !decimated(frame)) return false;
    return rgb_dec.getNumSubscribers() > 0 || (rgb_png && rgb_png.getNumSubscribers() > 0);
  }
  bool wanted() const {
    for (const ros::Publisher* p : publishers()) {
      if (*p && p->getNumSubscribers() > 0) return true;
    }
    return false;
  }
};

CameraRig::CameraRig(ros::NodeHandle& nh, const scenario::World& world,
                     const scenario::SimConfig& config, const CameraRigOptions& options)
    : world_(world), config_(config), options_(options) {
  for (std::size_t i = 0; i < config.uav.cameras.size(); ++i) {
    const auto& spec = config.uav.cameras[i];
    auto cam = std::make_unique<Camera>();
    cam->index = static_cast<int>(i);
    cam->spec = spec;
    cam->intrinsics = render::intrinsicsFromHfov(spec.width, spec.height, spec.hfov_deg);
    cam->frame_id = "uav/camera_" + spec.name + "_optical";
    const double steps = options.physics_rate_hz / spec.rate_hz;
    if (!(spec.rate_hz > 0) || std::abs(steps - std::round(steps)) > 1e-9 || steps < 1) {
      throw scenario::ConfigError("uav.payload.cameras[" + std::to_string(i) +
                                  "].rate_hz: expected a rate that divides the physics rate (" +
                                  scenario::formatNumber(options.physics_rate_hz) + " Hz), got " +
                                  scenario::formatNumber(spec.rate_hz));
    }
    cam->steps_per_frame = static_cast<int>(std::round(steps));
    for (const auto& m : spec.modalities) {
      if (m == "rgb") cam->rgb = true;
      if (m == "depth") cam->depth = true;
      if (m == "segmentation") cam->segmentation = true;
      if (m == "instances") cam->instances = true;
    }
    const std::string ns = "uav/camera/" + spec.name + "/";
    if (cam->rgb) cam->rgb_pub = nh.advertise<sensor_msgs::Image>(ns + "image_raw", 4);
    if (cam->depth) cam->depth_pub = nh.advertise<sensor_msgs::Image>(ns + "depth", 4);
    if (cam->segmentation) cam->seg_pub = nh.advertise<sensor_msgs::Image>(ns + "segmentation", 4);
    if (cam->instances) cam->inst_pub = nh.advertise<sensor_msgs::Image>(ns + "instances", 4);
    if (options.decimated_rate_hz > 0) {
      const double k = spec.rate_hz / options.decimated_rate_hz;
      if (std::abs(k - std::round(k)) > 1e-9 || k < 1) {
        throw scenario::ConfigError("~record_image_rate: expected a rate that divides camera " + spec.name +
                                    "'s rate (" + scenario::formatNumber(spec.rate_hz) + " Hz), got " +
                                    scenario::formatNumber(options.decimated_rate_hz));
      }
      cam->frames_per_decimated = static_cast<int>(std::round(k));
      const std::string dns = ns + "decimated/";
      if (cam->rgb) cam->rgb_dec = nh.advertise<sensor_msgs::Image>(dns + "image_raw", 4);
      if (cam->depth) cam->depth_dec = nh.advertise<sensor_msgs::Image>(dns + "depth", 4);
      if (cam->segmentation) cam->seg_dec = nh.advertise<sensor_msgs::Image>(dns + "segmentation", 4);
      if (cam->instances) cam->inst_dec = nh.advertise<sensor_msgs::Image>(dns + "instances", 4);
      if (options.decimated_png_level >= 0) {
        // The compressed_image_transport topic names; PNG cannot hold 32FC1 depth.
        using Compressed = sensor_msgs::CompressedImage;
        if (cam->rgb) cam->rgb_png = nh.advertise<Compressed>(dns + "image_raw/compressed", 4);
        if (cam->depth && options.decimated_depth_mm) {
          cam->depth_png = nh.advertise<Compressed>(dns + "depth/compressed", 4);
        }
        if (cam->segmentation)
          cam->seg_png = nh.advertise<Compressed>(dns + "segmentation/compressed", 4);
        if (cam->instances)
          cam->inst_png = nh.advertise<Compressed>(dns + "instances/compressed", 4);
      }
    }
    cam->info_pub = nh.advertise<sensor_msgs::CameraInfo>(ns + "camera_info", 4);
    cam->boxes_pub = nh.advertise<hameritt::BoundingBoxArray>(ns + "boxes", 4);
    if (options.gate) {
      for (const ros::Publisher* p : cam->publishers()) options.gate->watch(*p);
    }
    cameras_.push_back(std::move(cam));
  }
  if (cameras_.empty()) return;
  if (options_.render_threads < 1 || options_.render_threads > 8) {
    throw scenario::ConfigError("~render_threads: expected 1..8, got " +
                                std::to_string(options_.render_threads));
  }
  // Each renderer (and its EGL context) lives on its render thread; wait until all are up.
  const int n = options_.render_threads;
  for (int w = 0; w < n; ++w) threads_.emplace_back([this, w] { run(w); });
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [this, n] { return ready_ == n; });
  if (!error_.empty()) {
    stop_ = true;
    lock.unlock();
    cv_.notify_all();
    for (auto& t : threads_) t.join();
    throw render::RenderError(error_);
  }
}

CameraRig::~CameraRig() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  for (auto& t : threads_) {
    if (t.joinable()) t.join();
  }
}

std::vector<std::pair<std::string, Eigen::Isometry3d>> CameraRig::opticalMounts() const {
  std::vector<std::pair<std::string, Eigen::Isometry3d>> out;
  for (const auto& cam : cameras_) {
    const Eigen::Vector3d rpy = cam->spec.mount_rpy * kDeg;
    out.emplace_back(cam->frame_id,
                     render::opticalPose(Eigen::Isometry3d::Identity(), cam->spec.mount_xyz, rpy));
  }
  return out;
}

void CameraRig::afterStep(std::int64_t step, const sim::UavState& uav) {
  Job job;
  for (const auto& cam : cameras_) {
    if (step % cam->steps_per_frame != 0 || !cam->wanted()) continue;
    job.shots.emplace_back(cam->index, static_cast<std::uint64_t>(step / cam->steps_per_frame));
  }
  if (job.shots.empty()) return;
  job.time = uav.t;
  job.world_T_base = Eigen::Isometry3d::Identity();
  job.world_T_base.linear() = uav.orientation.toRotationMatrix();
  job.world_T_base.translation() = uav.position;
  job.velocity = uav.velocity;
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [this] {
    return static_cast<int>(queue_.size()) < std::max(1, options_.queue_depth) || stop_;
  });
  job.seq = next_seq_++;
  queue_.push_back(std::move(job));
  lock.unlock();
  cv_.notify_all();
}

void CameraRig::flush() {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [this] { return (queue_.empty() && busy_ == 0) || stop_; });
}

std::uint64_t CameraRig::framesPublished() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return published_;
}

int CameraRig::subscribers(const std::string& topic) const {
  for (const auto& cam : cameras_) {
    for (const ros::Publisher* p : cam->publishers()) {
      if (*p && p->getTopic() == topic) return static_cast<int>(p->getNumSubscribers());
    }
  }
  return -1;
}

std::string CameraRig::glRenderer() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return gl_renderer_;
}

void CameraRig::run(int worker) {
  std::unique_ptr<render::Renderer> renderer;
  try {
    render::RendererOptions ro;
    ro.backend = options_.backend;
    ro.models_dir = options_.models_dir;
    ro.lod_max_error_px = options_.lod_max_error_px;
    renderer = std::make_unique<render::Renderer>(world_, config_, ro);
    std::lock_guard<std::mutex> lock(mutex_);
    if (worker == 0) gl_renderer_ = renderer->glRenderer();
    ++ready_;
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (error_.empty()) error_ = e.what();
    ++ready_;
  }
  cv_.notify_all();
  if (!renderer) return;

  std::vector<render::RenderRequest> requests;
  std::vector<render::FrameSet> frames;
  while (true) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [this] { return !queue_.empty() || stop_; });
      if (stop_) return;
      job = std::move(queue_.front());
      queue_.pop_front();
      ++busy_;
    }
    cv_.notify_all();
    requests.clear();
    for (const auto& [index, frame] : job.shots) {
      const Camera& cam = *cameras_[static_cast<std::size_t>(index)];
      render::RenderRequest req;
      req.intrinsics = cam.intrinsics;
      req.world_T_optical =
          render::opticalPose(job.world_T_base, cam.spec.mount_xyz, cam.spec.mount_rpy * kDeg);
      req.time = job.time;
      req.camera_index = cam.index;
      req.frame_index = frame;
      req.weather = options_.weather;
      req.noise = options_.noise;
      req.noise_free_rgb = options_.decimated_rgb_noise_free && cam.decimatedRgbWanted(frame);
      // Motion blur along the image-plane direction of the camera's own motion.
      const Eigen::Vector3d v_opt = req.world_T_optical.linear().transpose() * job.velocity;
      if (std::hypot(v_opt.x(), v_opt.y()) > 0.2) {
        req.blur_direction = Eigen::Vector2d(v_opt.x(), v_opt.y()).normalized();
      }
      requests.push_back(req);
    }
    bool rendered = false;
    try {
      // One batch: the GL rasterizes one camera while the CPU finishes another.
      renderer->render(requests, &frames);
      rendered = true;
    } catch (const std::exception& e) {
      ROS_ERROR_THROTTLE(5.0, "simulator: cameras: %s", e.what());
    }
    {
      // Publish in the order the physics produced the frame sets.
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [this, &job] { return next_publish_ == job.seq || stop_; });
      if (stop_) return;
    }
    if (rendered) {
      for (std::size_t i = 0; i < job.shots.size(); ++i) {
        const Camera& cam = *cameras_[static_cast<std::size_t>(job.shots[i].first)];
        publish(cam, job.shots[i].second, job.time, frames[i]);
      }
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++next_publish_;
      --busy_;
      published_ += job.shots.size();
    }
    cv_.notify_all();
  }
}

void CameraRig::publish(const Camera& cam, std::uint64_t frame, double time, const render::FrameSet& fs) {
  std_msgs::Header header;
  header.stamp.fromSec(time);
  header.frame_id = cam.frame_id;
  const int w = fs.intrinsics.width, h = fs.intrinsics.height;
  auto image = [&](const std::string& encoding, int bytes_per_pixel, const void* data) {
    sensor_msgs::ImagePtr m = boost::make_shared<sensor_msgs::Image>();
    m->header = header;
    m->width = static_cast<std::uint32_t>(w);
    m->height = static_cast<std::uint32_t>(h);
    m->encoding = encoding;
    m->is_bigendian = 0;
    m->step = static_cast<std::uint32_t>(w * bytes_per_pixel);
    // One copy, no zero-fill first.
    const auto* bytes = static_cast<const std::uint8_t*>(data);
    m->data.assign(bytes, bytes + static_cast<std::size_t>(w) * h * bytes_per_pixel);
    return m;
  };
  const bool decimated = cam.decimated(frame);
  auto wants = [](const ros::Publisher& p) { return p && p.getNumSubscribers() > 0; };
  auto counted = [this](const ros::Publisher& p) {
    if (options_.gate) options_.gate->count(p.getTopic());
  };
  struct Plane {
    std::string encoding;
    int bytes = 0;
    const void* data = nullptr;
  };
  // One modality: the full-rate message, and the compact stream's (the same message unless the
  // compact stream converts the image) with its PNG.
  auto send = [&](bool on, const ros::Publisher& full, const ros::Publisher& dec,
                  const ros::Publisher& png, const Plane& full_plane, const Plane& dec_plane) {
    if (!on) return;
    sensor_msgs::ImagePtr full_msg;
    if (wants(full)) {
      full_msg = image(full_plane.encoding, full_plane.bytes, full_plane.data);
      full.publish(full_msg);
      counted(full);
    }
    if (!decimated || !(wants(dec) || wants(png))) return;
    const sensor_msgs::ImagePtr m =
        (full_msg && dec_plane.data == full_plane.data)
            ? full_msg
            : image(dec_plane.encoding, dec_plane.bytes, dec_plane.data);
    if (wants(dec)) {
      dec.publish(m);
      counted(dec);
    }
    if (wants(png)) {
      png.publish(toPngCompressed(*m, options_.decimated_png_level));
      counted(png);
    }
  };
  namespace enc = sensor_msgs::image_encodings;
  const Plane rgb{enc::RGB8, 3, fs.rgb.data()};
  // The noise-free image was requested when the frame was queued; a subscriber that came later
  // (never while recording: the clock waits for the recorder) gets the noisy one this once.
  const bool noise_free = fs.rgb_noise_free.size() == fs.rgb.size();
  send(cam.rgb, cam.rgb_pub, cam.rgb_dec, cam.rgb_png, rgb,
       noise_free ? Plane{enc::RGB8, 3, fs.rgb_noise_free.data()} : rgb);
  const Plane depth{enc::TYPE_32FC1, 4, fs.depth.data()};
  std::vector<std::uint16_t> depth_mm;
  if (cam.depth && decimated && options_.decimated_depth_mm &&
      (wants(cam.depth_dec) || wants(cam.depth_png))) {
    render::depthToMillimetres(fs.depth, &depth_mm);
  }
  send(cam.depth, cam.depth_pub, cam.depth_dec, cam.depth_png, depth,
       depth_mm.empty() ? depth : Plane{enc::TYPE_16UC1, 2, depth_mm.data()});
  const Plane seg{enc::MONO8, 1, fs.semantic.data()};
  send(cam.segmentation, cam.seg_pub, cam.seg_dec, cam.seg_png, seg, seg);
  const Plane inst{enc::TYPE_16UC1, 2, fs.instance.data()};
  send(cam.instances, cam.inst_pub, cam.inst_dec, cam.inst_png, inst, inst);
  cam.info_pub.publish(toCameraInfoMsg(fs.intrinsics, header));
  counted(cam.info_pub);
  cam.boxes_pub.publish(toBoxesMsg(fs.boxes, cam.spec.name, header));
  counted(cam.boxes_pub);
}

}  // namespace hameritt::ros_wrappers
