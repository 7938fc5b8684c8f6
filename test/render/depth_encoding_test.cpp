// Depth as 16UC1 millimetres (the compact recording's depth) and the noise-free colour image
// that the camera effects give beside the noisy one.
#include "hameritt/render/depth_encoding.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "camera_effects.h"

namespace hameritt::render {
namespace {

TEST(DepthEncoding, MillimetresRoundToNearestWithinHalfAMillimetre) {
  EXPECT_EQ(depthToMillimetres(1.0f), 1000);
  EXPECT_EQ(depthToMillimetres(0.1f), 100);
  EXPECT_EQ(depthToMillimetres(12.3454f), 12345);
  EXPECT_EQ(depthToMillimetres(12.3456f), 12346);
  EXPECT_EQ(depthToMillimetres(65.534f), 65534);
  // Every float metre value over the range decodes within 0.5 mm (plus float rounding).
  for (double m = 0.001; m < 65.5344; m += 0.000731) {
    const float f = static_cast<float>(m);
    const std::uint16_t mm = depthToMillimetres(f);
    ASSERT_LE(std::abs(mm / 1000.0 - static_cast<double>(f)), 0.0005 + 1e-9) << m;
    ASSERT_NE(mm, kDepthNoReturnMm) << m;
  }
}

TEST(DepthEncoding, NoReturnIsZeroAndFarDepthsSaturate) {
  EXPECT_EQ(depthToMillimetres(std::numeric_limits<float>::infinity()), kDepthNoReturnMm);
  EXPECT_EQ(depthToMillimetres(std::numeric_limits<float>::quiet_NaN()), kDepthNoReturnMm);
  EXPECT_EQ(depthToMillimetres(-std::numeric_limits<float>::infinity()), kDepthNoReturnMm);
  EXPECT_EQ(depthToMillimetres(0.0f), kDepthNoReturnMm);
  EXPECT_EQ(depthToMillimetres(-2.0f), kDepthNoReturnMm);
  // A hit nearer than 0.5 mm is still a hit.
  EXPECT_EQ(depthToMillimetres(0.0001f), 1);
  EXPECT_EQ(depthToMillimetres(65.5344f), 65534);
  EXPECT_EQ(depthToMillimetres(65.5346f), kDepthSaturatedMm);
  EXPECT_EQ(depthToMillimetres(1999.0f), kDepthSaturatedMm);
  EXPECT_EQ(depthToMillimetres(std::numeric_limits<float>::max()), kDepthSaturatedMm);
}

TEST(DepthEncoding, WholeImage) {
  const std::vector<float> metres = {1.5f, std::numeric_limits<float>::infinity(), 70.0f, 0.25f};
  std::vector<std::uint16_t> mm = {9};
  depthToMillimetres(metres, &mm);
  EXPECT_EQ(mm, (std::vector<std::uint16_t>{1500, 0, 65535, 250}));
}

// A test image with structure: gradients and a few edges.
std::vector<std::uint8_t> testImage(int w, int h) {
  std::vector<std::uint8_t> img(static_cast<std::size_t>(3 * w * h));
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int c = 0; c < 3; ++c) {
        img[static_cast<std::size_t>(3 * (y * w + x) + c)] =
            static_cast<std::uint8_t>((x * (c + 1) + y * 2 + ((x / 7 + y / 5) % 2) * 60) % 256);
      }
    }
  }
  return img;
}

TEST(CameraEffectsNoiseFree, EqualsTheEffectsWithoutNoiseByteForByte) {
  const int w = 64, h = 48;
  const auto in = testImage(w, h);
  CameraEffects noisy;
  motionBlurKernel(0.6, 0.8, 3.5, &noisy.blur);
  noisy.noise_std = 0.035f;
  noisy.salt = 0.01f;
  noisy.key[0] = 7;
  noisy.key[1] = 11;
  CameraEffects blur_only = noisy;
  blur_only.noise_std = 0;
  blur_only.salt = 0;
  CameraEffectsScratch scratch;
  std::vector<std::uint8_t> out(in.size()), noise_free(in.size()), expected(in.size()),
      plain(in.size());
  applyCameraEffects(in.data(), w, h, noisy, out.data(), &scratch, 0, -1, noise_free.data());
  applyCameraEffects(in.data(), w, h, blur_only, expected.data(), &scratch);
  applyCameraEffects(in.data(), w, h, noisy, plain.data(), &scratch);
  EXPECT_EQ(noise_free, expected);
  EXPECT_EQ(out, plain);  // the noisy image does not change with the second output
  EXPECT_NE(out, noise_free);
  // The same through the two-thread worker.
  CameraEffectsWorker worker;
  std::vector<std::uint8_t> out2(in.size()), noise_free2(in.size());
  worker.apply(in.data(), w, h, noisy, out2.data(), &scratch, noise_free2.data());
  EXPECT_EQ(out2, plain);
  EXPECT_EQ(noise_free2, expected);
  // Without blur and noise the noise-free image is the input.
  CameraEffects none;
  applyCameraEffects(in.data(), w, h, none, out.data(), &scratch, 0, -1, noise_free.data());
  EXPECT_EQ(noise_free, in);
}

}  // namespace
}  // namespace hameritt::render
