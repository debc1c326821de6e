#include "gl_program.h"

#include <cstdio>

#include "lightpatch/platform/gl.h"

namespace lightpatch::inn {
namespace {

GLuint compile(GLenum type, const char* source, char* message, unsigned message_size) {
  const GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[512] = {};
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    std::snprintf(message, message_size, "%s shader: %s",
                  type == GL_VERTEX_SHADER ? "vertex" : "fragment", log);
    glDeleteShader(shader);
    return 0;
  }
  return shader;
}

}  // namespace

uint32_t build_program(const char* vertex_source, const char* fragment_source,
                       const char* const* attributes, char* message, unsigned message_size) {
  const GLuint vs = compile(GL_VERTEX_SHADER, vertex_source, message, message_size);
  if (!vs) return 0;
  const GLuint fs = compile(GL_FRAGMENT_SHADER, fragment_source, message, message_size);
  if (!fs) {
    glDeleteShader(vs);
    return 0;
  }
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  for (GLuint i = 0; attributes && attributes[i]; ++i)
    glBindAttribLocation(program, i, attributes[i]);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint linked = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &linked);
  if (!linked) {
    char log[512] = {};
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    std::snprintf(message, message_size, "program link: %s", log);
    glDeleteProgram(program);
    return 0;
  }
  return program;
}

}  // namespace lightpatch::inn
