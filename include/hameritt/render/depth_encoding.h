#pragma once
// Depth in 16-bit unsigned millimetres (sensor_msgs 16UC1, the ROS depth-camera convention):
// the compact recording's depth, half the size of 32FC1 metres and far more compressible.
// Precision: rounded to the nearest millimetre, so |decoded - rendered| <= 0.5 mm from 1 mm to
// 65.534 m. Range: 0 means no return (nothing hit: sky, beyond the far clip; +inf, NaN or a
// depth <= 0 in metres); 65535 means 65.5345 m or farther (saturated, not "no return").

#include <cstdint>
#include <vector>

namespace hameritt::render {

// The millimetre value of "no return" (sky, nothing hit).
constexpr std::uint16_t kDepthNoReturnMm = 0;
// The millimetre value of every depth from 65.5345 m on (saturated).
constexpr std::uint16_t kDepthSaturatedMm = 65535;

// One depth in metres (+inf: nothing hit) as millimetres per the rules above.
std::uint16_t depthToMillimetres(float metres);

// A whole depth image; `out` is resized to `metres`' size.
void depthToMillimetres(const std::vector<float>& metres, std::vector<std::uint16_t>* out);

}  // namespace hameritt::render
