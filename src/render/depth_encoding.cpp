#include "hameritt/render/depth_encoding.h"

#include <algorithm>
#include <cmath>

namespace hameritt::render {

std::uint16_t depthToMillimetres(float metres) {
  if (!std::isfinite(metres) || !(metres > 0.0f)) return kDepthNoReturnMm;
  // In double: 65534.5 mm and the rounding of every metre value below it are exact.
  const double mm = std::round(static_cast<double>(metres) * 1000.0);
  if (mm >= kDepthSaturatedMm) return kDepthSaturatedMm;
  // A hit nearer than 0.5 mm still is a hit: 1, never "no return".
  return static_cast<std::uint16_t>(std::max(1.0, mm));
}

void depthToMillimetres(const std::vector<float>& metres, std::vector<std::uint16_t>* out) {
  out->resize(metres.size());
  std::uint16_t* dst = out->data();
  for (std::size_t i = 0; i < metres.size(); ++i) dst[i] = depthToMillimetres(metres[i]);
}

}  // namespace hameritt::render
