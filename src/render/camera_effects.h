#pragma once
// Camera effects on the read-back colour image: motion blur along a direction and the seeded
// sensor noise (Gaussian and salt-and-pepper). They run on the CPU: on a CPU rasterizer
// (llvmpipe) the same work as a full-screen GLSL pass costs about ten times more (see
// BENCHMARKS.md "Rendering"). Every random value is a counter-based hash of (pixel, key), so
// the result does not depend on threads or on the order of evaluation.

#include <cstdint>
#include <memory>
#include <vector>

namespace hameritt::render {

struct BlurTap {
  int dx = 0, dy = 0;
  int weight = 0;  // fixed point, the taps sum to 256
};

struct CameraEffects {
  std::vector<BlurTap> blur;  // empty or one tap: no blur
  float noise_std = 0;        // fraction of full scale
  float salt = 0;             // probability per pixel
  std::uint32_t key[2] = {0, 0};

  bool any() const { return blur.size() > 1 || noise_std > 0 || salt > 0; }
};

// The blur kernel of a motion of `length_px` along `(dir_x, dir_y)`: the segment centred on
// the pixel sampled at up to 16 points, each rounded to a pixel offset, equal offsets merged.
// `out` is reused (no allocation once it has grown).
void motionBlurKernel(double dir_x, double dir_y, double length_px, std::vector<BlurTap>* out);

// PCG-based 4D hash (Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 2020).
void pcg4d(std::uint32_t v[4]);

// Row buffers reused from frame to frame.
struct CameraEffectsScratch {
  std::vector<std::uint16_t> acc;
  std::vector<std::uint32_t> lanes;
  std::vector<std::int16_t> sums;
};

// Applies `fx` to `in` (RGB8, rows top first) into `out` (same size), rows [row_begin, row_end)
// only (row_end < 0: to the last row); every output pixel depends on its coordinates alone, so
// row ranges can run on different threads. A non-null `noise_free` (same size) also receives
// the image with the blur of `fx` but without its noise: byte for byte what `fx` with
// noise_std = salt = 0 gives (the compact recording's colour image, which compresses).
void applyCameraEffects(const std::uint8_t* in, int width, int height, const CameraEffects& fx,
                        std::uint8_t* out, CameraEffectsScratch* scratch, int row_begin = 0,
                        int row_end = -1, std::uint8_t* noise_free = nullptr);

// A thread that applies camera effects to the first half of an image while the caller does
// the second (two cores are the target machine's). One job at a time.
class CameraEffectsWorker {
 public:
  CameraEffectsWorker();
  ~CameraEffectsWorker();
  CameraEffectsWorker(const CameraEffectsWorker&) = delete;
  CameraEffectsWorker& operator=(const CameraEffectsWorker&) = delete;

  void apply(const std::uint8_t* in, int width, int height, const CameraEffects& fx,
             std::uint8_t* out, CameraEffectsScratch* scratch, std::uint8_t* noise_free = nullptr);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace hameritt::render
