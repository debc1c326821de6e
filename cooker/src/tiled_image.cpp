// TiledImage (maps.h): a float image without its all-zero tiles.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/maps.h"

namespace lightpatch::cooker {
namespace {

int tiles_along(int side) {
  return (side + TiledImage::kSide - 1) / TiledImage::kSide;
}

}  // namespace

TiledImage::TiledImage(const FloatImage& image) {
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0) return;
  if (image.data.size() != size_t(image.width) * size_t(image.height) * size_t(image.channels))
    throw CookError("a tiled image made from an image whose data does not match its size");
  width_ = image.width;
  height_ = image.height;
  channels_ = image.channels;
  tiles_x_ = tiles_along(width_);
  const int tiles_y = tiles_along(height_);
  slot_.assign(size_t(tiles_x_) * size_t(tiles_y), kNoTile);
  const size_t tile_floats = size_t(kSide) * kSide * size_t(channels_);
  const size_t row_floats = size_t(width_) * size_t(channels_);
  for (int ty = 0; ty < tiles_y; ++ty) {
    for (int tx = 0; tx < tiles_x_; ++tx) {
      const int x0 = tx * kSide, y0 = ty * kSide;
      const int w = std::min(kSide, width_ - x0), h = std::min(kSide, height_ - y0);
      const size_t run = size_t(w) * size_t(channels_);
      bool any = false;
      for (int y = y0; y < y0 + h && !any; ++y) {
        const float* row = &image.data[size_t(y) * row_floats + size_t(x0) * size_t(channels_)];
        for (size_t k = 0; k < run && !any; ++k) {
          uint32_t bits;
          std::memcpy(&bits, &row[k], sizeof bits);
          any = bits != 0;
        }
      }
      if (!any) continue;
      slot_[size_t(ty) * size_t(tiles_x_) + size_t(tx)] = uint32_t(data_.size() / tile_floats);
      const size_t first = data_.size();
      data_.resize(first + tile_floats, 0.0f);
      for (int y = 0; y < h; ++y)
        std::memcpy(&data_[first + size_t(y) * size_t(kSide) * size_t(channels_)],
                    &image.data[size_t(y0 + y) * row_floats + size_t(x0) * size_t(channels_)],
                    run * sizeof(float));
    }
  }
  data_.shrink_to_fit();
}

FloatImage TiledImage::dense() const {
  if (empty()) return FloatImage{};
  FloatImage out(width_, height_, channels_);
  const size_t tile_floats = size_t(kSide) * kSide * size_t(channels_);
  const size_t row_floats = size_t(width_) * size_t(channels_);
  for (size_t i = 0; i < slot_.size(); ++i) {
    if (slot_[i] == kNoTile) continue;
    const int x0 = int(i % size_t(tiles_x_)) * kSide, y0 = int(i / size_t(tiles_x_)) * kSide;
    const int w = std::min(kSide, width_ - x0), h = std::min(kSide, height_ - y0);
    const float* tile = &data_[size_t(slot_[i]) * tile_floats];
    for (int y = 0; y < h; ++y)
      std::memcpy(&out.data[size_t(y0 + y) * row_floats + size_t(x0) * size_t(channels_)],
                  &tile[size_t(y) * size_t(kSide) * size_t(channels_)],
                  size_t(w) * size_t(channels_) * sizeof(float));
  }
  return out;
}

float TiledImage::peak() const {
  float peak = 0.0f;
  for (float v : data_)
    if (std::isfinite(v)) peak = std::max(peak, v);
  return peak;
}

const float* TiledImage::texel(int x, int y) const {
  const uint32_t s = slot_[size_t(y / kSide) * size_t(tiles_x_) + size_t(x / kSide)];
  if (s == kNoTile) return nullptr;
  const size_t tile_floats = size_t(kSide) * kSide * size_t(channels_);
  return &data_[size_t(s) * tile_floats +
                (size_t(y % kSide) * size_t(kSide) + size_t(x % kSide)) * size_t(channels_)];
}

}  // namespace lightpatch::cooker
