// TextOverlay: lines of text on screen (objective, hints, frame statistics), drawn with the
// built-in stroke font of stb_easy_font (characters made of solid quads: no font file, no
// texture) on a translucent panel. All GL objects and buffers are made in init(); draw() only
// refills the one dynamic vertex buffer.
#pragma once

#include <cstdint>
#include <vector>

namespace lightpatch::inn {

class TextOverlay {
 public:
  TextOverlay() = default;
  ~TextOverlay();
  TextOverlay(const TextOverlay&) = delete;
  TextOverlay& operator=(const TextOverlay&) = delete;

  // `max_chars`: most characters drawn per frame (more are cut off).
  bool init(uint32_t max_chars, char* message, unsigned message_size);
  // Draws `text` ('\n' separates lines; non-printable characters show as '?') with its top-left
  // corner at pixel (x, y) of a viewport of width x height, each font pixel `scale` pixels wide.
  void draw(const char* text, int x, int y, float scale, int width, int height);

 private:
  uint32_t program_ = 0, vao_ = 0, vbo_ = 0, ibo_ = 0;
  int transform_location_ = -1;
  uint32_t max_quads_ = 0;
  std::vector<char> vertices_;  // stb_easy_font's vertex format: x, y, z, rgba8 (16 bytes)
  std::vector<char> text_;
};

}  // namespace lightpatch::inn
