#pragma once
// A headless OpenGL 4.5 core context over EGL: Mesa's surfaceless platform (llvmpipe on a
// CPU-only machine) or the EGL device platform (a GPU without a display server).

#include <string>

namespace hameritt::render {

class EglContext {
 public:
  // backend: auto | surfaceless | device. auto takes the first EGL device that is not a
  // software renderer (EGL_MESA_device_software) and falls back to surfaceless. Throws
  // RenderError naming the EGL call that failed. The context is current on return.
  explicit EglContext(const std::string& backend);
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  void makeCurrent();
  void releaseCurrent();
  bool isCurrent() const;
  // "surfaceless" or "device"
  const std::string& platform() const { return platform_; }

 private:
  void* display_ = nullptr;
  void* context_ = nullptr;
  void* surface_ = nullptr;  // 1x1 pbuffer, only without EGL_KHR_surfaceless_context
  std::string platform_;
};

}  // namespace hameritt::render
