// Environment and camera effects: each is off when its intensity is zero (byte for byte), does
// what it should when on (fog flattens the distance, snow whitens, dusk darkens, foliage density
// scales canopies), and the seeded noise is reproducible and has the configured statistics.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "render_test_util.h"

namespace hameritt::render {
namespace {

using testing::defaultSimConfig;
using testing::defaultWorld;
using testing::lookAt;

// The default scenario with clear weather and no camera noise at noon; `edit` changes it.
scenario::SimConfig config(const std::function<void(scenario::SimConfig*)>& edit = nullptr) {
  scenario::SimConfig c = defaultSimConfig();
  c.environment.time_of_day = 12.0;
  c.environment.rain = c.environment.snow = c.environment.fog = c.environment.dust = 0.0;
  c.environment.foliage = 1.0;
  c.perturbations = scenario::Perturbations{};
  if (edit) edit(&c);
  return c;
}

// A low oblique view over the target's block towards the horizon: the ground from about 20 m
// out to the far clip, houses at all distances, and sky.
RenderRequest obliqueView() {
  RenderRequest r;
  r.intrinsics = intrinsicsFromHfov(320, 240, 90.0);
  const Eigen::Vector3d eye(-250.0, 200.0, 9.0);
  r.world_T_optical = lookAt(eye, eye + Eigen::Vector3d(-30.0, 100.0, -12.0));
  r.time = 60.0;
  return r;
}

double luminance(const FrameSet& f, std::size_t i) {
  return 0.2126 * f.rgb[3 * i] + 0.7152 * f.rgb[3 * i + 1] + 0.0722 * f.rgb[3 * i + 2];
}

double meanLuminance(const FrameSet& f) {
  double s = 0;
  for (std::size_t i = 0; i < f.depth.size(); ++i) s += luminance(f, i);
  return s / static_cast<double>(f.depth.size());
}

double colourDistance(const FrameSet& a, std::size_t i, const double c[3]) {
  return std::abs(a.rgb[3 * i] - c[0]) + std::abs(a.rgb[3 * i + 1] - c[1]) +
         std::abs(a.rgb[3 * i + 2] - c[2]);
}

TEST(RenderEnvironment, ZeroIntensitiesAndEffectsOffGiveTheSameBytes) {
  // The shipped scenario (rain, camera noise) with weather and noise off ...
  Renderer shipped(defaultWorld(), defaultSimConfig());
  RenderRequest off = obliqueView();
  off.weather = false;
  off.noise = false;
  const FrameSet a = shipped.render(off);
  // ... is the same image as the same scenario with every intensity at zero and effects on.
  const scenario::SimConfig zero = config([](scenario::SimConfig* c) {
    c->environment.time_of_day = defaultSimConfig().environment.time_of_day;
    c->environment.foliage = defaultSimConfig().environment.foliage;
  });
  Renderer calm(defaultWorld(), zero);
  RenderRequest on = obliqueView();
  on.frame_index = 3;
  const FrameSet b = calm.render(on);
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_EQ(a.instance, b.instance);
  // And effects on in the shipped scenario change the colour only.
  const FrameSet c = shipped.render(obliqueView());
  EXPECT_NE(a.rgb, c.rgb);
  EXPECT_EQ(std::memcmp(a.depth.data(), c.depth.data(), a.depth.size() * sizeof(float)), 0);
  EXPECT_EQ(a.semantic, c.semantic);
  EXPECT_EQ(a.instance, c.instance);
}

TEST(RenderEnvironment, FogPullsFarPixelsToTheFogColourAndLeavesNearOnesAlmostAlone) {
  Renderer clear(defaultWorld(), config());
  Renderer foggy(defaultWorld(), config([](scenario::SimConfig* c) { c->environment.fog = 0.3; }));
  const FrameSet a = clear.render(obliqueView());
  const FrameSet b = foggy.render(obliqueView());
  // The fog colour: what the sky turns into.
  double fog[3] = {0, 0, 0};
  int sky = 0;
  for (std::size_t i = 0; i < b.depth.size(); ++i) {
    if (!std::isinf(b.depth[i])) continue;
    for (int c = 0; c < 3; ++c) fog[c] += b.rgb[3 * i + c];
    ++sky;
  }
  ASSERT_GT(sky, 100);
  for (double& c : fog) c /= sky;
  double near_change = 0, far_change = 0, far_clear_dist = 0, far_fog_dist = 0;
  int near = 0, far = 0;
  for (std::size_t i = 0; i < a.depth.size(); ++i) {
    const double d = a.depth[i];
    if (d < 25.0) {
      for (int c = 0; c < 3; ++c) near_change += std::abs(a.rgb[3 * i + c] - b.rgb[3 * i + c]);
      ++near;
    } else if (d > 150.0 && std::isfinite(d)) {
      for (int c = 0; c < 3; ++c) far_change += std::abs(a.rgb[3 * i + c] - b.rgb[3 * i + c]);
      far_clear_dist += colourDistance(a, i, fog);
      far_fog_dist += colourDistance(b, i, fog);
      ++far;
    }
  }
  ASSERT_GT(near, 300);
  ASSERT_GT(far, 300);
  near_change /= near;
  far_change /= far;
  EXPECT_LT(far_fog_dist / far, 0.25 * far_clear_dist / far)
      << "far pixels close to the fog colour";
  EXPECT_LT(near_change, 0.5 * far_change) << "near pixels change much less than far ones";
}

TEST(RenderEnvironment, SnowWhitensUpwardSurfaces) {
  Renderer clear(defaultWorld(), config());
  Renderer snowy(defaultWorld(), config([](scenario::SimConfig* c) { c->environment.snow = 1.0; }));
  RenderRequest down = obliqueView();
  down.world_T_optical = lookAt(Eigen::Vector3d(-250, 200, 60), Eigen::Vector3d(-251, 201, 0));
  down.weather = true;
  const FrameSet a = clear.render(down);
  const FrameSet b = snowy.render(down);
  int ground = 0, whiter = 0;
  for (std::size_t i = 0; i < a.depth.size(); ++i) {
    if (a.semantic[i] != kGroundSemantic) continue;
    ++ground;
    const int min_a = std::min({a.rgb[3 * i], a.rgb[3 * i + 1], a.rgb[3 * i + 2]});
    const int min_b = std::min({b.rgb[3 * i], b.rgb[3 * i + 1], b.rgb[3 * i + 2]});
    if (min_b > min_a + 40) ++whiter;
  }
  ASSERT_GT(ground, 1000);
  EXPECT_GT(whiter, ground * 8 / 10) << "lawn and sidewalks under snow";
  EXPECT_GT(meanLuminance(b), meanLuminance(a) + 30.0);
}

TEST(RenderEnvironment, DuskIsDarkerThanNoonAndNightDarkerStill) {
  auto at = [](double hours) {
    Renderer r(defaultWorld(),
               config([hours](scenario::SimConfig* c) { c->environment.time_of_day = hours; }));
    return meanLuminance(r.render(obliqueView()));
  };
  const double noon = at(12.0), dusk = at(18.3), night = at(23.0);
  EXPECT_LT(dusk, 0.7 * noon);
  EXPECT_LT(night, 0.5 * dusk);
  EXPECT_GT(night, 0.0) << "moonlight";
}

TEST(RenderEnvironment, FoliageDensityScalesCanopiesAndZeroLeavesBareTrunks) {
  auto tree_stats = [](double foliage, std::size_t* triangles) {
    Renderer r(defaultWorld(),
               config([foliage](scenario::SimConfig* c) { c->environment.foliage = foliage; }));
    RenderRequest req = obliqueView();
    req.world_T_optical = lookAt(Eigen::Vector3d(-250, 200, 80), Eigen::Vector3d(-250.5, 200.5, 0));
    *triangles = r.sceneTriangles(0).triangle_instance.size();
    const FrameSet f = r.render(req);
    return std::count(f.semantic.begin(), f.semantic.end(),
                      scenario::semanticId(scenario::EntityClass::kTree));
  };
  std::size_t t_full = 0, t_half = 0, t_bare = 0;
  const auto full = tree_stats(1.0, &t_full), half = tree_stats(0.5, &t_half),
             bare = tree_stats(0.0, &t_bare);
  EXPECT_GT(full, 1000);
  EXPECT_LT(half, full * 8 / 10);
  EXPECT_LT(bare, half / 3) << "trunks only";
  EXPECT_EQ(t_full, t_half);
  EXPECT_LT(t_bare, t_full) << "no canopy triangles at density 0";
}

TEST(RenderEnvironment, NoiseIsSeededByScenarioCameraAndFrame) {
  Renderer r(defaultWorld(), config([](scenario::SimConfig* c) {
               c->perturbations.gaussian_noise_std = 0.04;
               c->perturbations.salt_pepper_probability = 0.002;
             }));
  RenderRequest req = obliqueView();
  req.frame_index = 11;
  const FrameSet a = r.render(req);
  const FrameSet b = r.render(req);
  EXPECT_EQ(a.rgb, b.rgb) << "same (seed, camera, frame): same bytes";
  req.frame_index = 12;
  const FrameSet c = r.render(req);
  EXPECT_NE(a.rgb, c.rgb);
  req.frame_index = 11;
  req.camera_index = 1;
  const FrameSet d = r.render(req);
  EXPECT_NE(a.rgb, d.rgb);
  // A different scenario seed, same everything else.
  Renderer other(defaultWorld(), config([](scenario::SimConfig* c) {
                   c->seed += 1;
                   c->perturbations.gaussian_noise_std = 0.04;
                   c->perturbations.salt_pepper_probability = 0.002;
                 }));
  req.camera_index = 0;
  EXPECT_NE(other.render(req).rgb, a.rgb);
}

TEST(RenderEnvironment, NoiseStatisticsMatchTheConfiguredStandardDeviation) {
  const double sigma = 0.05, salt = 0.01;
  Renderer noisy(defaultWorld(), config([&](scenario::SimConfig* c) {
                   c->perturbations.gaussian_noise_std = sigma;
                   c->perturbations.salt_pepper_probability = salt;
                 }));
  RenderRequest req = obliqueView();
  req.noise = false;
  const FrameSet clean = noisy.render(req);
  req.noise = true;
  const FrameSet f = noisy.render(req);
  // Mean absolute deviation of N(0, s) is s sqrt(2 / pi); away from the clipping at 0 and 255.
  double sum = 0, sum2 = 0;
  int n = 0, salted = 0;
  for (std::size_t i = 0; i < f.depth.size(); ++i) {
    const bool extreme =
        (f.rgb[3 * i] == 0 && f.rgb[3 * i + 1] == 0 && f.rgb[3 * i + 2] == 0) ||
        (f.rgb[3 * i] == 255 && f.rgb[3 * i + 1] == 255 && f.rgb[3 * i + 2] == 255);
    if (extreme) {
      ++salted;
      continue;
    }
    for (int c = 0; c < 3; ++c) {
      const int v = clean.rgb[3 * i + c];
      if (v < 40 || v > 215) continue;
      const double d = f.rgb[3 * i + c] - v;
      sum += std::abs(d);
      sum2 += d * d;
      ++n;
    }
  }
  ASSERT_GT(n, 10000);
  const double expected_mad = sigma * 255.0 * std::sqrt(2.0 / M_PI);
  EXPECT_NEAR(sum / n, expected_mad, 0.1 * expected_mad);
  EXPECT_NEAR(std::sqrt(sum2 / n), sigma * 255.0, 0.1 * sigma * 255.0);
  const double pixels = static_cast<double>(f.depth.size());
  EXPECT_NEAR(salted / pixels, salt, 0.3 * salt);
}

TEST(RenderEnvironment, MotionBlurSmoothsAlongItsDirectionOnly) {
  Renderer r(defaultWorld(),
             config([](scenario::SimConfig* c) { c->perturbations.motion_blur_px = 6.0; }));
  RenderRequest req = obliqueView();
  // Straight down with the image axes along the street grid (east right, north up).
  req.world_T_optical = lookAt(Eigen::Vector3d(-250, 200, 60), Eigen::Vector3d(-250, 200.01, 0));
  req.noise = false;
  const FrameSet sharp = r.render(req);
  req.noise = true;
  req.blur_direction = Eigen::Vector2d(1.0, 0.0);
  const FrameSet blurred = r.render(req);
  auto energy = [](const FrameSet& f, double* gx, double* gy) {
    const int w = f.intrinsics.width, h = f.intrinsics.height;
    *gx = *gy = 0;
    for (int y = 1; y < h; ++y) {
      for (int x = 1; x < w; ++x) {
        const std::size_t i = 3 * (static_cast<std::size_t>(y) * w + x);
        const double dx = f.rgb[i + 1] - f.rgb[i + 1 - 3];
        const double dy = f.rgb[i + 1] - f.rgb[i + 1 - 3 * static_cast<std::size_t>(w)];
        *gx += dx * dx;
        *gy += dy * dy;
      }
    }
  };
  double sx, sy, bx, by;
  energy(sharp, &sx, &sy);
  energy(blurred, &bx, &by);
  // Gradient energy: averaging along x spreads each step in x over the blur length (its energy
  // drops by about that factor); steps in y stay sharp.
  EXPECT_LT(bx / sx, 0.5 * (by / sy)) << "horizontal " << bx / sx << ", vertical " << by / sy;
  EXPECT_EQ(sharp.instance, blurred.instance) << "labels are never blurred";
}

TEST(RenderEnvironment, RainAndSnowParticlesAreSeededAndOnlyTouchTheColour) {
  Renderer r(defaultWorld(), config([](scenario::SimConfig* c) {
               c->environment.rain = 0.8;
               c->environment.snow = 0.5;
             }));
  RenderRequest req = obliqueView();
  req.frame_index = 4;
  const FrameSet a = r.render(req);
  const FrameSet b = r.render(req);
  EXPECT_EQ(a.rgb, b.rgb);
  req.frame_index = 5;
  const FrameSet c = r.render(req);
  EXPECT_NE(a.rgb, c.rgb) << "particles move between frames";
  EXPECT_EQ(a.instance, c.instance);
  // Streaks and flakes are small bright marks on the smooth sky: count the sky pixels that
  // stand out from their left and right neighbours.
  req.weather = false;
  const FrameSet clear = r.render(req);
  auto specks = [](const FrameSet& f) {
    int n = 0;
    const int w = f.intrinsics.width;
    for (std::size_t i = 1; i + 1 < f.depth.size(); ++i) {
      if (static_cast<int>(i % w) == 0 || static_cast<int>(i % w) == w - 1) continue;
      if (!std::isinf(f.depth[i - 1]) || !std::isinf(f.depth[i]) || !std::isinf(f.depth[i + 1]))
        continue;
      if (luminance(f, i) > 0.5 * (luminance(f, i - 1) + luminance(f, i + 1)) + 12) ++n;
    }
    return n;
  };
  EXPECT_EQ(specks(clear), 0);
  EXPECT_GT(specks(c), 50);
}

}  // namespace
}  // namespace hameritt::render
