// OffscreenTarget: a colour (RGBA8) + depth framebuffer for headless play (a surfaceless context
// has no default framebuffer) and its read-back for screenshots.
#pragma once

#include <cstdint>
#include <vector>

namespace lightpatch::inn {

class OffscreenTarget {
 public:
  OffscreenTarget() = default;
  ~OffscreenTarget();
  OffscreenTarget(const OffscreenTarget&) = delete;
  OffscreenTarget& operator=(const OffscreenTarget&) = delete;

  bool init(int width, int height);
  void bind() const;
  // RGBA8 pixels, top row first (ready for an image file).
  void read(std::vector<uint8_t>* rgba) const;
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  uint32_t framebuffer_ = 0, color_ = 0, depth_ = 0;
  int width_ = 0, height_ = 0;
};

// Writes RGBA8 pixels (top row first) as a PNG file, through a temporary file and a rename.
bool write_png(const char* path, int width, int height, const uint8_t* rgba);

}  // namespace lightpatch::inn
