// Texels of the light map (seed 003): each triangle is rasterized into the layout, conservatively,
// so that every texel a chart touches gets a sample on the surface: at the texel centre when the
// centre is inside a triangle, otherwise at the triangle's point nearest to the centre (never an
// extrapolated point off the surface, where light would leak in). Samples buried in solid
// geometry are pushed out (seed 004 §6.10.3). After baking, finalize_map() fills unused texels
// from their neighbours (dilation) and makes both sides of every seam agree (stitching); both are
// linear in the map, so recomposing finalized maps equals finalizing a recomposed one.
#include "lightpatch/cooker/texel_builder.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>
#include <vector>

#include "lightpatch/cooker/tracer.h"
#include "surface_albedo.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

namespace {

// A texel is touched by a triangle when the triangle comes within this distance (texels) of its
// centre: half the texel diagonal.
constexpr float kTouch = 0.7072f;
// How far (texels) samples keep from triangle edges.
constexpr float kEdgeMargin = 0.1f;
// Tangent directions probed for the solid-space correction.
constexpr int kPushDirections = 8;
// Passes of the seam stitching: the second lets texels beyond one edge read the other chart's
// texels beyond it, already stitched.
constexpr int kSeamPasses = 2;
// A texel centre this close (texels) to a triangle lies inside it.
constexpr float kInside = 1e-3f;
// Rings of unused texels filled around each chart: more than the gutter between two charts.
constexpr int kDilationRings = 6;

struct Candidate {
  float distance = std::numeric_limits<float>::max();  // texels from the centre; 0 = inside
};

// Closest point of triangle abc to p (Ericson, Real-Time Collision Detection §5.1.5), returned as
// barycentrics (wa, wb, wc).
glm::vec3 closest_barycentric(const glm::vec2& p, const glm::vec2& a, const glm::vec2& b,
                              const glm::vec2& c) {
  const glm::vec2 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const glm::vec2 bp = p - b;
  const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const float v = d1 / (d1 - d3);  // d1 >= 0 >= d3 and not both 0 here
    return {1 - v, v, 0};
  }
  const glm::vec2 cp = p - c;
  const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const float w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const float w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const float sum = va + vb + vc;
  if (!(sum > 0.0f)) return {1.0f / 3, 1.0f / 3, 1.0f / 3};  // degenerate in UV
  return {va / sum, vb / sum, vc / sum};
}

// A sample on (or within kEdgeMargin texels of) a triangle's edge is moved that far towards the
// centroid: at a corner where a wall meets a floor, a sample exactly on the edge would start its
// shadow rays inside the wall's plane and see past it.
glm::vec3 away_from_edges(const glm::vec3& bary, const glm::vec2 p[3]) {
  const glm::vec2 q = bary.x * p[0] + bary.y * p[1] + bary.z * p[2];
  float edge = std::numeric_limits<float>::max();
  for (int k = 0; k < 3; ++k) {
    const glm::vec2 a = p[k], e = p[(k + 1) % 3] - a;
    const float len2 = glm::dot(e, e);
    const float t = len2 > 0.0f ? std::clamp(glm::dot(q - a, e) / len2, 0.0f, 1.0f) : 0.0f;
    edge = std::min(edge, glm::length(q - (a + e * t)));
  }
  if (!(edge < kEdgeMargin)) return bary;
  const glm::vec3 centroid(1.0f / 3.0f);
  const float to_centroid = glm::length((p[0] + p[1] + p[2]) / 3.0f - q);
  const float f = to_centroid > 0.0f ? std::min(1.0f, (kEdgeMargin - edge) / to_centroid) : 1.0f;
  return bary + (centroid - bary) * f;
}

// Rasterizes the meshes of one region into its rectangle.
void rasterize_region(const Scene& scene, const Layout& layout, int region_index, TexelSet& ts,
                      std::vector<Candidate>& best) {
  const Region& region = layout.regions[size_t(region_index)];
  const Rect& rc = region.rect;
  const glm::vec2 size(float(layout.width), float(layout.height));
  for (int mi : region.meshes) {
    const MeshInstance& m = scene.meshes[size_t(mi)];
    const MeshLayout& ml = layout.meshes[size_t(mi)];
    for (size_t t = 0; t < ml.indices.size() / 3; ++t) {
      const uint32_t l[3] = {ml.indices[3 * t], ml.indices[3 * t + 1], ml.indices[3 * t + 2]};
      const uint32_t s[3] = {ml.source_vertex[l[0]], ml.source_vertex[l[1]],
                             ml.source_vertex[l[2]]};
      const glm::vec2 p[3] = {ml.uv[l[0]] * size, ml.uv[l[1]] * size, ml.uv[l[2]] * size};
      const glm::vec2 lo = glm::min(p[0], glm::min(p[1], p[2]));
      const glm::vec2 hi = glm::max(p[0], glm::max(p[1], p[2]));
      const int x0 = std::max(rc.x, static_cast<int>(std::floor(lo.x - kTouch)));
      const int y0 = std::max(rc.y, static_cast<int>(std::floor(lo.y - kTouch)));
      const int x1 = std::min(rc.x + rc.w - 1, static_cast<int>(std::floor(hi.x + kTouch)));
      const int y1 = std::min(rc.y + rc.h - 1, static_cast<int>(std::floor(hi.y + kTouch)));
      const glm::vec3 pa = m.positions[s[0]], pb = m.positions[s[1]], pc = m.positions[s[2]];
      glm::vec3 face = glm::cross(pb - pa, pc - pa);
      const float face_len = glm::length(face);
      face = face_len > 0.0f ? face / face_len : glm::vec3(0, 0, 1);
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const glm::vec2 centre(float(x) + 0.5f, float(y) + 0.5f);
          glm::vec3 bary = closest_barycentric(centre, p[0], p[1], p[2]);
          const glm::vec2 q = bary.x * p[0] + bary.y * p[1] + bary.z * p[2];
          const float d = glm::length(q - centre);
          const size_t i = ts.index(x, y);
          // Earlier triangles win ties, so the result does not depend on anything but order.
          if (d > kTouch || !(d < best[i].distance)) continue;
          bary = away_from_edges(bary, p);
          best[i].distance = d;
          ts.valid[i] = 1;
          ts.position[i] = bary.x * pa + bary.y * pb + bary.z * pc;
          glm::vec3 n =
              bary.x * m.normals[s[0]] + bary.y * m.normals[s[1]] + bary.z * m.normals[s[2]];
          const float len = glm::length(n);
          ts.normal[i] = len > 1e-6f ? n / len : face;
          ts.albedo[i] = surface_albedo(scene, m, s[0], s[1], s[2], bary.y, bary.z);
          ts.mesh[i] = mi;
          ts.region[i] = region_index;
        }
    }
  }
}

// Solid-space correction: a sample whose short tangent-plane probes hit the back of a static
// surface lies inside solid geometry (a floor texel under a wall); it is moved just past the
// nearest such surface, where it sees what the visible part of the texel sees.
void push_out(const Tracer& tracer, const Layout& layout, TexelSet& ts, int threads) {
  const float texel_world = layout.texels_per_unit > 0.0f ? 1.0f / layout.texels_per_unit : 0.0f;
  if (!(texel_world > 0.0f)) return;
  const float reach = 0.75f * texel_world;  // about half the texel diagonal, with margin
  const float eps = tracer.epsilon();
  parallel_for(ts.height, threads, [&](int y) {
    for (int x = 0; x < ts.width; ++x) {
      const size_t i = ts.index(x, y);
      if (!ts.valid[i]) continue;
      const glm::vec3 n = ts.normal[i];
      const glm::vec3 a = std::abs(n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
      const glm::vec3 t = glm::normalize(glm::cross(a, n));
      const glm::vec3 b = glm::cross(n, t);
      // Probe from just above the surface so the sample's own triangle is not hit.
      const glm::vec3 origin = ts.position[i] + n * eps;
      float nearest = std::numeric_limits<float>::max();
      glm::vec3 moved = ts.position[i];
      for (int k = 0; k < kPushDirections; ++k) {
        const float angle = 6.2831853f * float(k) / float(kPushDirections);
        const glm::vec3 dir = std::cos(angle) * t + std::sin(angle) * b;
        const Hit hit = tracer.intersect(origin, dir, 0.0f, reach, false);
        if (!hit.hit || hit.t >= nearest) continue;
        if (glm::dot(hit.geometric_normal, dir) <= 0.0f) continue;  // a front face: open space
        nearest = hit.t;
        // Through the back face to its front side, one offset beyond.
        moved = origin + dir * (hit.t + 2.0f * eps);
      }
      ts.position[i] = moved;
    }
  });
}

// Region index of every texel from the layout's rectangles (-1 outside every region).
std::vector<int32_t> region_image(const Layout& layout) {
  std::vector<int32_t> img(size_t(layout.width) * size_t(layout.height), -1);
  for (size_t r = 0; r < layout.regions.size(); ++r) {
    const Rect& rc = layout.regions[r].rect;
    for (int y = std::max(0, rc.y); y < std::min(layout.height, rc.y + rc.h); ++y)
      for (int x = std::max(0, rc.x); x < std::min(layout.width, rc.x + rc.w); ++x)
        img[size_t(y) * size_t(layout.width) + size_t(x)] = int32_t(r);
  }
  return img;
}

// Plans the filling of unused texels: ring by ring, each takes the mean of its filled 8-neighbours
// in the same region. Rings stop after kDilationRings, which covers the gutters between charts
// (texels further out are never sampled).
void plan_dilation(const Layout& layout, TexelSet& ts) {
  const int w = ts.width, h = ts.height;
  const std::vector<int32_t> region = region_image(layout);
  std::vector<uint8_t> filled(ts.valid.begin(), ts.valid.end());
  std::vector<size_t> ring;
  for (int pass = 0; pass < kDilationRings; ++pass) {
    ring.clear();
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * size_t(w) + size_t(x);
        if (filled[i] || region[i] < 0) continue;
        const uint32_t first = static_cast<uint32_t>(ts.fill_sources.size());
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
            const size_t j = size_t(ny) * size_t(w) + size_t(nx);
            if (filled[j] && region[j] == region[i]) ts.fill_sources.push_back(uint32_t(j));
          }
        const uint32_t count = static_cast<uint32_t>(ts.fill_sources.size()) - first;
        if (count == 0) continue;
        ts.fill.push_back(TexelSet::Fill{uint32_t(i), first, count});
        ring.push_back(i);
      }
    if (ring.empty()) break;
    for (size_t i : ring) filled[i] = 1;
  }
}

void dilate(FloatImage& map, const TexelSet& ts) {
  const size_t ch = size_t(map.channels);
  for (const TexelSet::Fill& f : ts.fill) {
    const float inv = 1.0f / float(f.count);  // count >= 1 by construction
    for (size_t c = 0; c < ch; ++c) {
      float sum = 0.0f;
      for (uint32_t k = 0; k < f.count; ++k) sum += map.data[ts.fill_sources[f.first + k] * ch + c];
      map.data[size_t(f.texel) * ch + c] = sum * inv;
    }
  }
}

// Bilinear taps (texel index, weight) of a light-map UV, clamped to the map.
int bilinear_taps(const glm::vec2& uv, int w, int h, size_t idx[4], float wt[4]) {
  const float fx = uv.x * float(w) - 0.5f, fy = uv.y * float(h) - 0.5f;
  const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
  const float ax = fx - float(x0), ay = fy - float(y0);
  int n = 0;
  for (int k = 0; k < 4; ++k) {
    const int x = std::clamp(x0 + (k & 1), 0, w - 1), y = std::clamp(y0 + (k >> 1), 0, h - 1);
    idx[n] = size_t(y) * size_t(w) + size_t(x);
    wt[n] = ((k & 1) ? ax : 1 - ax) * ((k >> 1) ? ay : 1 - ay);
    ++n;
  }
  return n;
}

// Plans the seam stitching: a texel outside its chart (its centre in no triangle) within one texel
// of a cut edge, which bilinear filtering along the edge reads, takes the other chart's filtered
// value at the same point of the surface: the nearest edge point, moved across the edge as far as
// the texel lies outside it, which in the other chart is inside the triangle there. Filtering
// along the edge then mixes each chart's own texels with the other's data from beyond the edge,
// on both sides alike, and each pulled texel is a convex combination of others. (A least-squares
// projection that moved every tap by weighted differences made texels negative next to dark
// ones: -58 under texels of 80 on a small chart of the inn.)
void plan_seams(const Layout& layout, const std::vector<uint8_t>& inside, TexelSet& ts) {
  if (layout.seams.empty()) return;
  const int w = ts.width, h = ts.height;
  const glm::vec2 size{float(w), float(h)};
  std::map<uint32_t, std::vector<std::pair<uint32_t, float>>> pulls;  // ordered: deterministic
  auto side = [&](glm::vec2 a0, glm::vec2 a1, glm::vec2 a2, glm::vec2 b0, glm::vec2 b1,
                  glm::vec2 b2) {
    a0 *= size, a1 *= size, a2 *= size, b0 *= size, b1 *= size, b2 *= size;
    const float len_a = glm::length(a1 - a0), len_b = glm::length(b1 - b0);
    if (!(len_a > 0.0f) || !(len_b > 0.0f)) return;
    const glm::vec2 ua = (a1 - a0) / len_a, ub = (b1 - b0) / len_b;
    // Unit normals towards each triangle's inside; a triangle flat in UV has none.
    glm::vec2 na(-ua.y, ua.x), nb(-ub.y, ub.x);
    const float sa = glm::dot(na, a2 - a0), sb = glm::dot(nb, b2 - b0);
    if (sa == 0.0f || sb == 0.0f) return;
    if (sa < 0.0f) na = -na;
    if (sb < 0.0f) nb = -nb;
    const float scale = len_b / len_a;  // the charts' densities may differ (TEXCOORD_1)
    const glm::vec2 lo = glm::min(a0, a1) - 1.0f, hi = glm::max(a0, a1) + 1.0f;
    for (int y = std::max(0, int(std::floor(lo.y))); y <= std::min(h - 1, int(hi.y)); ++y)
      for (int x = std::max(0, int(std::floor(lo.x))); x <= std::min(w - 1, int(hi.x)); ++x) {
        const size_t i = ts.index(x, y);
        if (inside[i]) continue;
        const glm::vec2 c(float(x) + 0.5f, float(y) + 0.5f);
        const float across = glm::dot(c - a0, na);  // < 0: beyond the edge, outside the triangle
        if (!(across < 0.0f)) continue;
        const float f = std::clamp(glm::dot(c - a0, ua), 0.0f, len_a);
        const glm::vec2 off = c - (a0 + ua * f);
        const float reach = std::max(std::abs(off.x), std::abs(off.y));
        if (!(reach < 1.0f)) continue;  // outside every bilinear footprint of the edge
        const glm::vec2 q =
            b0 + ub * ((f + glm::dot(off, ua)) * scale) - nb * (glm::dot(off, na) * scale);
        size_t taps[4];
        float tw[4];
        bilinear_taps(q / size, w, h, taps, tw);
        auto& list = pulls[uint32_t(i)];
        for (int k = 0; k < 4; ++k)
          if (tw[k] > 0.0f) list.push_back({uint32_t(taps[k]), tw[k] * (1.0f - reach)});
      }
  };
  for (const SeamEdge& e : layout.seams) {
    side(e.a0, e.a1, e.a2, e.b0, e.b1, e.b2);
    side(e.b0, e.b1, e.b2, e.a0, e.a1, e.a2);
  }
  for (const auto& [texel, list] : pulls) {
    float total = 0.0f;
    for (const auto& [src, wt] : list) total += wt;
    if (!(total > 0.0f)) continue;
    ts.seam.push_back(
        TexelSet::Fill{texel, uint32_t(ts.seam_sources.size()), uint32_t(list.size())});
    for (const auto& [src, wt] : list) {
      ts.seam_sources.push_back(src);
      ts.seam_weights.push_back(wt / total);
    }
  }
}

// Applies the seam plan kSeamPasses times, each pass from the map before it (every new value a
// convex combination of old ones): linear, so finalizing the maps of a recomposition equals
// recomposing finalized maps, and never outside the range of the values it mixes.
void stitch(FloatImage& map, const TexelSet& ts) {
  if (ts.seam.empty()) return;
  const size_t ch = size_t(map.channels);
  std::vector<float> next(ts.seam.size() * ch);
  for (int pass = 0; pass < kSeamPasses; ++pass) {
    for (size_t k = 0; k < ts.seam.size(); ++k) {
      const TexelSet::Fill& f = ts.seam[k];
      for (size_t c = 0; c < ch; ++c) {
        float v = 0.0f;
        for (uint32_t j = 0; j < f.count; ++j)
          v += ts.seam_weights[f.first + j] * map.data[ts.seam_sources[f.first + j] * ch + c];
        next[k * ch + c] = v;
      }
    }
    for (size_t k = 0; k < ts.seam.size(); ++k)
      for (size_t c = 0; c < ch; ++c)
        map.data[size_t(ts.seam[k].texel) * ch + c] = next[k * ch + c];
  }
}

}  // namespace

TexelSet build_texels(const Scene& scene, const Layout& layout, const Tracer* tracer) {
  TexelSet ts;
  ts.width = layout.width;
  ts.height = layout.height;
  const size_t n = size_t(layout.width) * size_t(layout.height);
  ts.position.assign(n, glm::vec3(0.0f));
  ts.normal.assign(n, glm::vec3(0.0f, 0.0f, 1.0f));
  ts.albedo.assign(n, glm::vec3(0.0f));
  ts.valid.assign(n, 0);
  ts.mesh.assign(n, -1);
  ts.region.assign(n, -1);
  std::vector<Candidate> best(n);
  const int threads = worker_count(0);
  // Regions own disjoint rectangles, so they rasterize in parallel without sharing a texel.
  parallel_for(static_cast<int>(layout.regions.size()), threads,
               [&](int r) { rasterize_region(scene, layout, r, ts, best); });
  if (tracer) push_out(*tracer, layout, ts, threads);
  plan_dilation(layout, ts);
  std::vector<uint8_t> inside(n, 0);
  for (size_t i = 0; i < n; ++i) inside[i] = best[i].distance <= kInside ? 1 : 0;
  plan_seams(layout, inside, ts);
  return ts;
}

void finalize_map(FloatImage& map, const Scene& scene, const Layout& layout,
                  const TexelSet& texels) {
  (void)scene;
  (void)layout;
  dilate(map, texels);
  stitch(map, texels);
}

void finalize_maps(BakedMaps& maps, const Scene& scene, const Layout& layout,
                   const TexelSet& texels, Progress* progress) {
  // Every map whole, bounce light included, whether or not the pack stores its bounce part on
  // the indirect map: the light map then holds the difference (map_split.h), and the block
  // images need none (block_image() fills their rings).
  // Direct parts too (ShadowMap::direct): finalizing is linear, so the bounce part the pack
  // takes as the difference is the finalized map's.
  std::vector<FloatImage*> all;
  auto add = [&](FloatImage& m) {
    if (!m.data.empty()) all.push_back(&m);
  };
  all.push_back(&maps.base);
  add(maps.base_direct);
  for (FloatImage& c : maps.contribution) all.push_back(&c);
  for (FloatImage& c : maps.contribution_direct) add(c);
  for (ShadowMap& s : maps.shadows) all.push_back(&s.map), add(s.direct);
  for (PairCorrectionMap& p : maps.pair_corrections) all.push_back(&p.map), add(p.direct);
  for (StaticShadowMap& s : maps.static_shadows) all.push_back(&s.map), add(s.direct);
  // Panes with a light-map-sized map (else their block image alone, PaneMap), dense while they
  // are finalized.
  std::vector<TiledImage*> tiled;
  for (PaneMap& p : maps.panes)
    if (!p.map.empty()) tiled.push_back(&p.map);
  // Each map alone: both cores.
  parallel_for(int(all.size() + tiled.size()), worker_count(0), [&](int i) {
    if (size_t(i) < all.size()) {
      finalize_map(*all[size_t(i)], scene, layout, texels);
    } else {
      TiledImage& t = *tiled[size_t(i) - all.size()];
      FloatImage m = t.dense();
      finalize_map(m, scene, layout, texels);
      t = TiledImage(m);
    }
    if (progress) progress->advance();
  });
}

}  // namespace lightpatch::cooker
