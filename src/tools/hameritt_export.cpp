// hameritt_export: reads recorded mission bags (mission.launch record:=true) and writes a
// COCO or YOLO dataset: RGB images, 16-bit depth PNGs (millimetres), segmentation and instance
// masks, and the annotations (COCO RLE masks, boxes = mask extents, occlusion, the scenario's
// symbolic context). The bag is streamed in time order; frames are grouped by (camera, stamp)
// in a small bounded buffer and encoded on a thread pool in a fixed order, into a temporary
// directory next to --out that is renamed at the end (removed on error or SIGINT).
//   hameritt_export BAG... --format coco|yolo --out DIR [--every N] [--cameras front,down]
//                   [--split train=0.8,val=0.2] [--seed S] [--stream auto|decimated|full]
//                   [--image-format png|jpg] [--png-level fast|0..9] [--jpeg-quality 1..100]
//                   [--jobs N] [--force] [--quiet]
//   hameritt_export --preview DATASET --image-id ID|most --out FILE.png
// Exit codes: 0 success, 2 bad flags or output directory, 3 unreadable bag, 4 output write
// failure, 5 no frames to export, 1 internal error, 130 interrupted.

#include <fcntl.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "hameritt/BoundingBoxArray.h"
#include "hameritt/Mission.h"
#include "hameritt/dataset/coco.h"
#include "hameritt/dataset/encode_pool.h"
#include "hameritt/dataset/frame.h"
#include "hameritt/dataset/rle.h"
#include "hameritt/scenario/bounded_json.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/scenario_io.h"

namespace fs = std::filesystem;
namespace dataset = hameritt::dataset;

namespace {

const char* kUsage =
    "usage: hameritt_export BAG... --format coco|yolo --out DIR [--every N]\n"
    "                       [--cameras NAME,...] [--split NAME=F,...] [--seed S]\n"
    "                       [--stream auto|decimated|full] [--image-format png|jpg]\n"
    "                       [--png-level fast|0..9] [--jpeg-quality 1..100] [--jobs N] [--force]\n"
    "                       [--quiet]\n"
    "       hameritt_export --preview DATASET --image-id ID|most --out FILE.png\n"
    "  BAG...            mission bags (mission.launch record:=true)\n"
    "  --format          coco (annotations/instances_<split>.json) or yolo (labels/, data.yaml)\n"
    "  --out DIR         dataset directory (must not exist unless --force)\n"
    "  --every N         keep every N-th frame of each camera (default 1)\n"
    "  --cameras LIST    cameras to export (default: every camera in the bag)\n"
    "  --split LIST      splits and fractions, e.g. train=0.8,val=0.2 (default train=1)\n"
    "  --seed S          seed of the split assignment (default 0)\n"
    "  --stream          decimated (/uav/camera/<c>/decimated/...), full (/uav/camera/<c>/...)\n"
    "                    or auto: decimated if the bag has it (default)\n"
    "  --image-format    RGB images as png (default) or jpg\n"
    "  --png-level       fast (default: SUB filter, zlib level 1) or a zlib level 0..9 with\n"
    "                    libpng's adaptive filters (smaller, 2-3x slower)\n"
    "  --jpeg-quality    JPEG quality (default 95)\n"
    "  --jobs N          encoding threads, 1..64 (default 2)\n"
    "  --preview DATASET draw the boxes and masks of image ID of an exported COCO dataset\n"
    "                    (most: the image with the most annotations, the first of equals)\n"
    "Exit codes: 0 ok, 2 bad flags or output directory, 3 unreadable bag, 4 write failure,\n"
    "5 nothing to export, 130 interrupted.\n";

constexpr int kExitFlags = 2;
constexpr int kExitBag = 3;
constexpr int kExitWrite = 4;
constexpr int kExitEmpty = 5;
constexpr int kExitInterrupted = 130;
// --preview reads the COCO annotation files of an export: larger than scenario documents (one
// RLE mask per instance), so a limit of its own; nesting within kMaxJsonDepth.
constexpr std::uintmax_t kMaxAnnotationBytes = std::uintmax_t{1} << 30;  // 1 GiB

// An error that ends the run with an exit code.
struct ExitError : std::runtime_error {
  ExitError(int c, const std::string& m) : std::runtime_error(m), code(c) {}
  int code;
};

volatile std::sig_atomic_t g_interrupted = 0;
void onSignal(int) { g_interrupted = 1; }

const char* kModalities[] = {"image_raw", "depth", "segmentation", "instances"};
constexpr int kNumModalities = 4;
constexpr int kInstances = 3;

struct Options {
  std::vector<std::string> bags;
  std::string format;
  std::string out;
  int every = 1;
  std::vector<std::string> cameras;
  std::string split_text = "train=1";
  std::vector<dataset::SplitSpec> splits;
  std::uint64_t seed = 0;
  std::string stream = "auto";
  std::string image_format = "png";
  int png_level = -1;  // -1: OpenCV's fast path (SUB filter, zlib level 1, RLE strategy)
  int jpeg_quality = 95;
  int jobs = 2;
  bool force = false;
  bool quiet = false;
  std::string preview;
  std::int64_t image_id = -1;
};

bool parseInt(const std::string& s, long long lo, long long hi, long long* out) {
  if (s.empty()) return false;
  std::size_t used = 0;
  long long v = 0;
  try {
    v = std::stoll(s, &used);
  } catch (...) {
    return false;
  }
  if (used != s.size() || v < lo || v > hi) return false;
  *out = v;
  return true;
}

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::size_t pos = 0;
  while (true) {
    const std::size_t c = s.find(',', pos);
    out.push_back(s.substr(pos, c == std::string::npos ? std::string::npos : c - pos));
    if (c == std::string::npos) break;
    pos = c + 1;
  }
  return out;
}

Options parseArgs(int argc, char** argv) {
  Options o;
  auto need = [&](int& i) -> std::string {
    if (i + 1 >= argc) throw ExitError(kExitFlags, std::string(argv[i]) + ": expected a value");
    return argv[++i];
  };
  auto integer = [&](const std::string& flag, const std::string& v, long long lo, long long hi) {
    long long x = 0;
    if (!parseInt(v, lo, hi, &x)) {
      throw ExitError(kExitFlags, flag + ": expected an integer in " + std::to_string(lo) + ".." +
                                      std::to_string(hi) + ", got '" + v + "'");
    }
    return x;
  };
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (a == "--format") {
      o.format = need(i);
      if (o.format != "coco" && o.format != "yolo") {
        throw ExitError(kExitFlags, "--format: expected coco or yolo, got '" + o.format + "'");
      }
    } else if (a == "--out") {
      o.out = need(i);
    } else if (a == "--every") {
      o.every = static_cast<int>(integer(a, need(i), 1, 1000000));
    } else if (a == "--cameras") {
      o.cameras = splitList(need(i));
      for (const auto& c : o.cameras) {
        if (c.empty() || c.find('/') != std::string::npos) {
          throw ExitError(kExitFlags, "--cameras: expected camera names separated by commas");
        }
      }
    } else if (a == "--split") {
      o.split_text = need(i);
    } else if (a == "--seed") {
      const std::string v = need(i);
      long long x = 0;
      if (!parseInt(v, 0, std::numeric_limits<long long>::max(), &x)) {
        throw ExitError(kExitFlags, "--seed: expected a non-negative integer, got '" + v + "'");
      }
      o.seed = static_cast<std::uint64_t>(x);
    } else if (a == "--stream") {
      o.stream = need(i);
      if (o.stream != "auto" && o.stream != "decimated" && o.stream != "full") {
        throw ExitError(kExitFlags,
                        "--stream: expected auto, decimated or full, got '" + o.stream + "'");
      }
    } else if (a == "--image-format") {
      o.image_format = need(i);
      if (o.image_format != "png" && o.image_format != "jpg") {
        throw ExitError(kExitFlags,
                        "--image-format: expected png or jpg, got '" + o.image_format + "'");
      }
    } else if (a == "--png-level") {
      const std::string v = need(i);
      o.png_level = v == "fast" ? -1 : static_cast<int>(integer(a, v, 0, 9));
    } else if (a == "--jpeg-quality") {
      o.jpeg_quality = static_cast<int>(integer(a, need(i), 1, 100));
    } else if (a == "--jobs") {
      o.jobs = static_cast<int>(integer(a, need(i), 1, 64));
    } else if (a == "--force") {
      o.force = true;
    } else if (a == "--quiet") {
      o.quiet = true;
    } else if (a == "--preview") {
      o.preview = need(i);
    } else if (a == "--image-id") {
      const std::string v = need(i);
      o.image_id = v == "most" ? 0 : integer(a, v, 1, std::numeric_limits<long long>::max());
    } else if (a.size() > 1 && a[0] == '-') {
      throw ExitError(kExitFlags, "unknown flag '" + a + "'");
    } else {
      o.bags.push_back(a);
    }
  }
  if (o.out.empty()) throw ExitError(kExitFlags, "--out: required");
  if (!o.preview.empty()) {
    if (o.image_id < 0) throw ExitError(kExitFlags, "--preview: needs --image-id ID|most");
    return o;
  }
  if (o.bags.empty()) throw ExitError(kExitFlags, "expected at least one BAG");
  if (o.format.empty()) throw ExitError(kExitFlags, "--format: required (coco or yolo)");
  try {
    o.splits = dataset::parseSplits(o.split_text);
  } catch (const std::invalid_argument& e) {
    throw ExitError(kExitFlags, std::string("--split: ") + e.what());
  }
  return o;
}

// ------------------------------------------------------------------------- file output

void writeFile(const fs::path& path, const void* data, std::size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw ExitError(kExitWrite, path.string() + ": " + std::strerror(errno));
  const bool ok = std::fwrite(data, 1, size, f) == size;
  int err = ok ? 0 : errno;
  if (std::fclose(f) != 0 && err == 0) err = errno;
  if (!ok || err != 0) {
    throw ExitError(kExitWrite, path.string() + ": write failed: " + std::strerror(err));
  }
}

void writeFile(const fs::path& path, const std::string& text) {
  writeFile(path, text.data(), text.size());
}

void writeImage(const fs::path& path, const cv::Mat& img, const std::vector<int>& params) {
  std::vector<unsigned char> buf;
  if (!cv::imencode(path.extension().string(), img, buf, params)) {
    throw ExitError(kExitWrite, path.string() + ": image encoding failed");
  }
  writeFile(path, buf.data(), buf.size());
}

// ------------------------------------------------------------------------- bag input

// One image message of a frame set, raw or PNG-compressed (kept alive until encoded).
struct ImageInput {
  sensor_msgs::Image::ConstPtr raw;
  sensor_msgs::CompressedImage::ConstPtr compressed;
  bool present() const { return raw || compressed; }
};

// The modalities and boxes of one camera frame.
struct FrameSet {
  int camera = 0;
  std::int64_t stamp_ns = 0;
  ImageInput images[kNumModalities];
  bool has_boxes = false;
  std::vector<dataset::BoxMeta> boxes;
};

// A camera of the bag and the topics its frames come from.
struct CameraTopics {
  std::string name;
  bool stream_present[kNumModalities] = {false, false, false, false};
  std::string topic[kNumModalities];
  std::string boxes_topic;
};

// The decoded image (as a Mat over the message's data, or a decoded copy) and its encoding.
cv::Mat decode(const ImageInput& in, const std::string& what, std::string* encoding) {
  if (in.raw) {
    const auto& m = *in.raw;
    *encoding = m.encoding;
    int type = -1;
    std::size_t bpp = 0;
    if (m.encoding == "rgb8" || m.encoding == "bgr8") type = CV_8UC3, bpp = 3;
    if (m.encoding == "mono8") type = CV_8UC1, bpp = 1;
    if (m.encoding == "16UC1" || m.encoding == "mono16") type = CV_16UC1, bpp = 2;
    if (m.encoding == "32FC1") type = CV_32FC1, bpp = 4;
    if (type < 0) throw std::runtime_error(what + ": unsupported encoding '" + m.encoding + "'");
    if (m.width == 0 || m.height == 0 || m.step < m.width * bpp ||
        m.data.size() < static_cast<std::size_t>(m.step) * m.height) {
      throw std::runtime_error(what + ": " + std::to_string(m.data.size()) + " bytes for " +
                               std::to_string(m.width) + "x" + std::to_string(m.height) + " " +
                               m.encoding + " (step " + std::to_string(m.step) + ")");
    }
    if (m.is_bigendian && bpp > 1) throw std::runtime_error(what + ": big-endian image");
    return cv::Mat(static_cast<int>(m.height), static_cast<int>(m.width), type,
                   const_cast<std::uint8_t*>(m.data.data()), m.step);
  }
  // compressed_image_transport: "<encoding>; png compressed <bgr8|rgb8|...>".
  const auto& m = *in.compressed;
  const std::size_t semi = m.format.find(';');
  *encoding = m.format.substr(0, semi);
  if (semi == std::string::npos || m.format.find("png compressed", semi) == std::string::npos) {
    throw std::runtime_error(what + ": unsupported compressed format '" + m.format +
                             "' (expected '<encoding>; png compressed ...')");
  }
  cv::Mat img = cv::imdecode(m.data, cv::IMREAD_UNCHANGED);
  if (img.empty()) throw std::runtime_error(what + ": the PNG data does not decode");
  if (img.channels() == 3) {
    // The transport encodes in the order named after "compressed" (bgr8 unless "rgb8"), and
    // imdecode hands that order back: swap when it is not the message's encoding.
    const bool stored_rgb = m.format.find("compressed rgb8") != std::string::npos;
    if (stored_rgb != (*encoding == "rgb8")) cv::cvtColor(img, img, cv::COLOR_BGR2RGB);
  }
  return img;
}

// Ends an export whose encoding pool failed: an ExitError keeps its code, any other error is the
// bag's (a frame that does not decode).
[[noreturn]] void rethrowPoolFailure() {
  try {
    throw;
  } catch (const ExitError&) {
    throw;
  } catch (const std::exception& e) {
    throw ExitError(kExitBag, e.what());
  }
}

// ------------------------------------------------------------------------- export

class Exporter {
 public:
  Exporter(const Options& o, const fs::path& tmp) : o_(o), tmp_(tmp) {
    categories_ = dataset::entityCategories();
    class_index_ = dataset::yoloClassIndex(categories_);
    // fast: OpenCV's default path (SUB filter, zlib level 1, RLE strategy) for RGB and
    // segmentation, 2-3x faster than any explicit level (which turns on libpng's adaptive
    // filters) at similar sizes; zlib's default strategy for the 16-bit images, faster and
    // smaller there (measured per modality, BENCHMARKS.md "Dataset export").
    if (o.png_level >= 0) {
      png_params_ = png16_params_ = {cv::IMWRITE_PNG_COMPRESSION, o.png_level};
    } else {
      png16_params_ = {cv::IMWRITE_PNG_STRATEGY, cv::IMWRITE_PNG_STRATEGY_DEFAULT};
    }
    jpg_params_ = {cv::IMWRITE_JPEG_QUALITY, o.jpeg_quality};
    for (const auto& s : o.splits) {
      for (const char* d : {"images", "depth", "segmentation", "instances"}) {
        fs::create_directories(tmp / d / s.name);
      }
      if (o.format == "yolo") fs::create_directories(tmp / "labels" / s.name);
    }
    if (o.format == "coco") fs::create_directories(tmp / "annotations");
  }

  void exportBag(std::size_t bag_index, const std::string& path);
  void finish();

  std::size_t frames() const { return frames_.size(); }

 private:
  void dispatch(FrameSet&& set, const std::string& bag);
  void encode(FrameSet& set, dataset::FrameRecord& rec, const std::string& bag);

  const Options& o_;
  fs::path tmp_;
  std::vector<dataset::Category> categories_;
  std::map<std::string, int> class_index_;
  std::vector<int> png_params_, png16_params_, jpg_params_;
  std::vector<dataset::SceneContext> contexts_;
  std::vector<CameraTopics> cameras_;  // of the current bag
  std::vector<std::int64_t> camera_counter_;
  std::vector<std::unique_ptr<dataset::FrameRecord>> frames_;
  std::unique_ptr<dataset::EncodePool> pool_;
  std::mutex frames_mutex_;
  int skipped_boxes_ = 0;
  std::atomic<int> skipped_annotations_{0};
  int incomplete_ = 0;
};

void Exporter::exportBag(std::size_t bag_index, const std::string& path) {
  if (!fs::exists(path)) throw ExitError(kExitBag, path + ": no such file");
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagUnindexedException&) {
    throw ExitError(kExitBag, path +
                                  ": the bag is not indexed (a recording that did not end, "
                                  "e.g. a .bag.active file); run 'rosbag reindex' on it first");
  } catch (const std::exception& e) {
    throw ExitError(kExitBag, path + ": not a readable bag (" + e.what() +
                                  "); a truncated bag may be repaired with 'rosbag reindex'");
  }
  // Topics of the bag: cameras with an instances topic in the chosen stream.
  std::set<std::string> topics;
  {
    rosbag::View all(bag);
    for (const rosbag::ConnectionInfo* c : all.getConnections()) topics.insert(c->topic);
  }
  std::map<std::string, CameraTopics> found;
  const std::regex cam_re("^/uav/camera/([^/]+)/boxes$");
  for (const auto& t : topics) {
    std::smatch m;
    if (std::regex_match(t, m, cam_re)) found[m[1]].name = m[1];
  }
  auto has = [&](const std::string& t) {
    return topics.count(t) || topics.count(t + "/compressed");
  };
  cameras_.clear();
  for (auto& [name, cam] : found) {
    const std::string base = "/uav/camera/" + name + "/";
    bool decimated = has(base + "decimated/instances");
    if (o_.stream == "full") decimated = false;
    if (o_.stream == "decimated" && !decimated) continue;
    for (int k = 0; k < kNumModalities; ++k) {
      const std::string t = base + (decimated ? "decimated/" : "") + kModalities[k];
      cam.topic[k] = topics.count(t) ? t : t + "/compressed";
      cam.stream_present[k] = has(t);
    }
    cam.boxes_topic = base + "boxes";
    if (!cam.stream_present[kInstances]) continue;
    cameras_.push_back(cam);
  }
  if (!o_.cameras.empty()) {
    std::vector<CameraTopics> chosen;
    for (const auto& want : o_.cameras) {
      bool ok = false;
      for (const auto& c : cameras_) {
        if (c.name == want) chosen.push_back(c), ok = true;
      }
      if (!ok) {
        std::string avail;
        for (const auto& c : cameras_) avail += (avail.empty() ? "" : ", ") + c.name;
        throw ExitError(kExitFlags, "--cameras: " + path + " has no camera '" + want +
                                        "' with an instances stream (it has: " +
                                        (avail.empty() ? "none" : avail) + ")");
      }
    }
    cameras_ = chosen;
  }
  if (cameras_.empty()) {
    throw ExitError(kExitEmpty, path +
                                    ": no camera with /uav/camera/<c>/boxes and an instances "
                                    "image topic (" +
                                    o_.stream + " stream)");
  }
  camera_counter_.assign(cameras_.size(), 0);
  contexts_.push_back({});
  const int context = static_cast<int>(contexts_.size()) - 1;
  std::set<std::string> target_ids;

  std::vector<std::string> wanted = {"/mission"};
  std::map<std::string, std::pair<int, int>> route;  // topic -> (camera, modality or -1 boxes)
  for (std::size_t c = 0; c < cameras_.size(); ++c) {
    for (int k = 0; k < kNumModalities; ++k) {
      if (!cameras_[c].stream_present[k]) continue;
      wanted.push_back(cameras_[c].topic[k]);
      route[cameras_[c].topic[k]] = {static_cast<int>(c), k};
    }
    wanted.push_back(cameras_[c].boxes_topic);
    route[cameras_[c].boxes_topic] = {static_cast<int>(c), -1};
  }

  // Bounded buffers: frame sets waiting for their last modality, and boxes waiting for their
  // images (boxes come at the camera rate, images maybe decimated).
  constexpr std::size_t kMaxPending = 32;
  constexpr std::size_t kMaxBoxes = 64;
  std::map<std::pair<int, std::int64_t>, FrameSet> pending;
  std::vector<std::map<std::int64_t, std::vector<dataset::BoxMeta>>> boxes(cameras_.size());
  auto complete = [&](const FrameSet& s) {
    if (!s.has_boxes) return false;
    for (int k = 0; k < kNumModalities; ++k) {
      if (cameras_[s.camera].stream_present[k] && !s.images[k].present()) return false;
    }
    return true;
  };
  auto emitIfComplete = [&](std::map<std::pair<int, std::int64_t>, FrameSet>::iterator it) {
    if (!complete(it->second)) return;
    FrameSet set = std::move(it->second);
    pending.erase(it);
    if (camera_counter_[set.camera]++ % o_.every != 0) return;
    dispatch(std::move(set), path);
  };

  rosbag::View view(bag, rosbag::TopicQuery(wanted));
  const double t0 = view.getBeginTime().toSec(), t1 = view.getEndTime().toSec();
  auto last_report = std::chrono::steady_clock::now();
  try {
    for (const rosbag::MessageInstance& mi : view) {
      if (g_interrupted) throw ExitError(kExitInterrupted, "interrupted");
      const std::string& topic = mi.getTopic();
      if (topic == "/mission") {
        const auto m = mi.instantiate<hameritt::Mission>();
        if (!m) continue;
        auto& ctx = contexts_[context];
        ctx.scenario_id = m->scenario_id;
        ctx.relations.clear();
        for (const auto& r : m->relations) {
          ctx.relations.push_back({r.target_id, r.op, static_cast<bool>(r.eventually), r.related_id,
                                   r.related_class, r.text});
        }
        continue;
      }
      const auto rt = route.find(topic);
      if (rt == route.end()) continue;
      const int cam = rt->second.first, k = rt->second.second;
      if (k < 0) {
        const auto m = mi.instantiate<hameritt::BoundingBoxArray>();
        if (!m) throw std::runtime_error(topic + ": not a hameritt/BoundingBoxArray");
        std::vector<dataset::BoxMeta> metas;
        for (const auto& b : m->boxes) {
          metas.push_back({b.entity_id, b.entity_class, b.role, b.instance_id, b.visible_pixels,
                           b.total_pixels, b.occlusion});
          if (b.role == "target") target_ids.insert(b.entity_id);
        }
        const std::int64_t stamp = static_cast<std::int64_t>(m->header.stamp.toNSec());
        const auto it = pending.find({cam, stamp});
        if (it != pending.end()) {
          it->second.boxes = std::move(metas);
          it->second.has_boxes = true;
          emitIfComplete(it);
        } else {
          auto& cache = boxes[cam];
          cache[stamp] = std::move(metas);
          while (cache.size() > kMaxBoxes) cache.erase(cache.begin());
        }
      } else {
        ImageInput in;
        std::int64_t stamp = 0;
        if (topic.size() > 11 && topic.compare(topic.size() - 11, 11, "/compressed") == 0) {
          in.compressed = mi.instantiate<sensor_msgs::CompressedImage>();
          if (!in.compressed)
            throw std::runtime_error(topic + ": not a sensor_msgs/CompressedImage");
          stamp = static_cast<std::int64_t>(in.compressed->header.stamp.toNSec());
        } else {
          in.raw = mi.instantiate<sensor_msgs::Image>();
          if (!in.raw) throw std::runtime_error(topic + ": not a sensor_msgs/Image");
          stamp = static_cast<std::int64_t>(in.raw->header.stamp.toNSec());
        }
        auto it = pending.find({cam, stamp});
        if (it == pending.end()) {
          FrameSet s;
          s.camera = cam;
          s.stamp_ns = stamp;
          auto cached = boxes[cam].find(stamp);
          if (cached != boxes[cam].end()) {
            s.boxes = std::move(cached->second);
            s.has_boxes = true;
            boxes[cam].erase(cached);
          }
          it = pending.emplace(std::make_pair(cam, stamp), std::move(s)).first;
          // Keep the buffer bounded: the oldest incomplete set is dropped.
          if (pending.size() > kMaxPending) {
            auto oldest = pending.begin();
            for (auto p = pending.begin(); p != pending.end(); ++p) {
              if (p->first.second < oldest->first.second) oldest = p;
            }
            if (oldest != it) {
              pending.erase(oldest);
              ++incomplete_;
            }
          }
        }
        it->second.images[k] = std::move(in);
        emitIfComplete(it);
      }
      if (!o_.quiet) {
        const auto now = std::chrono::steady_clock::now();
        if (now - last_report > std::chrono::seconds(2)) {
          last_report = now;
          const double t = mi.getTime().toSec();
          std::fprintf(stderr, "hameritt_export: %s %3.0f%% (bag time %.1f / %.1f s), %zu frames\n",
                       path.c_str(), t1 > t0 ? 100.0 * (t - t0) / (t1 - t0) : 100.0, t - t0,
                       t1 - t0, frames_.size());
        }
      }
    }
  } catch (const rosbag::BagException& e) {
    throw ExitError(kExitBag, path + ": reading the bag failed (" + e.what() +
                                  "); the file may be truncated or corrupt");
  } catch (const ros::Exception& e) {
    throw ExitError(kExitBag, path + ": reading the bag failed (" + e.what() + ")");
  }
  incomplete_ += static_cast<int>(pending.size());
  auto& ctx = contexts_[context];
  if (ctx.scenario_id.empty()) {
    std::fprintf(stderr,
                 "hameritt_export: warning: %s has no /mission message; scenario id and "
                 "relations are empty\n",
                 path.c_str());
  }
  ctx.target_ids.assign(target_ids.begin(), target_ids.end());
  (void)bag_index;
}

void Exporter::dispatch(FrameSet&& set, const std::string& bag) {
  if (!pool_) {
    pool_ = std::make_unique<dataset::EncodePool>(o_.jobs, static_cast<std::size_t>(2 * o_.jobs));
  }
  auto rec = std::make_unique<dataset::FrameRecord>();
  rec->image_id = static_cast<std::int64_t>(frames_.size()) + 1;
  rec->camera = cameras_[set.camera].name;
  rec->stamp_ns = set.stamp_ns;
  rec->context = static_cast<int>(contexts_.size()) - 1;
  // All cameras of one instant of one scenario share a split (no near-duplicate leaks); the key
  // names the scenario (the bag's file name before its /mission), not where the bag lies.
  const std::string& scenario_id = contexts_.back().scenario_id;
  const std::string key = (scenario_id.empty() ? fs::path(bag).filename().string() : scenario_id) +
                          "@" + std::to_string(set.stamp_ns);
  rec->split = dataset::assignSplit(o_.splits, o_.seed, key);
  char name[64];
  std::snprintf(name, sizeof(name), "%06lld_", static_cast<long long>(rec->image_id));
  const std::string stem = name + rec->camera;
  const std::string& s = rec->split;
  rec->image_file = "images/" + s + "/" + stem + (o_.image_format == "jpg" ? ".jpg" : ".png");
  if (cameras_[set.camera].stream_present[1]) rec->depth_file = "depth/" + s + "/" + stem + ".png";
  if (cameras_[set.camera].stream_present[2]) {
    rec->segmentation_file = "segmentation/" + s + "/" + stem + ".png";
  }
  rec->instances_file = "instances/" + s + "/" + stem + ".png";
  if (o_.format == "yolo") rec->label_file = "labels/" + s + "/" + stem + ".txt";
  dataset::FrameRecord* r = rec.get();
  frames_.push_back(std::move(rec));
  auto shared = std::make_shared<FrameSet>(std::move(set));
  const bool queued = pool_->submit([this, shared, r, bag] {
    if (!g_interrupted) encode(*shared, *r, bag);
  });
  if (!queued) {
    try {
      pool_->finish();
    } catch (...) {
      rethrowPoolFailure();
    }
    throw ExitError(1, "internal error: the encoding pool refused a frame without a failure");
  }
}

void Exporter::encode(FrameSet& set, dataset::FrameRecord& rec, const std::string& bag) {
  std::string enc;
  const std::string where =
      bag + ": camera " + rec.camera + " at stamp " + std::to_string(set.stamp_ns) + " ns";
  cv::Mat inst = decode(set.images[kInstances], where + " instances", &enc);
  if (inst.type() != CV_16UC1) {
    throw std::runtime_error(where + ": instances image is " + enc + ", expected 16UC1");
  }
  if (!inst.isContinuous()) inst = inst.clone();
  rec.width = inst.cols;
  rec.height = inst.rows;
  auto check_size = [&](const cv::Mat& m, const char* what) {
    if (m.cols != inst.cols || m.rows != inst.rows) {
      throw std::runtime_error(where + ": " + what + " is " + std::to_string(m.cols) + "x" +
                               std::to_string(m.rows) + ", the instances image " +
                               std::to_string(inst.cols) + "x" + std::to_string(inst.rows));
    }
  };
  int skipped = 0;
  rec.annotations = dataset::annotateFrame(reinterpret_cast<const std::uint16_t*>(inst.data),
                                           inst.cols, inst.rows, set.boxes, &skipped);
  skipped_annotations_ += skipped;
  writeImage(tmp_ / rec.instances_file, inst, png16_params_);
  if (set.images[0].present()) {
    cv::Mat rgb = decode(set.images[0], where + " image_raw", &enc);
    check_size(rgb, "image_raw");
    cv::Mat bgr;
    if (rgb.channels() == 3) {
      if (enc == "bgr8") {
        bgr = rgb;
      } else {
        cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
      }
    } else {
      bgr = rgb;
    }
    writeImage(tmp_ / rec.image_file, bgr, o_.image_format == "jpg" ? jpg_params_ : png_params_);
  }
  if (!rec.depth_file.empty()) {
    cv::Mat d = decode(set.images[1], where + " depth", &enc);
    check_size(d, "depth");
    cv::Mat mm;
    if (d.type() == CV_32FC1) {
      mm.create(d.rows, d.cols, CV_16UC1);
      for (int y = 0; y < d.rows; ++y) {
        const float* src = d.ptr<float>(y);
        std::uint16_t* dst = mm.ptr<std::uint16_t>(y);
        for (int x = 0; x < d.cols; ++x) dst[x] = dataset::depthToMillimetres(src[x]);
      }
    } else if (d.type() == CV_16UC1) {
      mm = d;  // already millimetres
    } else {
      throw std::runtime_error(where + ": depth image is " + enc + ", expected 32FC1 or 16UC1");
    }
    writeImage(tmp_ / rec.depth_file, mm, png16_params_);
  }
  if (!rec.segmentation_file.empty()) {
    cv::Mat seg = decode(set.images[2], where + " segmentation", &enc);
    check_size(seg, "segmentation");
    if (seg.type() != CV_8UC1) {
      throw std::runtime_error(where + ": segmentation image is " + enc + ", expected mono8");
    }
    writeImage(tmp_ / rec.segmentation_file, seg, png_params_);
  }
  if (!rec.label_file.empty()) {
    writeFile(tmp_ / rec.label_file,
              dataset::yoloLabels(rec.annotations, rec.width, rec.height, class_index_));
  }
  // The images' data is no longer needed: free the messages now.
  for (auto& im : set.images) im = ImageInput();
}

void Exporter::finish() {
  if (pool_) {
    try {
      pool_->finish();
    } catch (...) {
      if (g_interrupted) throw ExitError(kExitInterrupted, "interrupted");
      rethrowPoolFailure();
    }
    if (g_interrupted) throw ExitError(kExitInterrupted, "interrupted");
  }
  if (frames_.empty()) {
    throw ExitError(kExitEmpty,
                    "no complete camera frame (every image modality, instances and "
                    "boxes with one stamp) in the bags");
  }
  std::map<std::string, std::vector<const dataset::FrameRecord*>> by_split;
  for (const auto& f : frames_) by_split[f->split].push_back(f.get());
  std::vector<std::string> names;
  for (const auto& s : o_.splits) names.push_back(s.name);
  if (o_.format == "coco") {
    std::int64_t next_id = 1;
    for (const auto& s : names) {
      writeFile(tmp_ / "annotations" / ("instances_" + s + ".json"),
                dataset::cocoJson(by_split[s], categories_, contexts_, s, &next_id));
    }
  } else {
    writeFile(tmp_ / "data.yaml", dataset::yoloDataYaml(names, categories_));
  }
  // Summary on stdout: images, annotations per category, split.
  std::map<std::string, int> per_class;
  std::size_t annotations = 0;
  for (const auto& f : frames_) {
    for (const auto& a : f->annotations) ++per_class[a.meta.entity_class], ++annotations;
  }
  std::printf("hameritt_export: %zu images, %zu annotations (", frames_.size(), annotations);
  bool first = true;
  for (const auto& [c, n] : per_class)
    std::printf("%s%s %d", first ? "" : ", ", c.c_str(), n), first = false;
  std::printf(")\nsplits:");
  for (const auto& s : names) std::printf(" %s %zu", s.c_str(), by_split[s].size());
  std::printf("\n");
  if (incomplete_ > 0 || skipped_annotations_ > 0) {
    std::fprintf(stderr,
                 "hameritt_export: warning: %d incomplete frame sets dropped, %d boxes without "
                 "pixels in their instances image skipped\n",
                 incomplete_, skipped_annotations_.load());
  }
}

// ------------------------------------------------------------------------- preview

int preview(Options o) {
  const fs::path root = o.preview;
  const fs::path ann_dir = root / "annotations";
  if (!fs::is_directory(ann_dir)) {
    throw ExitError(kExitFlags, root.string() + ": not a COCO dataset (no annotations/)");
  }
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(ann_dir)) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  auto load = [](const fs::path& file) {
    try {
      return nlohmann::json::parse(hameritt::scenario::readBoundedJsonFile(file.string(), kMaxAnnotationBytes));
    } catch (const std::exception& e) {
      throw ExitError(kExitFlags, file.string() + ": " + e.what());
    }
  };
  if (o.image_id == 0) {
    std::map<std::int64_t, int> count;
    for (const auto& file : files) {
      const nlohmann::json doc = load(file);
      for (const auto& img : doc.at("images")) count[img.at("id").get<std::int64_t>()] += 0;
      for (const auto& a : doc.at("annotations")) ++count[a.at("image_id").get<std::int64_t>()];
    }
    int best = -1;
    for (const auto& [id, n] : count) {
      if (n > best) best = n, o.image_id = id;
    }
  }
  for (const auto& file : files) {
    const nlohmann::json doc = load(file);
    for (const auto& img : doc.at("images")) {
      if (img.at("id").get<std::int64_t>() != o.image_id) continue;
      const fs::path image_path = root / img.at("file_name").get<std::string>();
      cv::Mat bgr = cv::imread(image_path.string(), cv::IMREAD_COLOR);
      if (bgr.empty()) throw ExitError(kExitFlags, image_path.string() + ": unreadable image");
      std::map<int, std::string> cat;
      for (const auto& c : doc.at("categories")) cat[c.at("id")] = c.at("name");
      cv::Mat overlay = bgr.clone();
      std::vector<std::pair<cv::Rect, std::string>> labels;
      for (const auto& a : doc.at("annotations")) {
        if (a.at("image_id").get<std::int64_t>() != o.image_id) continue;
        const auto& seg = a.at("segmentation");
        const int h = seg.at("size")[0], w = seg.at("size")[1];
        const auto mask = dataset::decodeRuns(
            dataset::countsFromString(seg.at("counts").get<std::string>()), w, h);
        const bool target = a.at("extra").at("is_target").get<bool>();
        const cv::Scalar colour = target                              ? cv::Scalar(0, 0, 255)
                                  : cat[a.at("category_id")] == "car" ? cv::Scalar(255, 160, 0)
                                                                      : cv::Scalar(0, 220, 0);
        for (int y = 0; y < h && y < overlay.rows; ++y) {
          for (int x = 0; x < w && x < overlay.cols; ++x) {
            if (mask[static_cast<std::size_t>(y) * w + x]) {
              overlay.at<cv::Vec3b>(y, x) = cv::Vec3b(colour[0], colour[1], colour[2]);
            }
          }
        }
        const auto& b = a.at("bbox");
        const cv::Rect r(b[0].get<int>(), b[1].get<int>(), b[2].get<int>(), b[3].get<int>());
        char text[128];
        std::snprintf(text, sizeof(text), "%s%s occ %.2f",
                      a.at("extra").at("entity_id").get<std::string>().c_str(),
                      target ? " (target)" : "", a.at("occlusion").get<double>());
        labels.emplace_back(r, text);
      }
      cv::addWeighted(overlay, 0.5, bgr, 0.5, 0.0, bgr);
      for (const auto& [r, text] : labels) {
        cv::rectangle(bgr, r, cv::Scalar(255, 255, 255), 1);
        // Text only on boxes tall enough to read it next to (far instances would hide the rest).
        if (r.height < 12) continue;
        cv::putText(bgr, text, cv::Point(r.x, std::max(10, r.y - 3)), cv::FONT_HERSHEY_SIMPLEX,
                    0.35, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
      }
      const fs::path out = o.out;
      const fs::path tmp = out.string() + ".tmp" + std::to_string(getpid()) + ".png";
      writeImage(tmp, bgr, {cv::IMWRITE_PNG_COMPRESSION, 6});
      fs::rename(tmp, out);
      std::printf("hameritt_export: image %lld (%zu annotations) -> %s\n",
                  static_cast<long long>(o.image_id), labels.size(), out.c_str());
      return 0;
    }
  }
  throw ExitError(kExitFlags, root.string() + ": no image with id " + std::to_string(o.image_id));
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  try {
    o = parseArgs(argc, argv);
  } catch (const ExitError& e) {
    std::fprintf(stderr, "hameritt_export: %s\n%s", e.what(), kUsage);
    return e.code;
  }
  if (!o.preview.empty()) {
    try {
      return preview(o);
    } catch (const ExitError& e) {
      std::fprintf(stderr, "hameritt_export: %s\n", e.what());
      return e.code;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "hameritt_export: %s\n", e.what());
      return kExitFlags;
    }
  }
  const fs::path out = fs::absolute(o.out).lexically_normal();
  const fs::path out_clean = out.has_filename() ? out : out.parent_path();
  if (fs::exists(out_clean) && !o.force) {
    std::fprintf(stderr, "hameritt_export: --out %s exists; pass --force to replace it\n",
                 out_clean.c_str());
    return kExitFlags;
  }
  if (!fs::is_directory(out_clean.parent_path())) {
    std::fprintf(stderr, "hameritt_export: --out %s: the parent directory does not exist\n",
                 out_clean.c_str());
    return kExitFlags;
  }
  const fs::path tmp = out_clean.string() + ".tmp" + std::to_string(getpid());
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  int code = 0;
  try {
    fs::create_directory(tmp);
    {
      Exporter exporter(o, tmp);
      for (std::size_t i = 0; i < o.bags.size(); ++i) exporter.exportBag(i, o.bags[i]);
      exporter.finish();
    }
    if (g_interrupted) throw ExitError(kExitInterrupted, "interrupted");
    // Every file on the disk before the dataset takes its name (a crash leaves the old one or
    // the new one whole); then the name, replacing an older dataset in one step.
    const int dir = ::open(tmp.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    const bool synced = dir >= 0 && ::syncfs(dir) == 0;
    const int sync_err = errno;
    if (dir >= 0) ::close(dir);
    if (!synced) {
      throw ExitError(kExitWrite, tmp.string() + ": sync failed: " + std::strerror(sync_err));
    }
    hameritt::scenario::replaceDirectory(tmp, out_clean);
    return 0;
  } catch (const ExitError& e) {
    std::fprintf(stderr, "hameritt_export: %s\n", e.what());
    code = e.code;
  } catch (const fs::filesystem_error& e) {
    std::fprintf(stderr, "hameritt_export: %s\n", e.what());
    code = kExitWrite;
  } catch (const hameritt::scenario::OutputError& e) {
    std::fprintf(stderr, "hameritt_export: %s\n", e.what());
    code = kExitWrite;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hameritt_export: %s\n", e.what());
    code = kExitBag;
  }
  std::error_code ec;
  fs::remove_all(tmp, ec);
  if (code != kExitInterrupted) {
    std::fprintf(stderr, "hameritt_export: no dataset written (%s removed)\n", tmp.c_str());
  }
  return code;
}
