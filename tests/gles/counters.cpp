// GL object creation counters (support/counters.h): this test binary's definitions of
// glGen*/glCreate* forward to the real ones and count while counting is on.
#include <dlfcn.h>

#include "lightpatch/platform/gl.h"
#include "support/counters.h"

using lightpatch::testing::counters;

namespace {
void count_gl() {
  if (counters().on.load(std::memory_order_relaxed)) counters().gl_creations.fetch_add(1);
}
template <typename F>
F next(const char* name) {
  return reinterpret_cast<F>(dlsym(RTLD_NEXT, name));
}
}  // namespace

// GL object creation.
extern "C" {
#define LP_GEN(name)                                                      \
  GL_APICALL void GL_APIENTRY name(GLsizei n, GLuint* out) {              \
    count_gl();                                                           \
    static auto real = next<void(GL_APIENTRY*)(GLsizei, GLuint*)>(#name); \
    real(n, out);                                                         \
  }
LP_GEN(glGenTextures)
LP_GEN(glGenBuffers)
LP_GEN(glGenFramebuffers)
LP_GEN(glGenRenderbuffers)
LP_GEN(glGenVertexArrays)
LP_GEN(glGenQueries)
LP_GEN(glGenSamplers)
LP_GEN(glGenTransformFeedbacks)
#undef LP_GEN
GL_APICALL GLuint GL_APIENTRY glCreateShader(GLenum type) {
  count_gl();
  static auto real = next<GLuint(GL_APIENTRY*)(GLenum)>("glCreateShader");
  return real(type);
}
GL_APICALL GLuint GL_APIENTRY glCreateProgram() {
  count_gl();
  static auto real = next<GLuint(GL_APIENTRY*)()>("glCreateProgram");
  return real();
}
GL_APICALL GLsync GL_APIENTRY glFenceSync(GLenum condition, GLbitfield flags) {
  count_gl();
  static auto real = next<GLsync(GL_APIENTRY*)(GLenum, GLbitfield)>("glFenceSync");
  return real(condition, flags);
}
}
