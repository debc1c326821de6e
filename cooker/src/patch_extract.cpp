#include "patch_extract.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "lightpatch/cooker/error.h"
#include "lightpatch/pack_format.h"
#include "lightpatch/patch_accumulate.h"

namespace lightpatch::cooker {

namespace {

bool significant_at(const FloatImage& map, int x, int y, float sign, float threshold) {
  for (int c = 0; c < map.channels; ++c) {
    if (sign * map.at(x, y, c) > threshold) return true;
  }
  return false;
}

// Bounding box of significant texels inside r; false if none.
bool significant_box(const FloatImage& map, const Rect& r, float sign, float threshold, Rect* box) {
  int x0 = r.x + r.w, y0 = r.y + r.h, x1 = r.x - 1, y1 = r.y - 1;
  for (int y = r.y; y < r.y + r.h; ++y) {
    for (int x = r.x; x < r.x + r.w; ++x) {
      if (!significant_at(map, x, y, sign, threshold)) continue;
      x0 = std::min(x0, x);
      y0 = std::min(y0, y);
      x1 = std::max(x1, x);
      y1 = std::max(y1, y);
    }
  }
  if (x1 < x0) return false;
  *box = Rect{x0, y0, x1 - x0 + 1, y1 - y0 + 1};
  return true;
}

}  // namespace

void extract_patches(const FloatImage& map, const std::vector<Region>& regions, float threshold,
                     int max_dim, const SourcePatch& prototype, const std::string& what,
                     std::vector<SourcePatch>& out, const FloatImage* tolerance_scale) {
  if (map.channels != 1 && map.channels != 3) {
    throw CookError(what + ": a map must have 1 or 3 channels, has " +
                    std::to_string(map.channels));
  }
  for (size_t i = 0; i < map.data.size(); ++i) {
    if (!std::isfinite(map.data[i])) {
      const size_t t = i / size_t(map.channels);
      throw CookError(what + ": non-finite value at texel (" +
                      std::to_string(t % size_t(map.width)) + ", " +
                      std::to_string(t / size_t(map.width)) + ")");
    }
  }
  if (tolerance_scale && (tolerance_scale->width != map.width ||
                          tolerance_scale->height != map.height || tolerance_scale->channels != 1))
    throw CookError(what + ": its tolerance scale does not match the map");
  for (const Region& region : regions) {
    // Clip the region to the map.
    const int rx0 = std::max(region.rect.x, 0), ry0 = std::max(region.rect.y, 0);
    const int rx1 = std::min(region.rect.x + region.rect.w, map.width);
    const int ry1 = std::min(region.rect.y + region.rect.h, map.height);
    if (rx1 <= rx0 || ry1 <= ry0) continue;
    const Rect clipped{rx0, ry0, rx1 - rx0, ry1 - ry0};
    for (const float sign : {1.0f, -1.0f}) {
      Rect box;
      if (!significant_box(map, clipped, sign, threshold, &box)) continue;
      for (int ty = box.y; ty < box.y + box.h; ty += max_dim) {
        for (int tx = box.x; tx < box.x + box.w; tx += max_dim) {
          const Rect tile{tx, ty, std::min(max_dim, box.x + box.w - tx),
                          std::min(max_dim, box.y + box.h - ty)};
          Rect r;
          if (!significant_box(map, tile, sign, threshold, &r)) continue;
          SourcePatch p = prototype;
          p.negative = sign < 0.0f;
          p.channels = map.channels;
          p.dest = r;
          p.threshold = threshold;
          p.values.assign(size_t(r.w) * r.h * map.channels, 0.0f);
          p.significant.assign(size_t(r.w) * r.h, 0);
          if (tolerance_scale) {
            p.tolerance_scale.resize(size_t(r.w) * r.h);
            for (int y = 0; y < r.h; ++y)
              for (int x = 0; x < r.w; ++x)
                p.tolerance_scale[size_t(y) * r.w + x] = tolerance_scale->at(r.x + x, r.y + y, 0);
          }
          for (int y = 0; y < r.h; ++y) {
            for (int x = 0; x < r.w; ++x) {
              for (int c = 0; c < map.channels; ++c) {
                p.values[(size_t(y) * r.w + x) * map.channels + c] =
                    std::max(sign * map.at(r.x + x, r.y + y, c), 0.0f);
              }
              p.significant[size_t(y) * r.w + x] =
                  significant_at(map, r.x + x, r.y + y, sign, threshold) ? 1 : 0;
            }
          }
          out.push_back(std::move(p));
        }
      }
    }
  }
}

void reduce_patch(SourcePatch& patch, int level) {
  if (patch.level != 0 || level < 1 || level > int(pack::kMaxPatchLevel))
    throw CookError("reduce_patch: level " + std::to_string(level) + " of a level-" +
                    std::to_string(patch.level) + " patch");
  const int w = patch.dest.w, h = patch.dest.h, ch = patch.channels, b = 1 << level;
  patch.level = level;
  const int sw = patch.stored_w(), sh = patch.stored_h();
  std::vector<float> values(size_t(sw) * sh * ch, 0.0f);
  std::vector<uint8_t> significant(size_t(sw) * sh, 0);
  for (int sy = 0; sy < sh; ++sy) {
    for (int sx = 0; sx < sw; ++sx) {
      const size_t s = size_t(sy) * sw + sx;
      const int x1 = std::min(w, (sx + 1) * b), y1 = std::min(h, (sy + 1) * b);
      int n = 0;
      for (int y = sy * b; y < y1; ++y) {
        for (int x = sx * b; x < x1; ++x, ++n) {
          const size_t t = size_t(y) * w + x;
          for (int c = 0; c < ch; ++c) values[s * ch + c] += patch.values[t * ch + c];
          significant[s] |= patch.significant[t];
        }
      }
      for (int c = 0; c < ch; ++c) values[s * ch + c] /= float(n);  // n >= 1: the block is in
    }
  }
  patch.values = std::move(values);
  patch.significant = std::move(significant);
  patch.tolerance_scale.clear();  // checked at level 0 only
}

void fit_patch(const SourcePatch& full, SourcePatch& reduced) {
  if (full.level != 0 || reduced.level < 1 || full.channels < 1 || full.channels > 3 ||
      reduced.dest.w != full.dest.w || reduced.dest.h != full.dest.h ||
      reduced.channels != full.channels ||
      full.values.size() != size_t(full.dest.w) * full.dest.h * size_t(full.channels) ||
      reduced.values.size() !=
          size_t(reduced.stored_w()) * reduced.stored_h() * size_t(reduced.channels))
    throw CookError("fit_patch: not a level-0 patch and its reduction");
  const int w = full.dest.w, h = full.dest.h, level = reduced.level;
  const int sw = reduced.stored_w(), sh = reduced.stored_h();
  const size_t ch = size_t(full.channels), n = size_t(w) * h * ch, m = size_t(sw) * sh * ch;
  const size_t row = size_t(w) * ch;  // a destination row, all channels interleaved
  // Scratch reused across calls on a thread: the pack builder fits many small tiles.
  thread_local std::vector<MagnifyTap<float>> tx, ty;
  thread_local std::vector<float> weight, c, r, s, p, q, half;
  tx.resize(size_t(w));
  ty.resize(size_t(h));
  for (int x = 0; x < w; ++x)
    tx[size_t(x)] = magnify_tap<float>(uint32_t(x), uint32_t(sw), uint32_t(level));
  for (int y = 0; y < h; ++y)
    ty[size_t(y)] = magnify_tap<float>(uint32_t(y), uint32_t(sh), uint32_t(level));
  // Each texel's error counts as a share of its own tolerance: weight 1 / scale^2.
  weight.assign(n, 1.0f);
  if (full.tolerance_scale.size() == size_t(w) * h) {
    for (size_t t = 0; t < size_t(w) * h; ++t) {
      const float sc = full.tolerance_scale[t];
      if (sc > 0.0f && std::isfinite(sc))
        for (size_t k = 0; k < ch; ++k) weight[t * ch + k] = 1.0f / (sc * sc);
    }
  }
  // out = M v, the runtime's magnification: along x on the stored rows, then along y (the order
  // of magnify_blend, so the same floats), every channel at once.
  auto magnify = [&](const std::vector<float>& v, std::vector<float>& out) {
    half.resize(size_t(sh) * row);
    for (int j = 0; j < sh; ++j) {
      const float* in = &v[size_t(j) * sw * ch];
      float* o = &half[size_t(j) * row];
      for (int x = 0; x < w; ++x) {
        const MagnifyTap<float>& a = tx[size_t(x)];
        for (size_t k = 0; k < ch; ++k) {
          const float l = in[a.i0 * ch + k], rt = in[a.i1 * ch + k];
          o[size_t(x) * ch + k] = l + a.t * (rt - l);
        }
      }
    }
    for (int y = 0; y < h; ++y) {
      const MagnifyTap<float>& b = ty[size_t(y)];
      const float* top = &half[b.i0 * row];
      const float* bottom = &half[b.i1 * row];
      float* o = &out[size_t(y) * row];
      for (size_t i = 0; i < row; ++i) o[i] = top[i] + b.t * (bottom[i] - top[i]);
    }
  };
  // out = M^T v: the same passes transposed, y first.
  auto spread = [&](const std::vector<float>& v, std::vector<float>& out) {
    half.assign(size_t(sh) * row, 0.0f);
    for (int y = 0; y < h; ++y) {
      const MagnifyTap<float>& b = ty[size_t(y)];
      const float* in = &v[size_t(y) * row];
      float* top = &half[b.i0 * row];
      float* bottom = &half[b.i1 * row];
      for (size_t i = 0; i < row; ++i) {
        top[i] += (1.0f - b.t) * in[i];
        bottom[i] += b.t * in[i];
      }
    }
    std::fill(out.begin(), out.end(), 0.0f);
    for (int j = 0; j < sh; ++j) {
      const float* in = &half[size_t(j) * row];
      float* o = &out[size_t(j) * sw * ch];
      for (int x = 0; x < w; ++x) {
        const MagnifyTap<float>& a = tx[size_t(x)];
        for (size_t k = 0; k < ch; ++k) {
          const float u = in[size_t(x) * ch + k];
          o[a.i0 * ch + k] += (1.0f - a.t) * u;
          o[a.i1 * ch + k] += a.t * u;
        }
      }
    }
  };
  // Per channel: sum of v[i] * u[i] * (weight[i] if given).
  auto dots = [&](const std::vector<float>& v, const std::vector<float>& u, const float* wt,
                  double* out) {
    for (size_t k = 0; k < ch; ++k) {
      double sum = 0.0;
      if (wt) {
        for (size_t i = k; i < v.size(); i += ch) sum += double(v[i]) * u[i] * wt[i];
      } else {
        for (size_t i = k; i < v.size(); i += ch) sum += double(v[i]) * u[i];
      }
      out[k] = sum;
    }
  };
  // Conjugate gradients on the normal equations (CGLS), each channel its own, from the block
  // means.
  c = reduced.values;
  r.resize(n);
  q.resize(n);
  s.resize(m);
  magnify(c, q);
  for (size_t i = 0; i < n; ++i) r[i] = weight[i] * (full.values[i] - q[i]);
  spread(r, s);
  p = s;
  double gamma[3], next[3], qq[3];
  float alpha[3], beta[3];
  dots(s, s, nullptr, gamma);
  for (int it = 0; it < kFitIterations; ++it) {
    magnify(p, q);
    dots(q, q, weight.data(), qq);
    bool any = false;
    for (size_t k = 0; k < ch; ++k) {
      const bool step = gamma[k] > 0.0 && qq[k] > 0.0;
      alpha[k] = step ? float(gamma[k] / qq[k]) : 0.0f;
      any = any || step;
    }
    if (!any) break;
    for (size_t k = 0; k < ch; ++k) {
      for (size_t i = k; i < m; i += ch) c[i] += alpha[k] * p[i];
      for (size_t i = k; i < n; i += ch) r[i] -= alpha[k] * weight[i] * q[i];
    }
    spread(r, s);
    dots(s, s, nullptr, next);
    for (size_t k = 0; k < ch; ++k) {
      beta[k] = gamma[k] > 0.0 ? float(next[k] / gamma[k]) : 0.0f;
      gamma[k] = next[k];
    }
    for (size_t k = 0; k < ch; ++k)
      for (size_t i = k; i < m; i += ch) p[i] = s[i] + beta[k] * p[i];
  }
  // Magnitudes: never negative (the sign is the patch's); a non-finite step keeps the mean.
  for (size_t i = 0; i < m; ++i)
    if (std::isfinite(c[i])) reduced.values[i] = std::max(c[i], 0.0f);
}

namespace {

// Whether the magnification of `reduced` stays within `tolerance` (times the texel's scale where
// `full` has them) of `full` at every texel and channel (false on a non-finite value).
bool within_tolerance(const SourcePatch& full, const SourcePatch& reduced, float tolerance) {
  const int w = full.dest.w, h = full.dest.h, ch = full.channels, level = reduced.level;
  const int sw = reduced.stored_w(), sh = reduced.stored_h();
  const float* v = reduced.values.data();
  for (int y = 0; y < h; ++y) {
    const MagnifyTap<float> ty = magnify_tap<float>(uint32_t(y), uint32_t(sh), uint32_t(level));
    for (int x = 0; x < w; ++x) {
      const MagnifyTap<float> tx = magnify_tap<float>(uint32_t(x), uint32_t(sw), uint32_t(level));
      const size_t a = (size_t(ty.i0) * sw + tx.i0) * ch, b = (size_t(ty.i0) * sw + tx.i1) * ch;
      const size_t c = (size_t(ty.i1) * sw + tx.i0) * ch, d = (size_t(ty.i1) * sw + tx.i1) * ch;
      const float at = full.tolerance_scale.empty()
                           ? tolerance
                           : tolerance * full.tolerance_scale[size_t(y) * w + x];
      for (int k = 0; k < ch; ++k) {
        const float m = magnify_blend(v[a + k], v[b + k], v[c + k], v[d + k], tx.t, ty.t);
        if (!(std::fabs(m - full.values[(size_t(y) * w + x) * ch + k]) <= at)) return false;
      }
    }
  }
  return true;
}

}  // namespace

int coarsest_level(const SourcePatch& patch, int max_level, float tolerance,
                   SourcePatch* coarsest) {
  if (patch.level != 0) throw CookError("coarsest_level: a magnified patch");
  const int w = patch.dest.w, h = patch.dest.h;
  int chosen = 0;
  for (int level = 1; level <= std::min(max_level, int(pack::kMaxPatchLevel)); ++level) {
    // A patch one texel wide along an axis gains nothing there; one that is 1 x 1 nothing at all.
    if ((w >> (level - 1)) < 2 && (h >> (level - 1)) < 2) break;
    SourcePatch reduced = patch;
    reduce_patch(reduced, level);
    fit_patch(patch, reduced);
    if (!within_tolerance(patch, reduced, tolerance)) break;
    chosen = level;
    if (coarsest) *coarsest = std::move(reduced);
  }
  return chosen;
}

std::vector<SourcePatch> cut_patch(const SourcePatch& patch, const std::vector<Rect>& cells) {
  if (patch.level != 0) throw CookError("cut_patch: a magnified patch");
  const int w = patch.dest.w, h = patch.dest.h, ch = patch.channels;
  auto kept = [&](size_t t) {
    if (patch.significant[t]) return true;
    for (int c = 0; c < ch; ++c)
      if (patch.values[t * ch + c] > kCutKeepFraction * patch.threshold) return true;
    return false;
  };
  std::vector<SourcePatch> out;
  for (const Rect& cell : cells) {
    const int cx0 = std::max(cell.x, 0), cy0 = std::max(cell.y, 0);
    const int cx1 = std::min(cell.x + cell.w, w), cy1 = std::min(cell.y + cell.h, h);
    if (cx1 <= cx0 || cy1 <= cy0) continue;
    int x0 = cx1, y0 = cy1, x1 = cx0 - 1, y1 = cy0 - 1;
    for (int y = cy0; y < cy1; ++y)
      for (int x = cx0; x < cx1; ++x)
        if (kept(size_t(y) * w + x)) {
          x0 = std::min(x0, x);
          y0 = std::min(y0, y);
          x1 = std::max(x1, x);
          y1 = std::max(y1, y);
        }
    if (x1 < x0) continue;
    SourcePatch q = patch;
    q.dest = Rect{patch.dest.x + x0, patch.dest.y + y0, x1 - x0 + 1, y1 - y0 + 1};
    q.values.assign(size_t(q.dest.w) * q.dest.h * ch, 0.0f);
    q.significant.assign(size_t(q.dest.w) * q.dest.h, 0);
    const bool scaled = !patch.tolerance_scale.empty();
    if (scaled) q.tolerance_scale.assign(size_t(q.dest.w) * q.dest.h, 1.0f);
    for (int y = 0; y < q.dest.h; ++y)
      for (int x = 0; x < q.dest.w; ++x) {
        const size_t from = size_t(y0 + y) * w + size_t(x0 + x), to = size_t(y) * q.dest.w + x;
        q.significant[to] = patch.significant[from];
        if (scaled) q.tolerance_scale[to] = patch.tolerance_scale[from];
        for (int c = 0; c < ch; ++c) q.values[to * ch + c] = patch.values[from * ch + c];
      }
    out.push_back(std::move(q));
  }
  return out;
}

std::vector<SourcePatch> split_patch(const SourcePatch& patch, int tile) {
  if (patch.level != 0 || tile < 1) throw CookError("split_patch: a magnified patch or no tile");
  std::vector<Rect> cells;
  for (int ty = 0; ty < patch.dest.h; ty += tile)
    for (int tx = 0; tx < patch.dest.w; tx += tile) cells.push_back(Rect{tx, ty, tile, tile});
  return cut_patch(patch, cells);
}

std::vector<SourcePatch> split_by_charts(const SourcePatch& patch,
                                         const std::vector<Region>& regions, int inset) {
  std::vector<Rect> cells;
  const Rect& d = patch.dest;
  for (const Region& region : regions) {
    const Rect& r = region.rect;
    if (r.x >= d.x + d.w || d.x >= r.x + r.w || r.y >= d.y + d.h || d.y >= r.y + r.h) continue;
    for (const Rect& c : region.charts)
      cells.push_back(Rect{c.x - d.x + inset, c.y - d.y + inset, c.w - 2 * inset, c.h - 2 * inset});
  }
  if (cells.size() < 2) return {};
  return cut_patch(patch, cells);
}

float colour_spread(const SourcePatch& patch) {
  float spread = 0.0f;
  if (patch.channels != 3) return spread;
  for (size_t i = 0; i + 2 < patch.values.size(); i += 3) {
    const float* v = &patch.values[i];
    spread = std::max(spread, std::max({v[0], v[1], v[2]}) - std::min({v[0], v[1], v[2]}));
  }
  return spread;
}

bool collapse_untinted(SourcePatch& patch, float spread) {
  if (patch.channels != 3 || spread > patch.threshold) return false;
  const size_t n = patch.values.size() / 3;
  std::vector<float> grey(n);
  for (size_t i = 0; i < n; ++i) {
    const float* v = &patch.values[3 * i];
    grey[i] = 0.5f * (std::max({v[0], v[1], v[2]}) + std::min({v[0], v[1], v[2]}));
  }
  patch.values = std::move(grey);
  patch.channels = 1;
  return true;
}

bool collapse_to_tint(SourcePatch& patch, float tolerance) {
  if (patch.channels != 3 || patch.values.empty()) return false;
  const size_t n = patch.values.size() / 3;
  // The colours' second moments; their principal eigenvector by power iteration from the mean
  // colour (the moments are non-negative, so the iteration stays in the positive octant).
  double m[3][3] = {}, t[3] = {};
  for (size_t i = 0; i < n; ++i) {
    const float* v = &patch.values[3 * i];
    for (int a = 0; a < 3; ++a) {
      t[a] += v[a];
      for (int b = 0; b < 3; ++b) m[a][b] += double(v[a]) * double(v[b]);
    }
  }
  for (int it = 0; it < 16; ++it) {
    double u[3] = {};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) u[a] += m[a][b] * t[b];
    const double top = std::max({u[0], u[1], u[2]});
    if (!(top > 0.0)) return false;  // no light at all
    for (int a = 0; a < 3; ++a) t[a] = u[a] / top;
  }
  uint8_t q[3];
  float tf[3];
  for (int a = 0; a < 3; ++a) {
    q[a] = uint8_t(std::clamp(std::lround(255.0 * t[a]), 0l, 255l));
    tf[a] = float(q[a]) / 255.0f;  // what the runtime multiplies by (patch_tint)
  }
  const float tt = tf[0] * tf[0] + tf[1] * tf[1] + tf[2] * tf[2];  // >= 1: the largest is 255
  std::vector<float> one(n);
  for (size_t i = 0; i < n; ++i) {
    const float* v = &patch.values[3 * i];
    const float x = std::max(0.0f, (tf[0] * v[0] + tf[1] * v[1] + tf[2] * v[2]) / tt);
    for (int a = 0; a < 3; ++a)
      if (std::fabs(tf[a] * x - v[a]) > tolerance) return false;
    one[i] = x;
  }
  patch.values = std::move(one);
  patch.channels = 1;
  for (int a = 0; a < 3; ++a) patch.tint[a] = q[a];
  return true;
}

namespace {

// The eigenvectors of a symmetric 3x3 matrix (cyclic Jacobi rotations), as the columns of `vec`
// ordered by decreasing eigenvalue.
void symmetric_eigen3(const double m[3][3], double vec[3][3]) {
  double a[3][3], v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) a[i][k] = m[i][k];
  for (int sweep = 0; sweep < 32; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
    if (!(off > 1e-30 * diag)) break;
    for (int p = 0; p < 2; ++p) {
      for (int q = p + 1; q < 3; ++q) {
        if (a[p][q] == 0.0) continue;
        const double theta = 0.5 * (a[q][q] - a[p][p]) / a[p][q];
        const double t =
            (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1.0 / std::sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < 3; ++k) {  // a <- a J (columns p, q)
          const double akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {  // a <- J^T a (rows p, q)
          const double apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {
          const double vkp = v[k][p], vkq = v[k][q];
          v[k][p] = c * vkp - s * vkq;
          v[k][q] = s * vkp + c * vkq;
        }
      }
    }
  }
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int x, int y) { return a[x][x] > a[y][y]; });
  for (int col = 0; col < 3; ++col)
    for (int k = 0; k < 3; ++k) vec[k][col] = v[k][order[col]];
}

}  // namespace

bool collapse_to_two_tints(SourcePatch& patch, float tolerance) {
  if (patch.channels != 3 || patch.values.empty()) return false;
  const size_t n = patch.values.size() / 3;
  double m[3][3] = {};
  for (size_t i = 0; i < n; ++i) {
    const float* v = &patch.values[3 * i];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) m[a][b] += double(v[a]) * double(v[b]);
  }
  double e[3][3];
  symmetric_eigen3(m, e);
  // The plane of the two largest: e1 is the moments' Perron vector, so every colour has e1.v >= 0.
  double e1[3] = {e[0][0], e[1][0], e[2][0]}, e2[3] = {e[0][1], e[1][1], e[2][1]};
  if (e1[0] + e1[1] + e1[2] < 0)
    for (double& x : e1) x = -x;
  // The cone of the colours in that plane: its two extreme rays are the tints, so that every
  // colour is a non-negative blend of them. Colours within the tolerance of black (which two
  // zeros hold) do not widen it: their direction is noise.
  double lo = INFINITY, hi = -INFINITY;
  for (size_t i = 0; i < n; ++i) {
    const float* v = &patch.values[3 * i];
    if (std::max({v[0], v[1], v[2]}) <= tolerance) continue;
    const double p = e1[0] * v[0] + e1[1] * v[1] + e1[2] * v[2];
    const double q = e2[0] * v[0] + e2[1] * v[1] + e2[2] * v[2];
    const double angle = std::atan2(q, p);
    lo = std::min(lo, angle);
    hi = std::max(hi, angle);
  }
  if (!(lo <= hi)) return false;
  uint8_t tq[2][3];
  float tf[2][3];
  for (int r = 0; r < 2; ++r) {
    const double angle = r == 0 ? lo : hi;
    double t[3], top = 0.0;
    for (int a = 0; a < 3; ++a) {
      t[a] = std::max(0.0, std::cos(angle) * e1[a] + std::sin(angle) * e2[a]);
      top = std::max(top, t[a]);
    }
    if (!(top > 0.0)) return false;
    for (int a = 0; a < 3; ++a) {
      tq[r][a] = uint8_t(std::clamp(std::lround(255.0 * t[a] / top), 0l, 255l));
      tf[r][a] = float(tq[r][a]) / 255.0f;  // what the runtime multiplies by (patch_tint)
    }
  }
  // Each texel's non-negative least-squares blend of the two quantized tints.
  const float g00 = tf[0][0] * tf[0][0] + tf[0][1] * tf[0][1] + tf[0][2] * tf[0][2];  // >= 1
  const float g11 = tf[1][0] * tf[1][0] + tf[1][1] * tf[1][1] + tf[1][2] * tf[1][2];  // >= 1
  const float g01 = tf[0][0] * tf[1][0] + tf[0][1] * tf[1][1] + tf[0][2] * tf[1][2];
  const float det = g00 * g11 - g01 * g01;
  if (!(det > 1e-4f * g00 * g11)) return false;  // one tint twice: collapse_to_tint's case
  std::vector<float> two(2 * n);
  float top_a = 0.0f, top_b = 0.0f;
  for (size_t i = 0; i < n; ++i) {
    const float* v = &patch.values[3 * i];
    const float ra = tf[0][0] * v[0] + tf[0][1] * v[1] + tf[0][2] * v[2];
    const float rb = tf[1][0] * v[0] + tf[1][1] * v[1] + tf[1][2] * v[2];
    float a = (g11 * ra - g01 * rb) / det, b = (g00 * rb - g01 * ra) / det;
    if (a < 0.0f || b < 0.0f) {  // on the cone's edge: the better of the two single tints
      const float a1 = std::max(0.0f, ra / g00), b1 = std::max(0.0f, rb / g11);
      float ea = 0.0f, eb = 0.0f;
      for (int c = 0; c < 3; ++c) {
        ea += (tf[0][c] * a1 - v[c]) * (tf[0][c] * a1 - v[c]);
        eb += (tf[1][c] * b1 - v[c]) * (tf[1][c] * b1 - v[c]);
      }
      a = ea <= eb ? a1 : 0.0f;
      b = ea <= eb ? 0.0f : b1;
    }
    for (int c = 0; c < 3; ++c)
      if (std::fabs(tf[0][c] * a + tf[1][c] * b - v[c]) > tolerance) return false;
    two[2 * i] = a;
    two[2 * i + 1] = b;
    top_a = std::max(top_a, a);
    top_b = std::max(top_b, b);
  }
  if (!(top_a > 0.0f) || !(top_b > 0.0f)) return false;  // one tint holds it: collapse_to_tint's
  patch.values = std::move(two);
  patch.channels = 2;
  for (int a = 0; a < 3; ++a) {
    patch.tint[a] = tq[0][a];
    patch.tint_b[a] = tq[1][a];
  }
  return true;
}

}  // namespace lightpatch::cooker
