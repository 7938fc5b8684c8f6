#include "camera_effects.h"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <thread>

namespace hameritt::render {

namespace {

constexpr int kMaxBlurSamples = 16;

// Blurred row y into acc (value * 256 per channel).
inline void blurRow(const std::uint8_t* in, int width, int height, int y,
                    const std::vector<BlurTap>& taps, std::uint16_t* acc) {
  const int n = 3 * width;
  std::fill(acc, acc + n, 0);
  for (const BlurTap& t : taps) {
    const int sy = std::clamp(y + t.dy, 0, height - 1);
    const std::uint8_t* src = in + static_cast<std::size_t>(sy) * static_cast<std::size_t>(n);
    const auto w = static_cast<std::uint16_t>(t.weight);
    // Interior: x + dx inside the row, one contiguous (vectorizable) loop; edges clamp.
    const int x0 = std::clamp(-t.dx, 0, width), x1 = std::clamp(width - t.dx, x0, width);
    for (int x = 0; x < x0; ++x) {
      for (int c = 0; c < 3; ++c)
        acc[3 * x + c] = static_cast<std::uint16_t>(acc[3 * x + c] + w * src[c]);
    }
    const std::uint8_t* shifted = src + 3 * t.dx;
    for (int i = 3 * x0; i < 3 * x1; ++i)
      acc[i] = static_cast<std::uint16_t>(acc[i] + w * shifted[i]);
    const std::uint8_t* last = src + 3 * (width - 1);
    for (int x = x1; x < width; ++x) {
      for (int c = 0; c < 3; ++c)
        acc[3 * x + c] = static_cast<std::uint16_t>(acc[3 * x + c] + w * last[c]);
    }
  }
}

}  // namespace

void pcg4d(std::uint32_t v[4]) {
  for (int i = 0; i < 4; ++i) v[i] = v[i] * 1664525u + 1013904223u;
  v[0] += v[1] * v[3];
  v[1] += v[2] * v[0];
  v[2] += v[0] * v[1];
  v[3] += v[1] * v[2];
  for (int i = 0; i < 4; ++i) v[i] ^= v[i] >> 16;
  v[0] += v[1] * v[3];
  v[1] += v[2] * v[0];
  v[2] += v[0] * v[1];
  v[3] += v[1] * v[2];
}

void motionBlurKernel(double dir_x, double dir_y, double length_px, std::vector<BlurTap>* out) {
  std::vector<BlurTap>& taps = *out;
  taps.clear();
  const double norm = std::hypot(dir_x, dir_y);
  if (!(length_px > 0.0) || !(norm > 0.0)) return;
  const double bx = dir_x / norm * length_px, by = dir_y / norm * length_px;
  const int samples =
      std::min(kMaxBlurSamples, std::max(2, static_cast<int>(std::ceil(2.0 * length_px)) + 1));
  int count[kMaxBlurSamples] = {};
  for (int k = 0; k < samples; ++k) {
    const double s = static_cast<double>(k) / (samples - 1) - 0.5;
    const int dx = static_cast<int>(std::lround(bx * s)),
              dy = static_cast<int>(std::lround(by * s));
    std::size_t j = 0;
    while (j < taps.size() && (taps[j].dx != dx || taps[j].dy != dy)) ++j;
    if (j == taps.size()) taps.push_back({dx, dy, 0});
    ++count[j];
  }
  // Fixed-point weights that sum to exactly 256 (the remainder goes to the heaviest tap).
  int total = 0;
  std::size_t heaviest = 0;
  for (std::size_t j = 0; j < taps.size(); ++j) {
    taps[j].weight = (256 * count[j]) / samples;
    total += taps[j].weight;
    if (count[j] > count[heaviest]) heaviest = j;
  }
  taps[heaviest].weight += 256 - total;
  if (taps.size() == 1) taps.clear();  // shorter than half a pixel: nothing moves
}

// The loops are written to vectorize; on x86-64 an AVX2 clone is picked at load time when the
// CPU has it (32-bit multiplies for the hash lanes).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void applyCameraEffects(const std::uint8_t* in, int width, int height, const CameraEffects& fx,
                        std::uint8_t* out, CameraEffectsScratch* scratch, int row_begin,
                        int row_end, std::uint8_t* noise_free) {
  const bool blur = fx.blur.size() > 1;
  const int n = 3 * width;
  scratch->acc.resize(static_cast<std::size_t>(n));
  std::uint16_t* acc = scratch->acc.data();
  const float noise_scale = fx.noise_std * 255.0f / 147.80f;
  const auto salt_threshold =
      static_cast<std::uint32_t>(std::clamp(static_cast<double>(fx.salt), 0.0, 1.0) * 16777216.0);
  const bool noisy = fx.noise_std > 0 || salt_threshold > 0;
  // Per-row hash lanes (structure of arrays, so that the loops vectorize).
  scratch->lanes.resize(noisy ? 4 * static_cast<std::size_t>(width) : 0);
  // Without noise the lanes are empty (data() may be null): no offset is applied to them then.
  std::uint32_t* h0 = noisy ? scratch->lanes.data() : nullptr;
  std::uint32_t* h1 = noisy ? h0 + width : nullptr;
  std::uint32_t* h2 = noisy ? h1 + width : nullptr;
  std::uint32_t* h3 = noisy ? h2 + width : nullptr;
  scratch->sums.resize(noisy ? static_cast<std::size_t>(n) : 0);
  std::int16_t* sums = scratch->sums.data();
  if (row_end < 0) row_end = height;
  for (int y = row_begin; y < row_end; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * static_cast<std::size_t>(n);
    if (blur) {
      blurRow(in, width, height, y, fx.blur, acc);
    } else {
      for (int i = 0; i < n; ++i)
        acc[i] = static_cast<std::uint16_t>(in[row + static_cast<std::size_t>(i)] << 8);
    }
    std::uint8_t* dst = out + row;
    if (noise_free != nullptr) {
      std::uint8_t* clean = noise_free + row;
      for (int i = 0; i < n; ++i) clean[i] = static_cast<std::uint8_t>((acc[i] + 128) >> 8);
    }
    if (!noisy) {
      for (int i = 0; i < n; ++i) dst[i] = static_cast<std::uint8_t>((acc[i] + 128) >> 8);
      continue;
    }
    // pcg4d of (x, y, key) for the whole row, lane by lane.
    for (int x = 0; x < width; ++x) {
      std::uint32_t v0 = static_cast<std::uint32_t>(x) * 1664525u + 1013904223u;
      std::uint32_t v1 = static_cast<std::uint32_t>(y) * 1664525u + 1013904223u;
      std::uint32_t v2 = fx.key[0] * 1664525u + 1013904223u;
      std::uint32_t v3 = fx.key[1] * 1664525u + 1013904223u;
      v0 += v1 * v3;
      v1 += v2 * v0;
      v2 += v0 * v1;
      v3 += v1 * v2;
      v0 ^= v0 >> 16;
      v1 ^= v1 >> 16;
      v2 ^= v2 >> 16;
      v3 ^= v3 >> 16;
      v0 += v1 * v3;
      v1 += v2 * v0;
      v2 += v0 * v1;
      v3 += v1 * v2;
      h0[x] = v0;
      h1[x] = v1;
      h2[x] = v2;
      h3[x] = v3;
    }
    // Gaussian noise: per channel the Irwin-Hall sum of the four bytes of one hash lane
    // (mean 510, standard deviation 147.80), scaled to noise_std of full scale.
    auto byte_sum = [](std::uint32_t v) {
      return static_cast<std::int16_t>(
          static_cast<int>((v & 255u) + ((v >> 8) & 255u) + ((v >> 16) & 255u) + (v >> 24)) - 510);
    };
    for (int x = 0; x < width; ++x) {
      sums[3 * x] = byte_sum(h0[x]);
      sums[3 * x + 1] = byte_sum(h1[x]);
      sums[3 * x + 2] = byte_sum(h2[x]);
    }
    for (int i = 0; i < n; ++i) {
      float value = static_cast<float>(acc[i]) * (1.0f / 256.0f) +
                    noise_scale * static_cast<float>(sums[i]) + 0.5f;
      value = std::min(std::max(value, 0.0f), 255.0f);
      dst[i] = static_cast<std::uint8_t>(value);
    }
    if (salt_threshold > 0) {
      for (int x = 0; x < width; ++x) {
        if ((h3[x] >> 8) < salt_threshold) {
          const std::uint8_t v = (h3[x] & 1u) ? 255 : 0;
          dst[3 * x] = dst[3 * x + 1] = dst[3 * x + 2] = v;
        }
      }
    }
  }
}

struct CameraEffectsWorker::State {
  std::mutex mutex;
  std::condition_variable cv;
  bool busy = false, stop = false;
  // The job: rows [0, rows) of the image.
  const std::uint8_t* in = nullptr;
  std::uint8_t* out = nullptr;
  std::uint8_t* noise_free = nullptr;
  int width = 0, height = 0, rows = 0;
  const CameraEffects* fx = nullptr;
  CameraEffectsScratch scratch;
  std::thread thread;
};

CameraEffectsWorker::CameraEffectsWorker() : state_(std::make_unique<State>()) {
  State* s = state_.get();
  s->thread = std::thread([s] {
    std::unique_lock<std::mutex> lock(s->mutex);
    while (true) {
      s->cv.wait(lock, [s] { return s->busy || s->stop; });
      if (s->stop) return;
      lock.unlock();
      applyCameraEffects(s->in, s->width, s->height, *s->fx, s->out, &s->scratch, 0, s->rows,
                         s->noise_free);
      lock.lock();
      s->busy = false;
      s->cv.notify_all();
    }
  });
}

CameraEffectsWorker::~CameraEffectsWorker() {
  {
    std::lock_guard<std::mutex> lock(state_->mutex);
    state_->stop = true;
  }
  state_->cv.notify_all();
  state_->thread.join();
}

void CameraEffectsWorker::apply(const std::uint8_t* in, int width, int height,
                                const CameraEffects& fx, std::uint8_t* out,
                                CameraEffectsScratch* scratch, std::uint8_t* noise_free) {
  State* s = state_.get();
  const int half = height / 2;
  {
    std::lock_guard<std::mutex> lock(s->mutex);
    s->in = in;
    s->out = out;
    s->noise_free = noise_free;
    s->width = width;
    s->height = height;
    s->rows = half;
    s->fx = &fx;
    s->busy = true;
  }
  s->cv.notify_all();
  applyCameraEffects(in, width, height, fx, out, scratch, half, height, noise_free);
  std::unique_lock<std::mutex> lock(s->mutex);
  s->cv.wait(lock, [s] { return !s->busy; });
}

}  // namespace hameritt::render
