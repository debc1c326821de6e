#include "atlas_packer.h"

#include <algorithm>
#include <numeric>

#include "lightpatch/cooker/error.h"

namespace lightpatch::cooker {

namespace {

// Skyline of one channel: segments [x, x+w) whose free space starts at row y (rows grow down).
class Skyline {
 public:
  struct Segment {
    int x, y, w;
  };
  explicit Skyline(int width) { segs_.push_back({0, 0, width}); }

  // Highest occupied row over [x, x+w) (the lowest y at which a rect of width w may start).
  int level(int x, int w) const {
    int y = 0;
    for (const Segment& s : segs_) {
      if (s.x + s.w <= x || s.x >= x + w) continue;
      y = std::max(y, s.y);
    }
    return y;
  }
  const std::vector<Segment>& segments() const { return segs_; }

  void place(int x, int y_top, int w) {  // the rect occupies columns [x, x+w) down to row y_top
    std::vector<Segment> next;
    for (const Segment& s : segs_) {
      if (s.x + s.w <= x || s.x >= x + w) {
        next.push_back(s);
        continue;
      }
      if (s.x < x) next.push_back({s.x, s.y, x - s.x});
      if (s.x + s.w > x + w) next.push_back({x + w, s.y, s.x + s.w - (x + w)});
    }
    next.push_back({x, y_top, w});
    std::sort(next.begin(), next.end(),
              [](const Segment& a, const Segment& b) { return a.x < b.x; });
    segs_.clear();
    for (const Segment& s : next) {
      if (!segs_.empty() && segs_.back().y == s.y)
        segs_.back().w += s.w;
      else
        segs_.push_back(s);
    }
  }

  void widen(int old_width, int new_width) { place(old_width, 0, new_width - old_width); }

 private:
  std::vector<Segment> segs_;
};

struct Atlas {
  int size = 0;
  std::vector<Skyline> channels;
  bool empty = true;
  explicit Atlas(int s) : size(s), channels(4, Skyline(s)) {}

  // Best (lowest, then leftmost) position for a w x h rect over channels [c, c+n); false if none.
  bool find(int c, int n, int w, int h, int* out_x, int* out_y) const {
    int best_x = -1, best_y = size + 1;
    for (int k = c; k < c + n; ++k) {
      for (const Skyline::Segment& s : channels[size_t(k)].segments()) {
        const int x = s.x;
        if (x + w > size) continue;
        int y = 0;
        for (int j = c; j < c + n; ++j) y = std::max(y, channels[size_t(j)].level(x, w));
        if (y + h > size) continue;
        if (y < best_y || (y == best_y && x < best_x)) {
          best_x = x;
          best_y = y;
        }
      }
    }
    if (best_x < 0) return false;
    *out_x = best_x;
    *out_y = best_y;
    return true;
  }
  void place(int c, int n, int x, int y, int w, int h) {
    for (int k = c; k < c + n; ++k) channels[size_t(k)].place(x, y + h, w);
    empty = false;
  }
  void grow() {
    for (Skyline& s : channels) s.widen(size, size * 2);
    size *= 2;
  }
};

int pow2_at_least(int v) {
  int p = 1;
  while (p < v) p *= 2;
  return p;
}

}  // namespace

AtlasLayout pack_atlases(const std::vector<PackItem>& items, int max_size) {
  AtlasLayout out;
  out.placements.resize(items.size());
  if (max_size < kMinAtlasSize || (max_size & (max_size - 1)) != 0) {
    throw CookError("maximum atlas size " + std::to_string(max_size) +
                    " must be a power of two >= " + std::to_string(kMinAtlasSize));
  }
  for (const PackItem& it : items) {
    if (it.width + 2 > max_size || it.height + 2 > max_size) {
      throw CookError("a " + std::to_string(it.width) + "x" + std::to_string(it.height) +
                      " patch does not fit a " + std::to_string(max_size) +
                      " atlas with its gutter");
    }
  }
  std::vector<size_t> order(items.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    const PackItem& p = items[a];
    const PackItem& q = items[b];
    if (p.channels != q.channels) return p.channels > q.channels;
    return std::max(p.width, p.height) > std::max(q.width, q.height);
  });
  auto cost = [&](size_t i) {
    return int64_t(items[i].width + 2) * (items[i].height + 2) * items[i].channels;
  };
  std::vector<int> used_rows;  // per atlas: rows actually used (to trim the height)
  while (!order.empty()) {
    if (out.atlases.size() >= 256) throw CookError("the patches need more than 256 atlases");
    const int atlas_index = static_cast<int>(out.atlases.size());
    const PackItem& first = items[order[0]];
    Atlas atlas(std::min(
        max_size, pow2_at_least(std::max({kMinAtlasSize, first.width + 2, first.height + 2}))));
    int64_t remaining = 0;
    for (size_t i : order) remaining += cost(i);
    int rows = 0;
    std::vector<size_t> postponed;
    for (size_t i : order) {
      const PackItem& it = items[i];
      const int w = it.width + 2, h = it.height + 2;
      for (;;) {
        int x = 0, y = 0, channel = -1;
        if (it.channels == 3) {
          if (atlas.find(0, 3, w, h, &x, &y)) channel = 0;
        } else {
          for (int c = 0; c < 4 && channel < 0; ++c) {
            if (atlas.find(c, 1, w, h, &x, &y)) channel = c;
          }
        }
        if (channel >= 0) {
          atlas.place(channel, it.channels, x, y, w, h);
          out.placements[i] = Placement{atlas_index, x + 1, y + 1, channel};
          rows = std::max(rows, y + h);
          break;
        }
        const int64_t s_a = int64_t(atlas.size) * atlas.size * 4;
        if (atlas.size < max_size && (atlas.empty || 2 * s_a < remaining)) {
          atlas.grow();
          continue;
        }
        postponed.push_back(i);
        break;
      }
      remaining -= cost(i);
    }
    // The atlas stays square while packing; rows never used at the bottom are trimmed, keeping a
    // power-of-two height.
    int height = atlas.size;
    while (height / 2 >= rows && height / 2 >= 1) height /= 2;
    out.atlases.push_back(AtlasSize{atlas.size, height});
    order.swap(postponed);
  }
  return out;
}

}  // namespace lightpatch::cooker
