#pragma once
// sensor_msgs/CompressedImage PNG messages as the standard compressed_image_transport plugin
// ("compressed", format png) writes them, so that its subscriber and any PNG reader decode them:
// format "<encoding>; png compressed bgr8" for colour (the PNG holds BGR-ordered pixels, the
// plugin's convention), "<encoding>; png compressed " for mono8 and 16UC1 (16-bit PNG).

#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>

namespace hameritt::ros_wrappers {

// The PNG of `image` (rgb8, mono8 or 16UC1; tightly packed rows) at zlib `level` (0-9), header
// copied. Throws std::invalid_argument for any other encoding.
sensor_msgs::CompressedImagePtr toPngCompressed(const sensor_msgs::Image& image, int level);

}  // namespace hameritt::ros_wrappers
