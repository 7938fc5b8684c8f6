#include "hameritt/ros/image_compression.h"

#include <sensor_msgs/image_encodings.h>

#include <boost/make_shared.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace hameritt::ros_wrappers {

sensor_msgs::CompressedImagePtr toPngCompressed(const sensor_msgs::Image& image, int level) {
  namespace enc = sensor_msgs::image_encodings;
  auto* data = const_cast<std::uint8_t*>(image.data.data());
  const int h = static_cast<int>(image.height), w = static_cast<int>(image.width);
  auto out = boost::make_shared<sensor_msgs::CompressedImage>();
  out->header = image.header;
  out->format = image.encoding + "; png compressed ";
  const std::vector<int> params = {cv::IMWRITE_PNG_COMPRESSION, level};
  cv::Mat mat;
  if (image.encoding == enc::RGB8) {
    cv::cvtColor(cv::Mat(h, w, CV_8UC3, data, image.step), mat, cv::COLOR_RGB2BGR);
    out->format += "bgr8";
  } else if (image.encoding == enc::MONO8) {
    mat = cv::Mat(h, w, CV_8UC1, data, image.step);
  } else if (image.encoding == enc::TYPE_16UC1 || image.encoding == enc::MONO16) {
    mat = cv::Mat(h, w, CV_16UC1, data, image.step);
  } else {
    throw std::invalid_argument("toPngCompressed: expected rgb8, mono8 or 16UC1, got " +
                                image.encoding);
  }
  if (!cv::imencode(".png", mat, out->data, params)) {
    throw std::runtime_error("toPngCompressed: cv::imencode failed on a " + image.encoding +
                             " image");
  }
  return out;
}

}  // namespace hameritt::ros_wrappers
