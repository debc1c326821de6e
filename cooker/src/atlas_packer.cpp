#include "atlas_packer.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <string>

#include "lightpatch/cooker/error.h"
#include "lightpatch/pack_format.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

namespace {

constexpr int kAtlasAlign = int(pack::kAtlasAlign);

// Columns [x, x + w) are free from row y down (rows grow down).
struct Segment {
  int x, y, w;
};

// Skyline of one channel: segments sorted by x, covering the atlas width, neighbours at
// different heights.
class Skyline {
 public:
  explicit Skyline(int width) : segs_{{0, 0, width}} {}
  const std::vector<Segment>& segments() const { return segs_; }

  // The rect occupies columns [x, x + w) down to row y_top.
  void place(int x, int y_top, int w) {
    next_.clear();
    bool inserted = false;
    auto push = [&](const Segment& s) {
      if (!next_.empty() && next_.back().y == s.y)
        next_.back().w += s.w;
      else
        next_.push_back(s);
    };
    auto insert = [&]() {
      if (!inserted) push({x, y_top, w});
      inserted = true;
    };
    for (const Segment& s : segs_) {
      if (s.x + s.w <= x) {
        push(s);
        continue;
      }
      if (s.x >= x + w) {
        insert();
        push(s);
        continue;
      }
      if (s.x < x) push({s.x, s.y, x - s.x});
      insert();
      if (s.x + s.w > x + w) push({x + w, s.y, s.x + s.w - (x + w)});
    }
    insert();
    segs_.swap(next_);
  }

 private:
  std::vector<Segment> segs_, next_;
};

// The skyline of channels [0, n) together (the highest of them at every column) into `out`.
void merge(const Skyline* channels, int n, int width, std::vector<Segment>& out) {
  out.clear();
  size_t at[4] = {0, 0, 0, 0};
  for (int x = 0; x < width;) {
    int y = 0, end = width;
    for (int k = 0; k < n; ++k) {
      const std::vector<Segment>& s = channels[k].segments();
      while (s[at[k]].x + s[at[k]].w <= x) ++at[k];
      y = std::max(y, s[at[k]].y);
      end = std::min(end, s[at[k]].x + s[at[k]].w);
    }
    if (!out.empty() && out.back().y == y)
      out.back().w += end - x;
    else
      out.push_back({x, y, end - x});
    x = end;
  }
}

// The lowest, then leftmost, position of a w x h rect on the skyline within width x height, if
// it is lower than *best_y (then *best_x, *best_y are updated).
bool find(const std::vector<Segment>& segs, int width, int height, int w, int h, int* best_x,
          int* best_y) {
  bool found = false;
  int limit = std::min(*best_y, height - h + 1);  // y must stay below this
  for (size_t i = 0; i < segs.size(); ++i) {
    const int x = segs[i].x;
    if (x + w > width) break;
    int y = 0;
    for (size_t j = i; j < segs.size() && segs[j].x < x + w && y < limit; ++j)
      y = std::max(y, segs[j].y);
    if (y < limit) {
      *best_x = x;
      *best_y = limit = y;
      found = true;
    }
  }
  return found;
}

int align_up(int64_t v) {
  return int((v + kAtlasAlign - 1) / kAtlasAlign * kAtlasAlign);
}

// One atlas filled with the patches of `order` in turn, in a width x height area.
struct Fill {
  std::vector<Placement> placements;  // parallel to `order`; atlas -1: did not fit
  std::vector<size_t> postponed;      // items that did not fit, in order
  int used_width = 0, used_height = 0;
  int64_t texels() const { return int64_t(align_up(used_width)) * align_up(used_height); }
};

// With `all`, gives up (false) at the first patch that does not fit, or once the atlas takes
// `give_up_at` texels or more (it can only grow: a search's trial that cannot win).
bool fill(const std::vector<PackItem>& items, const std::vector<size_t>& order, int width,
          int height, bool all, Fill* out,
          int64_t give_up_at = std::numeric_limits<int64_t>::max()) {
  std::vector<Skyline> channels(4, Skyline(width));
  std::vector<Segment> rgb;
  out->placements.assign(order.size(), Placement{-1, 0, 0, 0});
  out->postponed.clear();
  out->used_width = out->used_height = 0;
  for (size_t k = 0; k < order.size(); ++k) {
    const PackItem& it = items[order[k]];
    const int w = it.width, h = it.height;
    int x = 0, y = std::numeric_limits<int>::max(), channel = -1;
    if (it.channels == 3) {
      merge(channels.data(), 3, width, rgb);
      if (find(rgb, width, height, w, h, &x, &y)) channel = 0;
    } else if (it.channels == 2) {
      // The lowest place of channels 0-1 or 2-3 together.
      for (int c = 0; c < 4; c += 2) {
        merge(channels.data() + c, 2, width, rgb);
        if (find(rgb, width, height, w, h, &x, &y)) channel = c;
      }
    } else {
      // The lowest place in any channel: 1-channel patches fill the alpha plane under 3-channel
      // ones before they raise the atlas.
      for (int c = 0; c < 4; ++c) {
        if (find(channels[size_t(c)].segments(), width, height, w, h, &x, &y)) channel = c;
      }
    }
    if (channel < 0) {
      if (all) return false;
      out->postponed.push_back(order[k]);
      continue;
    }
    for (int c = channel; c < channel + it.channels; ++c) channels[size_t(c)].place(x, y + h, w);
    out->placements[k] = Placement{0, x, y, channel};
    out->used_width = std::max(out->used_width, x + w);
    out->used_height = std::max(out->used_height, y + h);
    if (all && out->texels() >= give_up_at) return false;
  }
  return true;
}

// Widths to try for an atlas that holds everything left: from lo, each a fifth wider than the
// last (about 24 from 16 to 2048), then hi; integers, so that every target writes the same pack.
std::vector<int> candidate_widths(int lo, int hi) {
  std::vector<int> out;
  for (int w = lo; w < hi; w = std::max(align_up(int64_t(w) * 6 / 5), w + kAtlasAlign))
    out.push_back(w);
  out.push_back(hi);
  return out;
}

// Orders the patches may be placed in: each first by channel count (2, 3, then 1: see
// atlas_packer.h), then by the key, then by height and width, descending.
enum class SortKey { kHeight, kLongestSide, kArea, kWidth };
constexpr SortKey kSortKeys[] = {SortKey::kHeight, SortKey::kLongestSide, SortKey::kArea,
                                 SortKey::kWidth};

void sort_items(const std::vector<PackItem>& items, SortKey key, std::vector<size_t>& order) {
  auto measure = [key](const PackItem& p) -> int64_t {
    switch (key) {
      case SortKey::kLongestSide:
        return std::max(p.width, p.height);
      case SortKey::kArea:
        return int64_t(p.width) * p.height;
      case SortKey::kWidth:
        return p.width;
      case SortKey::kHeight:
        break;
    }
    return p.height;
  };
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    const PackItem& p = items[a];
    const PackItem& q = items[b];
    // 2-channel patches first, in pairs (channels 0-1 and 2-3 of one place); then 3-channel ones
    // above them, whose alpha plane the 1-channel ones fill last. (2-channel patches after the
    // 3-channel ones would raise the alpha plane's skyline over their empty alpha.)
    auto rank = [](int channels) { return channels == 2 ? 0 : channels == 3 ? 1 : 2; };
    if (p.channels != q.channels) return rank(p.channels) < rank(q.channels);
    if (measure(p) != measure(q)) return measure(p) > measure(q);
    if (p.height != q.height) return p.height > q.height;
    return p.width > q.width;
  });
}

// Patch placements the search for the last atlas may make (patches times widths and orders
// tried): every width in every order for a pack of a few hundred patches, the candidate widths
// for a large one. The small inn at draft (5,719 patches, 2 threads): 0.07 s a search against
// 0.04 s for the candidate widths in one order; at 2^20, 0.12 s, for fewer bytes only on the small
// inn without bounce light (2.3 % waste instead of 3.2 %).
constexpr int64_t kSearchPlacements = int64_t(1) << 19;

}  // namespace

AtlasLayout pack_atlases(const std::vector<PackItem>& items, int max_size, int threads) {
  AtlasLayout out;
  out.placements.resize(items.size());
  if (max_size < kMinAtlasSize || max_size % kAtlasAlign != 0) {
    throw CookError("maximum atlas size " + std::to_string(max_size) + " must be a multiple of " +
                    std::to_string(kAtlasAlign) + " >= " + std::to_string(kMinAtlasSize));
  }
  for (const PackItem& it : items) {
    if (it.width < 1 || it.height < 1 || it.width > max_size || it.height > max_size ||
        it.channels < 1 || it.channels > 3) {
      throw CookError("a " + std::to_string(it.width) + "x" + std::to_string(it.height) + "x" +
                      std::to_string(it.channels) + " patch does not fit a " +
                      std::to_string(max_size) + " atlas");
    }
  }
  std::vector<size_t> order(items.size());
  std::iota(order.begin(), order.end(), size_t(0));
  sort_items(items, SortKey::kHeight, order);
  const int64_t max_texels = int64_t(max_size) * max_size;
  while (!order.empty()) {
    if (out.atlases.size() >= 256) throw CookError("the patches need more than 256 atlases");
    // Texels the patches left need at least: 3-channel patches each take a rectangle of their
    // own; all of them together a quarter of their channel-texels.
    int64_t rgb_texels = 0, channel_texels = 0;
    int widest = 1;
    for (size_t i : order) {
      const int64_t t = int64_t(items[i].width) * items[i].height;
      channel_texels += t * items[i].channels;
      if (items[i].channels == 3) rgb_texels += t;
      widest = std::max(widest, items[i].width);
    }
    const int64_t need = std::max(rgb_texels, (channel_texels + 3) / 4);
    Fill best;
    bool found = false;
    if (need <= max_texels) {
      // Everything left may fit one atlas. How well the skylines fill it jumps from one width
      // to the next and from one order to another, so try many: the candidate widths in each
      // order, then every few texels around the best of them, then, while the budget of
      // placements lasts, every width (a small pack tries every width in every order).
      const int lo = std::min(max_size, std::max(align_up(widest), align_up(need / max_size)));
      const std::vector<int> widths = candidate_widths(lo, max_size);
      const int64_t trials_allowed =
          std::max<int64_t>(kSearchPlacements / int64_t(order.size()), 1);
      std::vector<std::vector<size_t>> orders;
      std::vector<std::vector<char>> tried;
      for (SortKey key : kSortKeys) {
        orders.push_back(order);
        sort_items(items, key, orders.back());
        tried.emplace_back(size_t(max_size / kAtlasAlign) + 1, 0);
      }
      struct Trial {
        size_t order;
        int width;
      };
      std::vector<Trial> batch;
      int64_t trials = 0, best_texels = 0;
      Trial best_trial{0, 0};
      // Queues a trial not made yet, within the budget unless `always`.
      auto add = [&](size_t k, int w, bool always) {
        char& t = tried[k][size_t(w / kAtlasAlign)];
        if (t || (!always && trials >= trials_allowed)) return;
        t = 1;
        ++trials;
        batch.push_back(Trial{k, w});
      };
      // Runs the queued trials on the threads. Strictly fewer texels wins and the first of equals
      // (in queue order) is kept, so the pack is the same on every target and thread count.
      auto run = [&]() {
        std::vector<int64_t> texels(batch.size(), 0);
        const int64_t give_up_at = found ? best_texels : std::numeric_limits<int64_t>::max();
        parallel_for(int(batch.size()), threads, [&](int i) {
          Fill f;
          const Trial& t = batch[size_t(i)];
          if (fill(items, orders[t.order], t.width, max_size, true, &f, give_up_at))
            texels[size_t(i)] = f.texels();
        });
        for (size_t i = 0; i < batch.size(); ++i) {
          if (texels[i] > 0 && (!found || texels[i] < best_texels)) {
            best_texels = texels[i];
            best_trial = batch[i];
            found = true;
          }
        }
        batch.clear();
      };
      for (size_t k = 0; k < orders.size(); ++k) {
        for (int w : widths) add(k, w, k == 0);
        run();  // so that each order's trials give up where the orders before did better
      }
      if (found) {
        // Every few texels around the best width so far, in every order.
        const int w0 = best_trial.width;
        const auto at = std::lower_bound(widths.begin(), widths.end(), w0);
        const int from = at == widths.begin() ? lo : *(at - 1);
        const int to = at == widths.end() || at + 1 == widths.end() ? max_size : *(at + 1);
        const int step = std::max(kAtlasAlign, align_up((to - from) / 16));
        for (size_t k = 0; k < orders.size(); ++k)
          for (int w = from; w <= to; w += step) add(k, w, k == 0);
        run();
      }
      for (int w = lo; w <= max_size && trials < trials_allowed; w += kAtlasAlign)
        for (size_t k = 0; k < orders.size(); ++k) add(k, w, false);
      run();
      if (found) {
        order = std::move(orders[best_trial.order]);
        fill(items, order, best_trial.width, max_size, true, &best);
      }
    }
    if (!found) fill(items, order, max_size, max_size, false, &best);
    const int atlas_index = int(out.atlases.size());
    for (size_t k = 0; k < order.size(); ++k) {
      if (best.placements[k].atlas < 0) continue;
      out.placements[order[k]] = best.placements[k];
      out.placements[order[k]].atlas = atlas_index;
    }
    out.atlases.push_back(AtlasSize{align_up(best.used_width), align_up(best.used_height)});
    order = best.postponed;
  }
  return out;
}

}  // namespace lightpatch::cooker
