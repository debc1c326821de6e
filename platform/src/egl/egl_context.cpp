// The one place EGL headers are included (see egl_context.h).
#include "lightpatch/platform/egl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstdarg>
#include <cstdio>
#include <cstring>

#if defined(LIGHTPATCH_HAVE_X11)
#include <X11/Xlib.h>
#include <X11/Xutil.h>
#include <X11/keysym.h>
#include <cstdlib>
#endif

namespace lightpatch::platform {
namespace {

bool fail(char* message, unsigned size, const char* format, ...) {
  if (message && size) {
    va_list args;
    va_start(args, format);
    std::vsnprintf(message, size, format, args);
    va_end(args);
  }
  return false;
}

bool has_extension(const char* list, const char* name) {
  if (!list) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  }
  return false;
}

const EGLint kContextAttribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 0,
                                  EGL_NONE};

}  // namespace

EglContext::~EglContext() {
  destroy();
}

bool EglContext::create_headless(char* message, unsigned message_size) {
  destroy();
  EGLDisplay display = EGL_NO_DISPLAY;
  bool surfaceless = false;
  const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (has_extension(client_ext, "EGL_MESA_platform_surfaceless")) {
    auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (get_platform_display) {
      display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    }
  }
  EGLint major = 0, minor = 0;
  if (display != EGL_NO_DISPLAY && !eglInitialize(display, &major, &minor))
    display = EGL_NO_DISPLAY;
  if (display == EGL_NO_DISPLAY) {
    display = eglGetDisplay(EGL_DEFAULT_DISPLAY);
    if (display == EGL_NO_DISPLAY || !eglInitialize(display, &major, &minor)) {
      return fail(message, message_size, "EGL: no display could be initialized (error 0x%x)",
                  eglGetError());
    }
  }
  display_ = display;
  surfaceless =
      has_extension(eglQueryString(display, EGL_EXTENSIONS), "EGL_KHR_surfaceless_context");
  if (!eglBindAPI(EGL_OPENGL_ES_API)) {
    destroy();
    return fail(message, message_size, "EGL: OpenGL ES API not available");
  }
  const EGLint config_attribs[] = {EGL_SURFACE_TYPE, surfaceless ? 0 : EGL_PBUFFER_BIT,
                                   EGL_RENDERABLE_TYPE, EGL_OPENGL_ES3_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  if (!eglChooseConfig(display, config_attribs, &config, 1, &count) || count < 1) {
    destroy();
    return fail(message, message_size, "EGL: no OpenGL ES 3 config (error 0x%x)", eglGetError());
  }
  EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, kContextAttribs);
  if (context == EGL_NO_CONTEXT) {
    destroy();
    return fail(message, message_size, "EGL: cannot create an OpenGL ES 3.0 context (error 0x%x)",
                eglGetError());
  }
  context_ = context;
  if (!surfaceless) {
    const EGLint pbuffer_attribs[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
    EGLSurface surface = eglCreatePbufferSurface(display, config, pbuffer_attribs);
    if (surface == EGL_NO_SURFACE) {
      destroy();
      return fail(message, message_size, "EGL: cannot create a pbuffer (error 0x%x)",
                  eglGetError());
    }
    surface_ = surface;
  }
  width_ = height_ = 1;
  if (!make_current()) {
    destroy();
    return fail(message, message_size, "EGL: eglMakeCurrent failed (error 0x%x)", eglGetError());
  }
  return true;
}

bool EglContext::create_window(int width, int height, const char* title, char* message,
                               unsigned message_size) {
  destroy();
#if defined(LIGHTPATCH_HAVE_X11)
  const char* display_name = std::getenv("DISPLAY");
  if (!display_name || !*display_name) return fail(message, message_size, "no DISPLAY set");
  Display* x = XOpenDisplay(nullptr);
  if (!x) return fail(message, message_size, "cannot open X display '%s'", display_name);
  x_display_ = x;
  const int screen = DefaultScreen(x);
  XSetWindowAttributes attributes{};
  attributes.event_mask =
      KeyPressMask | KeyReleaseMask | PointerMotionMask | StructureNotifyMask | ExposureMask;
  Window window = XCreateWindow(x, RootWindow(x, screen), 0, 0, static_cast<unsigned>(width),
                                static_cast<unsigned>(height), 0, CopyFromParent, InputOutput,
                                CopyFromParent, CWEventMask, &attributes);
  window_ = window;
  XStoreName(x, window, title ? title : "lightpatch");
  Atom wm_delete = XInternAtom(x, "WM_DELETE_WINDOW", False);
  XSetWMProtocols(x, window, &wm_delete, 1);
  wm_delete_ = wm_delete;
  XMapWindow(x, window);
  XFlush(x);

  EGLDisplay display = eglGetDisplay(reinterpret_cast<EGLNativeDisplayType>(x));
  EGLint major = 0, minor = 0;
  if (display == EGL_NO_DISPLAY || !eglInitialize(display, &major, &minor)) {
    destroy();
    return fail(message, message_size, "EGL: cannot initialize the X11 display");
  }
  display_ = display;
  eglBindAPI(EGL_OPENGL_ES_API);
  const EGLint config_attribs[] = {EGL_SURFACE_TYPE,
                                   EGL_WINDOW_BIT,
                                   EGL_RENDERABLE_TYPE,
                                   EGL_OPENGL_ES3_BIT,
                                   EGL_RED_SIZE,
                                   8,
                                   EGL_GREEN_SIZE,
                                   8,
                                   EGL_BLUE_SIZE,
                                   8,
                                   EGL_DEPTH_SIZE,
                                   24,
                                   EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  if (!eglChooseConfig(display, config_attribs, &config, 1, &count) || count < 1) {
    destroy();
    return fail(message, message_size, "EGL: no OpenGL ES 3 window config");
  }
  EGLSurface surface =
      eglCreateWindowSurface(display, config, static_cast<EGLNativeWindowType>(window), nullptr);
  if (surface == EGL_NO_SURFACE) {
    destroy();
    return fail(message, message_size, "EGL: cannot create a window surface (error 0x%x)",
                eglGetError());
  }
  surface_ = surface;
  EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, kContextAttribs);
  if (context == EGL_NO_CONTEXT) {
    destroy();
    return fail(message, message_size, "EGL: cannot create an OpenGL ES 3.0 context");
  }
  context_ = context;
  width_ = width;
  height_ = height;
  if (!make_current()) {
    destroy();
    return fail(message, message_size, "EGL: eglMakeCurrent failed (error 0x%x)", eglGetError());
  }
  return true;
#else
  (void)width;
  (void)height;
  (void)title;
  return fail(message, message_size, "this build has no X11 support (windowed contexts)");
#endif
}

void EglContext::destroy() {
  if (display_) {
    EGLDisplay display = static_cast<EGLDisplay>(display_);
    eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (context_) eglDestroyContext(display, static_cast<EGLContext>(context_));
    if (surface_) eglDestroySurface(display, static_cast<EGLSurface>(surface_));
    eglTerminate(display);
  }
  display_ = context_ = surface_ = nullptr;
#if defined(LIGHTPATCH_HAVE_X11)
  if (x_display_) {
    Display* x = static_cast<Display*>(x_display_);
    if (window_) XDestroyWindow(x, static_cast<Window>(window_));
    XCloseDisplay(x);
  }
#endif
  x_display_ = nullptr;
  window_ = 0;
  width_ = height_ = 0;
}

bool EglContext::make_current() {
  if (!context_) return false;
  EGLSurface surface = surface_ ? static_cast<EGLSurface>(surface_) : EGL_NO_SURFACE;
  return eglMakeCurrent(static_cast<EGLDisplay>(display_), surface, surface,
                        static_cast<EGLContext>(context_)) == EGL_TRUE;
}

void EglContext::swap() {
  if (window_ && surface_) {
    eglSwapBuffers(static_cast<EGLDisplay>(display_), static_cast<EGLSurface>(surface_));
  }
}

bool EglContext::poll_event(InputEvent* event) {
  *event = InputEvent{};
#if defined(LIGHTPATCH_HAVE_X11)
  if (!x_display_) return false;
  Display* x = static_cast<Display*>(x_display_);
  while (XPending(x) > 0) {
    XEvent e;
    XNextEvent(x, &e);
    switch (e.type) {
      case KeyPress:
      case KeyRelease: {
        const KeySym sym = XLookupKeysym(&e.xkey, 0);
        uint32_t key = 0;
        switch (sym) {
          case XK_Escape:
            key = kKeyEscape;
            break;
          case XK_Left:
            key = kKeyLeft;
            break;
          case XK_Right:
            key = kKeyRight;
            break;
          case XK_Up:
            key = kKeyUp;
            break;
          case XK_Down:
            key = kKeyDown;
            break;
          case XK_Shift_L:
          case XK_Shift_R:
            key = kKeyShift;
            break;
          default:
            if (sym >= 0x20 && sym < 0x7f) key = static_cast<uint32_t>(sym);
        }
        if (!key) continue;
        // X repeats keys as release+press pairs; drop the release of an auto-repeat.
        if (e.type == KeyRelease && XEventsQueued(x, QueuedAfterReading)) {
          XEvent next;
          XPeekEvent(x, &next);
          if (next.type == KeyPress && next.xkey.time == e.xkey.time &&
              next.xkey.keycode == e.xkey.keycode) {
            continue;
          }
        }
        event->type = e.type == KeyPress ? InputEvent::kKeyDown : InputEvent::kKeyUp;
        event->key = key;
        return true;
      }
      case MotionNotify:
        event->type = InputEvent::kMouseMove;
        event->x = e.xmotion.x;
        event->y = e.xmotion.y;
        return true;
      case ConfigureNotify:
        if (e.xconfigure.width == width_ && e.xconfigure.height == height_) continue;
        width_ = e.xconfigure.width;
        height_ = e.xconfigure.height;
        event->type = InputEvent::kResize;
        event->x = width_;
        event->y = height_;
        return true;
      case ClientMessage:
        if (static_cast<unsigned long>(e.xclient.data.l[0]) != wm_delete_) continue;
        event->type = InputEvent::kClose;
        return true;
      default:
        continue;
    }
  }
#endif
  return false;
}

}  // namespace lightpatch::platform
