// EGL contexts for OpenGL ES 3.0: a surfaceless (or 1x1 pbuffer) context for tools and tests,
// and a windowed one (X11 through EGL) for the demo. The one place EGL headers are included is
// egl_context.cpp; this header exposes none of EGL's types.
//
// The platform never changes GL state: creating a context makes it current and touches nothing
// else; swap() only swaps. Errors are returned as false plus a NUL-terminated message (truncated to
// message_size), like FileMapping: the platform sits below the runtime and uses none of its types.
#pragma once

#include <cstdint>

namespace lightpatch::platform {

// A simple input event of the windowed context, for a first-person demo.
struct InputEvent {
  enum Type : uint8_t { kNone, kKeyDown, kKeyUp, kMouseMove, kClose, kResize };
  Type type = kNone;
  // Keys: ASCII for printable keys (lower case), or one of the kKey* codes below.
  uint32_t key = 0;
  int32_t x = 0, y = 0;  // kMouseMove: pointer position in window pixels; kResize: new size
};
constexpr uint32_t kKeyEscape = 27;
constexpr uint32_t kKeyLeft = 0x100, kKeyRight = 0x101, kKeyUp = 0x102, kKeyDown = 0x103;
constexpr uint32_t kKeyShift = 0x104, kKeySpace = ' ';

class EglContext {
 public:
  EglContext() = default;
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  // A GLES 3.0 context with no window: EGL_MESA_platform_surfaceless with
  // EGL_KHR_surfaceless_context where present, else a 1x1 pbuffer on the default display.
  // On success the context is current on the calling thread.
  bool create_headless(char* message, unsigned message_size);

  // A GLES 3.0 context on a new X11 window of width x height pixels titled `title` (needs a
  // build with X11 and a reachable DISPLAY). Current on success.
  bool create_window(int width, int height, const char* title, char* message,
                     unsigned message_size);

  // Destroys the context, surface, window and display connection (safe to call twice). GL
  // objects made in the context are gone afterwards: a runtime must restore() in a new one.
  void destroy();

  bool valid() const { return context_ != nullptr; }
  bool windowed() const { return window_ != 0; }
  bool make_current();

  // Windowed contexts: presents the back buffer. Headless contexts: no-op.
  void swap();
  int width() const { return width_; }
  int height() const { return height_; }

  // Windowed contexts: the next pending input event, or false when none is pending.
  bool poll_event(InputEvent* event);

 private:
  void* display_ = nullptr;    // EGLDisplay
  void* context_ = nullptr;    // EGLContext
  void* surface_ = nullptr;    // EGLSurface, null when surfaceless
  void* x_display_ = nullptr;  // Display*
  unsigned long window_ = 0;   // X11 Window
  unsigned long wm_delete_ = 0;
  int width_ = 0, height_ = 0;
};

}  // namespace lightpatch::platform
