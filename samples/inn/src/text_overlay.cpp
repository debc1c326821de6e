#include "text_overlay.h"

#include <algorithm>
#include <cstring>

// stb_easy_font is a header of static functions, some of which this file does not call.
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#endif
#include <stb/stb_easy_font.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

#include "gl_program.h"
#include "lightpatch/platform/gl.h"

namespace lightpatch::inn {
namespace {

constexpr uint32_t kVertexBytes = 16;

const char* const kVertexShader = R"(#version 300 es
uniform vec4 u_transform;  // pixel -> clip: scale.xy, offset.xy
in vec2 a_position;
in vec4 a_color;
out vec4 v_color;
void main() {
  gl_Position = vec4(a_position * u_transform.xy + u_transform.zw, 0.0, 1.0);
  v_color = a_color;
}
)";

const char* const kFragmentShader = R"(#version 300 es
precision mediump float;
in vec4 v_color;
out vec4 o_color;
void main() { o_color = v_color; }
)";

// One quad in stb_easy_font's vertex format.
void put_quad(char* out, float x0, float y0, float x1, float y1, const unsigned char rgba[4]) {
  const float corners[4][2] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  for (int i = 0; i < 4; ++i) {
    const float xyz[3] = {corners[i][0], corners[i][1], 0.0f};
    std::memcpy(out + i * kVertexBytes, xyz, sizeof xyz);
    std::memcpy(out + i * kVertexBytes + 12, rgba, 4);
  }
}

}  // namespace

TextOverlay::~TextOverlay() {
  if (program_) glDeleteProgram(program_);
  if (vao_) glDeleteVertexArrays(1, &vao_);
  if (vbo_) glDeleteBuffers(1, &vbo_);
  if (ibo_) glDeleteBuffers(1, &ibo_);
}

bool TextOverlay::init(uint32_t max_chars, char* message, unsigned message_size) {
  const char* const attributes[] = {"a_position", "a_color", nullptr};
  program_ = build_program(kVertexShader, kFragmentShader, attributes, message, message_size);
  if (!program_) return false;
  transform_location_ = glGetUniformLocation(program_, "u_transform");
  // stb_easy_font needs at most ~9 quads per character; one more quad for the panel. 16-bit
  // indices address 16384 quads.
  max_quads_ = std::min<uint32_t>(max_chars * 9 + 1, 16383);
  vertices_.assign(static_cast<size_t>(max_quads_) * 4 * kVertexBytes, 0);
  text_.assign(static_cast<size_t>(max_chars) + 1, 0);
  std::vector<uint16_t> indices(static_cast<size_t>(max_quads_) * 6);
  for (uint32_t q = 0; q < max_quads_; ++q) {
    const uint16_t b = static_cast<uint16_t>(q * 4);
    const uint16_t quad[6] = {b, static_cast<uint16_t>(b + 1), static_cast<uint16_t>(b + 2),
                              b, static_cast<uint16_t>(b + 2), static_cast<uint16_t>(b + 3)};
    std::memcpy(&indices[static_cast<size_t>(q) * 6], quad, sizeof quad);
  }
  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &vbo_);
  glGenBuffers(1, &ibo_);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices_.size()), nullptr,
               GL_DYNAMIC_DRAW);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo_);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(uint16_t)),
               indices.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, kVertexBytes, nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 4, GL_UNSIGNED_BYTE, GL_TRUE, kVertexBytes,
                        reinterpret_cast<const void*>(12));
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  stb_easy_font_spacing(0.0f);
  return glGetError() == GL_NO_ERROR;
}

void TextOverlay::draw(const char* text, int x, int y, float scale, int width, int height) {
  // Printable ASCII only: stb_easy_font indexes its glyph table by character - 32.
  size_t n = 0;
  for (; text[n] && n + 1 < text_.size(); ++n) {
    const unsigned char c = static_cast<unsigned char>(text[n]);
    text_[n] = c == '\n' || (c >= 32 && c < 127) ? static_cast<char>(c) : '?';
  }
  text_[n] = 0;
  if (n == 0) return;
  // Word wrap in place: a space becomes a line break where the line would leave the viewport.
  const int max_width = static_cast<int>(static_cast<float>(width - x - 8) / scale);
  size_t line_start = 0, last_space = n;
  for (size_t i = 0; i <= n; ++i) {
    if (i < n && text_[i] == '\n') {
      line_start = i + 1;
      last_space = n;
      continue;
    }
    if (i < n && text_[i] != ' ') continue;
    const char saved = text_[i];
    text_[i] = 0;
    const int line_width = stb_easy_font_width(&text_[line_start]);
    text_[i] = saved;
    if (line_width > max_width && last_space < i) {
      text_[last_space] = '\n';
      line_start = last_space + 1;
    }
    last_space = i;
  }
  int lines = 1;
  for (size_t i = 0; i < n; ++i) lines += text_[i] == '\n';
  const float w = static_cast<float>(stb_easy_font_width(text_.data()));
  const float h = 12.0f * static_cast<float>(lines);
  const unsigned char panel[4] = {0, 0, 0, 150};
  put_quad(vertices_.data(), -4.0f, -4.0f, w + 4.0f, h + 1.0f, panel);
  unsigned char white[4] = {235, 225, 200, 255};
  const int room = static_cast<int>(vertices_.size()) - static_cast<int>(4 * kVertexBytes);
  const int quads = 1 + stb_easy_font_print(0.0f, 0.0f, text_.data(), white,
                                            vertices_.data() + 4 * kVertexBytes, room);

  glViewport(0, 0, width, height);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glUseProgram(program_);
  // Font pixels -> clip space, origin at the text's top-left corner, y down.
  const float sx = 2.0f * scale / static_cast<float>(width),
              sy = -2.0f * scale / static_cast<float>(height);
  glUniform4f(transform_location_, sx, sy,
              -1.0f + 2.0f * static_cast<float>(x) / static_cast<float>(width),
              1.0f - 2.0f * static_cast<float>(y) / static_cast<float>(height));
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(quads) * 4 * kVertexBytes,
                  vertices_.data());
  glDrawElements(GL_TRIANGLES, quads * 6, GL_UNSIGNED_SHORT, nullptr);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_BLEND);
}

}  // namespace lightpatch::inn
