#include "indirect/gather.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <unordered_map>

#include "direct_light.h"
#include "sample_hash.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

namespace {

constexpr float kPi = 3.14159265358979f;
// Texels of one block and chart whose normals are within this cosine share a coarse texel; the
// same cone decides which coarse texel of a neighbouring block continues a surface.
constexpr float kSameSurfaceCos = 0.7f;
// Objects a gather ray records before its static hit (more are ignored: they hide the rest).
constexpr int kMaxCrossed = 8;
// A texel whose gather rays hit the back of a surface more often than this lies inside solid
// geometry (where walls meet, under a wall): its rays would see the world beyond the wall, so
// they are dropped, and rays that land on it are given to the nearest texel that is not buried.
constexpr float kBuriedFraction = 0.1f;
// Marks a ray's hit on the back of a surface while the rays are traced.
constexpr uint32_t kBackFace = 0xFFFFFFFEu;
// The fewest rays a coarse texel gathers with in the series' later bounces.
constexpr int kMinLevelRays = 16;
// block_touches(): how far its probes reach (blocks), how many leave each texel, and the share
// of them that must be blocked. Chosen on the test room at preview (docs/accuracy.md, section
// (m)): 0.5 and 1 block, or a share of 0.2, split fewer blocks and left more of the blur.
constexpr float kContactReach = 2.0f;
constexpr int kContactProbes = 8;
constexpr float kContactFraction = 0.1f;
// Only 2x2 blocks split (preview's; production gathers per texel): a 4x4 block split is 16
// gathers for one, which would undo what draft's and the coarser indirect maps' blocks save.
constexpr int kContactLevel = 2;
// A split texel traces 1/kFineRayDivisor of a coarse texel's rays (fine_ray_count): a split 2x2
// block costs two blocks. Chosen on the test room, the thin panel and the small inn at preview
// (docs/accuracy.md, section (m)): all the rays cost twice as much for no gain on the inn, a
// quarter gained less on the inn than it cost in noise.
constexpr int kFineRayDivisor = 2;

// Union-find over fine texels: charts are the connected valid texels of one region.
struct Charts {
  std::vector<uint32_t> parent;
  uint32_t find(uint32_t i) {
    while (parent[i] != i) {
      parent[i] = parent[parent[i]];
      i = parent[i];
    }
    return i;
  }
  void join(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

void basis(const glm::vec3& w, glm::vec3& t, glm::vec3& b) {
  const float sign = std::copysign(1.0f, w.z);
  const float a = -1.0f / (sign + w.z);
  const float c = w.x * w.y * a;
  t = glm::vec3(1.0f + sign * w.x * w.x * a, sign * c, -sign * w.x);
  b = glm::vec3(c, sign + w.y * w.y * a, -w.y);
}

// Cosine-distributed direction about n for the unit square point (u, v).
glm::vec3 cosine_dir(const glm::vec3& n, float u, float v) {
  const float r = std::sqrt(u), phi = 2.0f * kPi * v;
  glm::vec3 t, b;
  basis(n, t, b);
  const float z = std::sqrt(std::max(0.0f, 1.0f - u));
  return glm::normalize(t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * z);
}

// Which of a coarse texel's mc members lie inside solid geometry: more than kBuriedFraction of
// their rays (ray k leaves member k % mc) hit the back of a surface. `hits`: the n_rays raw hits
// (fine texels, kBackFace). Out: buried[m], 0 or 1.
void buried_members(const uint32_t* hits, int n_rays, uint32_t mc, std::vector<uint32_t>& back,
                    std::vector<uint32_t>& total, std::vector<uint8_t>& buried) {
  back.assign(mc, 0);
  total.assign(mc, 0);
  for (int k = 0; k < n_rays; ++k) {
    ++total[uint32_t(k) % mc];
    back[uint32_t(k) % mc] += hits[k] == kBackFace ? 1 : 0;
  }
  buried.assign(mc, 0);
  for (uint32_t m = 0; m < mc; ++m)
    buried[m] = float(back[m]) > kBuriedFraction * float(total[m]) ? 1 : 0;
}

// A coarse texel's near rays (in ray order), less those of buried members, as NearHits: those
// that land on one texel keep the points of the first kNearPerTexel of them in ray order, each
// standing for an equal share of them. A low-discrepancy sequence's first points are its
// best-spread subset; every n-th of them, as before, is a sequence of its own whose step can sit
// near a lattice (with the rays' points and directions drawn as one sequence, gather_ray, that
// took the slab of bounce_quality_test from 14.6 to 20.8 % and its bias from -4.5 to -9.5 %;
// the first ones 14.0 % and -6.4 %). Appended to `out` with the coarse texel c.
void add_near_hits(uint32_t c, const std::vector<NearHit>& rays, const std::vector<uint8_t>& buried,
                   uint32_t mc, std::vector<uint32_t>& order,
                   std::vector<std::pair<uint32_t, NearHit>>& out) {
  order.clear();
  for (uint32_t i = 0; i < rays.size(); ++i)
    if (!buried[rays[i].ray % mc]) order.push_back(i);
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return rays[a].fine < rays[b].fine; });
  const uint32_t per = uint32_t(kNearPerTexel);
  for (size_t a = 0; a < order.size();) {
    size_t b = a;
    while (b < order.size() && rays[order[b]].fine == rays[order[a]].fine) ++b;
    const uint32_t n = uint32_t(b - a), keep = std::min(n, per);
    for (uint32_t j = 0; j < keep; ++j) {
      NearHit h = rays[order[a + j]];
      h.count = (j + 1) * n / keep - j * n / keep;
      out.push_back({c, h});
    }
    a = b;
  }
}

}  // namespace

std::vector<TexelSurface> texel_surfaces(const TexelSet& texels) {
  std::vector<TexelSurface> out(texels.valid.size());
  for (size_t t = 0; t < out.size(); ++t)
    if (texels.valid[t]) out[t] = {texels.mesh[t], texels.normal[t]};
  return out;
}

uint32_t texel_under(const Layout& layout, const TexelSet& texels, const Hit& h) {
  const MeshLayout& ml = layout.meshes[size_t(h.mesh)];
  const size_t t3 = size_t(h.triangle) * 3;
  if (t3 + 2 >= ml.indices.size()) return kNoTexel;
  const glm::vec2 uv = (1.0f - h.u - h.v) * ml.uv[ml.indices[t3]] +
                       h.u * ml.uv[ml.indices[t3 + 1]] + h.v * ml.uv[ml.indices[t3 + 2]];
  const float fx = uv.x * float(texels.width), fy = uv.y * float(texels.height);
  const int x0 = std::clamp(int(std::floor(fx)), 0, texels.width - 1);
  const int y0 = std::clamp(int(std::floor(fy)), 0, texels.height - 1);
  return uint32_t(texels.index(x0, y0));
}

uint32_t texel_of_hit(const TexelSet& texels, const std::vector<TexelSurface>& surfaces,
                      const Hit& h, const glm::vec3& point, uint32_t under) {
  if (under == kNoTexel) return kNoTexel;
  const int x0 = int(under % uint32_t(texels.width)), y0 = int(under / uint32_t(texels.width));
  // The texel must sample this side of this surface: a chart of the same mesh beside it in the
  // page (the other face of a wall slab) must not lend it its light.
  auto same_surface = [&](size_t t) {
    return surfaces[t].mesh == h.mesh &&
           glm::dot(surfaces[t].normal, h.geometric_normal) > kSameSurfaceCos - 0.2f;
  };
  const size_t t0 = texels.index(x0, y0);
  if (same_surface(t0)) return uint32_t(t0);
  uint32_t best = kNoTexel;
  float best_d2 = std::numeric_limits<float>::max();
  for (int dy = -2; dy <= 2; ++dy) {
    for (int dx = -2; dx <= 2; ++dx) {
      const int x = x0 + dx, y = y0 + dy;
      if (x < 0 || y < 0 || x >= texels.width || y >= texels.height) continue;
      const size_t t = texels.index(x, y);
      if (!same_surface(t)) continue;
      const glm::vec3 d = texels.position[t] - point;
      const float d2 = glm::dot(d, d);
      if (d2 < best_d2) {
        best_d2 = d2;
        best = uint32_t(t);
      }
    }
  }
  return best;
}

namespace {

// Hits on texel sets made without a layout (tests' hand-made grids): the nearest valid texel to
// the hit point whose normal faces the same way, within two texel spacings.
class TexelLocator {
 public:
  explicit TexelLocator(const TexelSet& texels) : texels_(texels) {
    std::vector<float> gaps;
    for (int y = 0; y < texels.height; ++y)
      for (int x = 0; x + 1 < texels.width; ++x) {
        const size_t t = texels.index(x, y);
        if (texels.valid[t] && texels.valid[t + 1])
          gaps.push_back(glm::length(texels.position[t + 1] - texels.position[t]));
      }
    if (!gaps.empty()) {
      std::nth_element(gaps.begin(), gaps.begin() + long(gaps.size() / 2), gaps.end());
      spacing_ = std::max(gaps[gaps.size() / 2], 1e-12f);
    }
    cell_ = 2.0f * spacing_;
    for (size_t t = 0; t < texels.valid.size(); ++t)
      if (texels.valid[t]) cells_[key(cell_of(texels.position[t]))].push_back(uint32_t(t));
  }

  uint32_t find(const glm::vec3& p, const glm::vec3& n) const {
    const glm::ivec3 c = cell_of(p);
    uint32_t best = kNoTexel;
    float best_d2 = cell_ * cell_;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          auto it = cells_.find(key(c + glm::ivec3(dx, dy, dz)));
          if (it == cells_.end()) continue;
          for (uint32_t t : it->second) {
            if (glm::dot(texels_.normal[t], n) < 0.5f) continue;
            const glm::vec3 d = texels_.position[t] - p;
            const float d2 = glm::dot(d, d);
            if (d2 < best_d2) {
              best_d2 = d2;
              best = t;
            }
          }
        }
    return best;
  }

 private:
  glm::ivec3 cell_of(const glm::vec3& p) const { return glm::ivec3(glm::floor(p / cell_)); }
  static int64_t key(const glm::ivec3& c) {
    return (int64_t(c.x) * 73856093) ^ (int64_t(c.y) * 19349663) ^ (int64_t(c.z) * 83492791);
  }
  const TexelSet& texels_;
  float spacing_ = 1.0f, cell_ = 2.0f;
  std::unordered_map<int64_t, std::vector<uint32_t>> cells_;
};

// Two surface points (pa, normal na; pb, nb) see each other past static geometry, both lifted off
// their surfaces by the tracer's epsilon.
bool surfaces_see(const Tracer& tracer, const glm::vec3& pa, const glm::vec3& na,
                  const glm::vec3& pb, const glm::vec3& nb) {
  const float eps = tracer.epsilon();
  const glm::vec3 a = pa + na * eps, d = pb + nb * eps - a;
  const float len = glm::length(d);
  if (!(len > 2.0f * eps)) return true;
  return !tracer.occluded_static(a, d / len, eps, len - eps);
}

// Whether a block's texels have other geometry within kContactReach blocks: a crate's side where
// it stands on the floor, a wall behind a thin panel. There bounce light changes within a block
// (the floor in front of the crate lies in its shadow), which one value per block and its
// magnification blur into a bright band. kContactProbes short any-hit rays per texel, cosine-
// distributed, through static geometry and every object (the grid is one for every state);
// the block touches when at least kContactFraction of them are blocked.
bool block_touches(const Tracer& tracer, const TexelSet& texels,
                   const std::vector<uint32_t>& chart_of, const std::vector<uint32_t>& block, int k,
                   std::vector<Ray>& probes, std::vector<uint8_t>& blocked) {
  // The block's texel spacing: the largest gap between one of its texels and the next one of
  // the same chart in the page, across or down.
  float spacing = 0.0f;
  for (uint32_t a : block) {
    const size_t x = a % size_t(texels.width);
    for (const size_t b : {size_t(a) + 1, size_t(a) + size_t(texels.width)}) {
      if (b >= texels.valid.size() || (b == size_t(a) + 1 && x + 1 == size_t(texels.width)) ||
          !texels.valid[b] || chart_of[b] != chart_of[a])
        continue;
      spacing = std::max(spacing, glm::length(texels.position[a] - texels.position[b]));
    }
  }
  if (!(spacing > 0.0f)) return false;
  const float eps = tracer.epsilon();
  const float reach = kContactReach * float(k) * spacing;
  if (!(reach > 2.0f * eps)) return false;
  probes.clear();
  for (uint32_t t : block) {
    const auto [o1, o2] = rotation_of(sample_hash(0x636f6e74616374ull, t, 0, 0));
    const glm::vec3 n = texels.normal[t];
    for (int i = 0; i < kContactProbes; ++i) {
      const glm::vec3 d =
          cosine_dir(n, float(kronecker(o1, kR2[0], i)), float(kronecker(o2, kR2[1], i)));
      probes.push_back(Ray{texels.position[t] + n * eps, eps, d, reach});
    }
  }
  blocked.resize(probes.size());
  tracer.occluded_many(probes.data(), int(probes.size()), blocked.data());
  size_t hits = 0;
  for (uint8_t b : blocked) hits += b;
  return float(hits) >= kContactFraction * float(probes.size());
}

}  // namespace

CoarseGrid build_coarse_grid(const TexelSet& texels, int level, const Tracer* tracer, int threads,
                             bool split_contacts) {
  auto sees = [&](const glm::vec3& pa, const glm::vec3& na, const glm::vec3& pb,
                  const glm::vec3& nb) { return !tracer || surfaces_see(*tracer, pa, na, pb, nb); };
  CoarseGrid g;
  g.level = std::max(1, level);
  const int k = g.level;
  const int w = texels.width, h = texels.height;
  g.width = (w + k - 1) / k;
  g.height = (h + k - 1) / k;
  const size_t n = size_t(w) * size_t(h);
  Charts charts;
  charts.parent.resize(n);
  std::iota(charts.parent.begin(), charts.parent.end(), 0u);
  auto same = [&](size_t a, size_t b) {
    return texels.valid[a] && texels.valid[b] && texels.region[a] == texels.region[b];
  };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t t = texels.index(x, y);
      if (x + 1 < w && same(t, t + 1)) charts.join(uint32_t(t), uint32_t(t + 1));
      if (y + 1 < h && same(t, t + size_t(w))) charts.join(uint32_t(t), uint32_t(t + size_t(w)));
    }
  }
  // Chart roots, resolved once (find() compresses paths, so it is not shared across threads).
  std::vector<uint32_t> chart_of(n);
  for (size_t t = 0; t < n; ++t) chart_of[t] = charts.find(uint32_t(t));
  // Greedy clusters per block, block rows in parallel: a texel joins the first coarse texel of
  // its chart whose seed normal is within the cone and which it sees, else seeds a new one. In a
  // block that touches other geometry (block_touches), every texel is a coarse texel of its own.
  std::vector<std::vector<std::vector<uint32_t>>> row_groups(size_t(g.height));
  std::vector<std::vector<uint32_t>> row_group_block(size_t(g.height));
  std::vector<std::vector<uint8_t>> row_group_fine(size_t(g.height));
  parallel_for(g.height, threads, [&](int by) {
    std::vector<uint32_t> block, seeds;
    std::vector<Ray> probes;
    std::vector<uint8_t> blocked;
    for (int bx = 0; bx < g.width; ++bx) {
      block.clear();
      for (int y = by * k; y < std::min(h, (by + 1) * k); ++y)
        for (int x = bx * k; x < std::min(w, (bx + 1) * k); ++x)
          if (texels.valid[texels.index(x, y)]) block.push_back(uint32_t(texels.index(x, y)));
      seeds.clear();
      const size_t first = row_groups[size_t(by)].size();
      const bool split = k == kContactLevel && tracer && split_contacts && !block.empty() &&
                         block_touches(*tracer, texels, chart_of, block, k, probes, blocked);
      for (uint32_t t : block) {
        size_t j = 0;
        if (split) j = seeds.size();
        for (; j < seeds.size(); ++j) {
          const uint32_t sd = seeds[j];
          if (chart_of[sd] == chart_of[t] &&
              glm::dot(texels.normal[sd], texels.normal[t]) >= kSameSurfaceCos &&
              sees(texels.position[sd], texels.normal[sd], texels.position[t], texels.normal[t]))
            break;
        }
        if (j == seeds.size()) {
          seeds.push_back(t);
          row_groups[size_t(by)].emplace_back();
          row_group_block[size_t(by)].push_back(
              uint32_t(size_t(by) * size_t(g.width) + size_t(bx)));
          row_group_fine[size_t(by)].push_back(split ? 1 : 0);
        }
        row_groups[size_t(by)][first + j].push_back(t);
      }
    }
  });
  g.coarse_of.assign(n, kNoTexel);
  g.block_offset.assign(size_t(g.width) * size_t(g.height) + 1, 0);
  g.member_offset.push_back(0);
  size_t next_block = 0;
  for (int by = 0; by < g.height; ++by) {
    for (size_t i = 0; i < row_groups[size_t(by)].size(); ++i) {
      const std::vector<uint32_t>& grp = row_groups[size_t(by)][i];
      const uint32_t b = row_group_block[size_t(by)][i];
      while (next_block <= b) g.block_offset[next_block++] = uint32_t(g.chart.size());
      const uint32_t c = uint32_t(g.chart.size());
      glm::vec3 p(0.0f), nn(0.0f), a(0.0f);
      for (uint32_t t : grp) {
        g.coarse_of[t] = c;
        g.members.push_back(t);
        p += texels.position[t];
        nn += texels.normal[t];
        a += texels.albedo[t];
      }
      const float m = float(grp.size());
      g.member_offset.push_back(uint32_t(g.members.size()));
      g.block_of.push_back(b);
      g.block_coarse.push_back(c);
      g.fine.push_back(row_group_fine[size_t(by)][i]);
      g.chart.push_back(chart_of[grp.front()]);
      g.position.push_back(p / m);
      const float len = glm::length(nn);
      g.normal.push_back(len > 0.0f ? nn / len : texels.normal[grp.front()]);
      g.albedo.push_back(a / m);
    }
  }
  while (next_block < g.block_offset.size())
    g.block_offset[next_block++] = uint32_t(g.chart.size());
  g.alive.assign(g.size(), 1);

  // Neighbour links.
  const size_t nc = g.size();
  g.links.assign(nc * size_t(CoarseGrid::kLinks), kNoTexel);
  parallel_for(int((nc + 255) / 256), threads, [&](int item) {
    for (size_t c = size_t(item) * 256; c < std::min(nc, size_t(item + 1) * 256); ++c) {
      const uint32_t b = g.block_of[c];
      const int bx = int(b % uint32_t(g.width)), by = int(b / uint32_t(g.width));
      for (int si = 0; si < CoarseGrid::kLinkSteps; ++si) {
        const int step = 1 << si;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            if (dx == 0 && dy == 0) continue;
            const int nx = bx + dx * step, ny = by + dy * step;
            if (nx < 0 || ny < 0 || nx >= g.width || ny >= g.height) continue;
            const size_t nb = size_t(ny) * size_t(g.width) + size_t(nx);
            // Of a split block's texels, the nearest within the cone continues the surface (its
            // mean normal alone would pick one at random on a flat one).
            uint32_t best = kNoTexel;
            float best_cos = kSameSurfaceCos, best_d2 = std::numeric_limits<float>::max();
            for (uint32_t i = g.block_offset[nb]; i < g.block_offset[nb + 1]; ++i) {
              const uint32_t q = g.block_coarse[i];
              if (g.chart[q] != g.chart[c]) continue;
              const float d = glm::dot(g.normal[q], g.normal[c]);
              if (g.fine[q]) {
                const glm::vec3 e = g.position[q] - g.position[c];
                if (d >= kSameSurfaceCos && glm::dot(e, e) < best_d2) {
                  best_d2 = glm::dot(e, e);
                  best = q;
                }
              } else if (d >= best_cos) {
                best_cos = d;
                best = q;
              }
            }
            if (best != kNoTexel &&
                !sees(g.position[c], g.normal[c], g.position[best], g.normal[best]))
              best = kNoTexel;
            g.links[c * size_t(CoarseGrid::kLinks) + size_t(si) * 8 +
                    size_t(CoarseGrid::direction(dx, dy))] = best;
          }
        }
      }
    }
  });
  return g;
}

int fine_ray_count(int rays) {
  return std::min(rays, std::max(kMinLevelRays, rays / kFineRayDivisor));
}

GatherOperator build_gather(const Scene& scene, const Layout& layout, const TexelSet& texels,
                            const Tracer& tracer, int level, const GatherOptions& options) {
  GatherOperator op;
  const uint64_t rays0 = tracer.rays_traced();  // the grid's probes and sight lines included
  op.grid = build_coarse_grid(texels, level, &tracer, options.threads, options.split_contacts);
  const CoarseGrid& g = op.grid;
  const size_t nc = g.size();
  const int n_rays = std::max(1, options.rays);
  op.rays = n_rays;
  op.hit.assign(nc * size_t(n_rays), kNoTexel);
  const float eps = tracer.epsilon();
  const float extent = 1.5f * (scene.scale() > 0.0f ? scene.scale() : 1.0f);
  // Low-discrepancy directions per coarse texel: the R2 sequence, rotated per texel (Cranley-
  // Patterson) so neighbours do not share a pattern. The points the rays leave from, over the
  // texel's footprint: R4's last two dimensions at the same index, so that (point, direction) is
  // one low-discrepancy sequence of four dimensions (sample_hash.h). A point from
  // footprint_point's R2 of the same index made the direction a function of the point: the
  // texel's estimate then missed most of its four dimensions and kept an error that did not fall
  // with more rays (docs/accuracy.md, section (l)).
  // Work items are block rows: each a contiguous range of coarse texels.
  std::vector<uint32_t> row_first(size_t(g.height) + 1, 0);
  for (int by = 0; by <= g.height; ++by)
    row_first[size_t(by)] = g.block_offset[size_t(by) * size_t(g.width)];
  std::vector<std::vector<Crossing>> row_crossings(size_t(g.height));
  std::vector<std::vector<CrossingHit>> row_hits(size_t(g.height));
  std::vector<std::vector<uint32_t>> row_counts(size_t(g.height));
  // Near hits of each block row, with their coarse texel (kept in coarse and ray order).
  std::vector<std::vector<std::pair<uint32_t, NearHit>>> row_near(size_t(g.height));
  // Texel sets made without a layout (tests) find hits by position.
  std::unique_ptr<TexelLocator> locator;
  std::vector<TexelSurface> surfaces;
  if (layout.meshes.size() != scene.meshes.size())
    locator = std::make_unique<TexelLocator>(texels);
  else
    surfaces = texel_surfaces(texels);
  // While tracing, hits are fine texels (or kBackFace); resolved to coarse texels after.
  auto to_fine = [&](const Hit& h, const glm::vec3& origin, const glm::vec3& dir, uint32_t under) {
    if (glm::dot(dir, h.geometric_normal) > 0.0f) return kBackFace;
    const glm::vec3 point = origin + dir * h.t;
    return locator ? locator->find(point, h.geometric_normal)
                   : texel_of_hit(texels, surfaces, h, point, under);
  };
  // Ray k of coarse texel c, whose hash offsets are (o1, o2): traced below, and again for the few
  // that land on a buried texel.
  auto gather_ray = [&](uint32_t c, int k, double o1, double o2) {
    const uint32_t m0 = g.member_offset[c], mc = g.member_count(c);
    const uint32_t t = g.members[m0 + uint32_t(k) % mc];
    const double u = kronecker(o1, kR2[0], k), v = kronecker(o2, kR2[1], k);
    const glm::vec3 n = texels.normal[t];
    glm::vec3 p = texels.position[t];
    if (options.footprints) {
      const auto [r1, r2] = rotation_of(sample_hash(options.seed, t, 0x7061746368ull, 0));
      p = footprint_point_at((*options.footprints)[t], p, kronecker(r1, kR4Last[0], k),
                             kronecker(r2, kR4Last[1], k));
    }
    return Ray{p + n * eps, eps, cosine_dir(n, float(u), float(v)), extent};
  };
  auto ray_offsets = [&](uint32_t c) {
    return rotation_of(sample_hash(options.seed, c, 0x6761746865ull, 0));
  };
  // A texel split from a block at a contact traces the first op.traced_rays(c) of its rays; the
  // rest stay unused (kNoTexel as assigned above, out of its weights).
  const bool objects = !scene.objects.empty();
  // The widest texel spacing of the page: a hit farther than kNearHitSpacings of it is near no
  // texel, decided without loading the hit texel's footprint (a cache miss on nearly every ray:
  // most rays cross the room).
  float max_spacing = 0.0f;
  if (options.footprints)
    for (const TexelFootprint& f : *options.footprints)
      max_spacing = std::max({max_spacing, glm::length(f.u), glm::length(f.v)});
  parallel_for(g.height, options.threads, [&](int by) {
    std::vector<Crossing>& cr = row_crossings[size_t(by)];
    std::vector<CrossingHit>& ch = row_hits[size_t(by)];
    std::vector<uint32_t>& counts = row_counts[size_t(by)];
    std::vector<std::pair<uint32_t, NearHit>>& near = row_near[size_t(by)];
    std::vector<NearHit> near_rays;  // this coarse texel's
    std::vector<uint32_t> back, total, order;
    std::vector<uint8_t> member_buried;
    std::vector<Ray> rays(static_cast<size_t>(n_rays)), to_static(static_cast<size_t>(n_rays));
    std::vector<Hit> first(static_cast<size_t>(n_rays)), object(static_cast<size_t>(n_rays));
    std::vector<uint32_t> under(static_cast<size_t>(n_rays), kNoTexel);
    for (uint32_t c = row_first[size_t(by)]; c < row_first[size_t(by) + 1]; ++c) {
      const uint32_t m0 = g.member_offset[c], mc = g.member_count(c);
      const auto [o1, o2] = ray_offsets(c);
      uint32_t crossings_here = 0;
      const int traced = op.traced_rays(c);
      // One texel's rays leave a few nearby points: coherent, so they are traced as packets,
      // first through static geometry, then each up to its static hit through the objects alone
      // (a scene of their own, small). Tracing on through the whole scene after each object hit
      // cost a semi-dynamic cook's gather a third more than a static one's, and lost the static
      // surface an object rests on (the floor under a crate, hit where the crate's bottom is).
      for (int k = 0; k < traced; ++k) rays[size_t(k)] = gather_ray(c, k, o1, o2);
      tracer.intersect_many(rays.data(), traced, first.data(), false);
      if (objects) {
        for (int k = 0; k < traced; ++k) {
          to_static[size_t(k)] = rays[size_t(k)];
          if (first[size_t(k)].hit) to_static[size_t(k)].tmax = first[size_t(k)].t;
        }
        tracer.intersect_objects_many(to_static.data(), traced, object.data());
      }
      // The texels under the hits are far apart in memory: fetched for all rays at once, their
      // cache misses overlap instead of stalling ray after ray.
      if (!locator) {
        for (int k = 0; k < traced; ++k) {
          under[size_t(k)] =
              first[size_t(k)].hit ? texel_under(layout, texels, first[size_t(k)]) : kNoTexel;
          if (under[size_t(k)] != kNoTexel) __builtin_prefetch(&surfaces[under[size_t(k)]]);
        }
      }
      for (int k = 0; k < traced; ++k) {
        const glm::vec3 origin = rays[size_t(k)].origin, dir = rays[size_t(k)].dir;
        Crossing rec{uint32_t(k), uint32_t(ch.size()), 0};
        const Hit& s = first[size_t(k)];
        const uint32_t static_hit = s.hit ? to_fine(s, origin, dir, under[size_t(k)]) : kNoTexel;
        const float static_t = s.hit ? s.t : 0.0f;
        // The objects before the static hit, nearest first, each once.
        Hit h = objects ? object[size_t(k)] : Hit{};
        for (int guard = 0; h.hit && guard <= kMaxCrossed * 2; ++guard) {
          const int o = scene.meshes[size_t(h.mesh)].object;
          bool seen = false;
          for (uint32_t i = rec.first; i < rec.first + rec.count; ++i) seen |= ch[i].object == o;
          if (!seen && rec.count < uint32_t(kMaxCrossed)) {
            const uint32_t u = locator ? kNoTexel : texel_under(layout, texels, h);
            ch.push_back({o, to_fine(h, origin, dir, u)});
            ++rec.count;
          }
          h = tracer.intersect_objects(origin, dir, h.t + eps, to_static[size_t(k)].tmax);
        }
        op.hit[size_t(c) * size_t(n_rays) + size_t(k)] = static_hit;
        // A receiver on a mesh that stops no ray (a flame, a bulb) lends its light to no other
        // texel, and no player sees it lit by bounce light: its rays keep the cache.
        if (options.footprints && rec.count == 0 && static_hit != kNoTexel &&
            static_hit != kBackFace && static_t < kNearHitSpacings * max_spacing) {
          const TexelFootprint& f = (*options.footprints)[static_hit];
          const float spacing = std::max(glm::length(f.u), glm::length(f.v));
          const int32_t from =
              texels.mesh.empty() ? -1 : texels.mesh[g.members[m0 + uint32_t(k) % mc]];
          if (static_t < kNearHitSpacings * spacing &&
              (from < 0 || scene.meshes[size_t(from)].cast_shadows))
            near_rays.push_back({origin + dir * static_t, uint32_t(k), static_hit, 1});
        }
        if (rec.count > 0) {
          cr.push_back(rec);
          ++crossings_here;
        }
      }
      counts.push_back(crossings_here);
      // Near rays merged now, while they are one texel's: kept ray by ray, production's ran to
      // gigabytes on the full inn.
      if (!near_rays.empty()) {
        buried_members(op.hit.data() + size_t(c) * size_t(n_rays), traced, mc, back, total,
                       member_buried);
        add_near_hits(c, near_rays, member_buried, mc, order, near);
        near_rays.clear();
      }
    }
  });
  // Buried texels, then every hit as a coarse texel.
  std::vector<uint8_t> buried(texels.valid.size(), 0);
  parallel_for(int((nc + 255) / 256), options.threads, [&](int item) {
    std::vector<uint32_t> back, total;
    std::vector<uint8_t> member_buried;
    for (size_t c = size_t(item) * 256; c < std::min(nc, size_t(item + 1) * 256); ++c) {
      const uint32_t m0 = g.member_offset[c], mc = g.member_count(uint32_t(c));
      buried_members(op.hit.data() + c * size_t(n_rays), op.traced_rays(uint32_t(c)), mc, back,
                     total, member_buried);
      for (uint32_t m = 0; m < mc; ++m)
        if (member_buried[m]) buried[g.members[m0 + m]] = 1;
    }
  });
  // Calls visit(t, dx, dy) for each texel within two of buried texel f in the page that is of
  // its surface and not buried.
  auto for_each_unburied = [&](uint32_t f, auto&& visit) {
    const int x0 = int(f % uint32_t(texels.width)), y0 = int(f / uint32_t(texels.width));
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) {
        const int x = x0 + dx, y = y0 + dy;
        if (x < 0 || y < 0 || x >= texels.width || y >= texels.height) continue;
        const size_t t = texels.index(x, y);
        if (!texels.valid[t] || buried[t] || texels.mesh[t] != texels.mesh[f] ||
            glm::dot(texels.normal[t], texels.normal[f]) < kSameSurfaceCos)
          continue;
        visit(uint32_t(t), dx, dy);
      }
  };
  // A static hit on a buried texel (its sample point inside solid geometry: a ceiling texel under
  // a partition) moves to the texel of the same surface nearest to the hit point that is not
  // buried and that the hit point sees. Nearest in the page alone gave a hit in one room the texel
  // beyond the partition, lit by the other room's lamp. The ray is traced again for its point:
  // few rays land on buried texels, and none is stored.
  auto resolve_buried = [&](uint32_t f, const Ray& ray) {
    const Hit h = tracer.intersect(ray.origin, ray.dir, ray.tmin, ray.tmax, false);
    if (!h.hit) return kNoTexel;
    const glm::vec3 point = ray.origin + ray.dir * h.t;
    const glm::vec3 up =
        glm::dot(h.geometric_normal, ray.dir) < 0.0f ? h.geometric_normal : -h.geometric_normal;
    std::pair<float, uint32_t> near[25];
    int count = 0;
    for_each_unburied(f, [&](uint32_t t, int, int) {
      const glm::vec3 d = texels.position[t] - point;
      near[count++] = {glm::dot(d, d), t};
    });
    std::sort(near, near + count);
    for (int i = 0; i < count; ++i) {
      const uint32_t t = near[i].second;
      if (surfaces_see(tracer, point, up, texels.position[t], texels.normal[t]))
        return g.coarse_of[t];
    }
    return kNoTexel;
  };
  // An object's hit on a buried texel moves to the nearest such texel in the page.
  auto resolve = [&](uint32_t f) {
    if (f == kNoTexel || f == kBackFace) return kNoTexel;
    if (!buried[f]) return g.coarse_of[f];
    uint32_t best = kNoTexel;
    int best_d2 = 1 << 30;
    for_each_unburied(f, [&](uint32_t t, int dx, int dy) {
      if (dx * dx + dy * dy < best_d2) {
        best_d2 = dx * dx + dy * dy;
        best = t;
      }
    });
    return best == kNoTexel ? kNoTexel : g.coarse_of[best];
  };
  for (int l = 0; l < GatherOperator::kLevels; ++l) {
    op.level_rays[l] =
        l == 0 ? n_rays : std::min(n_rays, std::max(kMinLevelRays, n_rays >> (2 * l)));
    op.weight[l].assign(nc, 0.0f);
  }
  op.grid.alive.assign(nc, 0);
  parallel_for(g.height, options.threads, [&](int by) {
    std::vector<Crossing>& cr = row_crossings[size_t(by)];
    std::vector<CrossingHit>& ch = row_hits[size_t(by)];
    size_t next = 0;
    for (uint32_t c = row_first[size_t(by)]; c < row_first[size_t(by) + 1]; ++c) {
      const uint32_t m0 = g.member_offset[c], mc = g.member_count(c);
      const auto [o1, o2] = ray_offsets(c);
      uint32_t used[GatherOperator::kLevels] = {0, 0, 0};
      uint32_t* hits = op.hit.data() + size_t(c) * size_t(n_rays);
      const int traced = op.traced_rays(c);
      for (int k = 0; k < n_rays; ++k) {
        const bool drop = k >= traced || buried[g.members[m0 + uint32_t(k) % mc]] != 0;
        const uint32_t f = hits[k];
        if (drop)
          hits[k] = kNoTexel;
        else if (f != kNoTexel && f != kBackFace && buried[f])
          hits[k] = resolve_buried(f, gather_ray(c, k, o1, o2));
        else
          hits[k] = resolve(f);
        for (int l = 0; l < GatherOperator::kLevels; ++l)
          if (k < op.level_rays[l] && !drop) ++used[l];
      }
      for (int l = 0; l < GatherOperator::kLevels; ++l)
        op.weight[l][c] = used[l] > 0 ? 1.0f / float(used[l]) : 0.0f;
      const uint32_t count = row_counts[size_t(by)][c - row_first[size_t(by)]];
      for (size_t i = next; i < next + count; ++i) {
        const bool drop = buried[g.members[m0 + cr[i].ray % mc]] != 0;
        for (uint32_t j = cr[i].first; j < cr[i].first + cr[i].count; ++j)
          ch[j].coarse = drop ? kNoTexel : resolve(ch[j].coarse);
      }
      next += count;
      op.grid.alive[c] = used[0] > 0 ? 1 : 0;
    }
  });
  // Near hits whose texel no longer resolves to a live one go (all of a hit's rays land on it).
  op.near_offset.assign(nc + 1, 0);
  for (int by = 0; by < g.height; ++by) {
    for (const auto& [c, h] : row_near[size_t(by)]) {
      if (op.hit[size_t(c) * size_t(n_rays) + h.ray] == kNoTexel) continue;
      op.near.push_back(h);
      ++op.near_offset[c + 1];
    }
  }
  for (size_t c = 0; c < nc; ++c) op.near_offset[c + 1] += op.near_offset[c];
  for (uint8_t v : buried) op.buried_texels += v;
  op.buried = std::move(buried);
  {
    double sum = 0.0, count = 0.0;
    for (size_t c = 0; c < nc; ++c) {
      if (!g.alive[c]) continue;
      const glm::vec3 a = g.albedo[c];
      sum += double(std::max({a.x, a.y, a.z})) * g.member_count(uint32_t(c));
      count += g.member_count(uint32_t(c));
    }
    op.mean_albedo = count > 0.0 ? float(std::min(0.995, sum / count)) : 0.0f;
  }
  // Concatenate the rows in order (deterministic for any thread count).
  op.crossing_offset.assign(nc + 1, 0);
  op.coarse_crossing.assign(scene.objects.size(), {});
  {
    uint32_t c = 0;
    for (int by = 0; by < g.height; ++by) {
      const uint32_t base = uint32_t(op.crossing_hits.size());
      for (size_t i = 0; i < row_counts[size_t(by)].size(); ++i, ++c)
        op.crossing_offset[c + 1] = op.crossing_offset[c] + row_counts[size_t(by)][i];
      for (Crossing rec : row_crossings[size_t(by)]) {
        rec.first += base;
        op.crossings.push_back(rec);
      }
      op.crossing_hits.insert(op.crossing_hits.end(), row_hits[size_t(by)].begin(),
                              row_hits[size_t(by)].end());
    }
    for (uint32_t cc = 0; cc < nc; ++cc) {
      for (uint32_t i = op.crossing_offset[cc]; i < op.crossing_offset[cc + 1]; ++i) {
        const Crossing& rec = op.crossings[i];
        for (uint32_t j = rec.first; j < rec.first + rec.count; ++j) {
          std::vector<uint32_t>& list = op.coarse_crossing[size_t(op.crossing_hits[j].object)];
          if (list.empty() || list.back() != cc) list.push_back(cc);
        }
      }
    }
  }
  // Tiles and the tiles each tile's rays reach.
  op.tiles_x = (g.width + GatherOperator::kTile - 1) / GatherOperator::kTile;
  op.tiles_y = (g.height + GatherOperator::kTile - 1) / GatherOperator::kTile;
  const size_t n_tiles = size_t(op.tiles_x) * size_t(op.tiles_y);
  op.tile_of.resize(nc);
  op.tile_coarse.assign(n_tiles, {});
  for (uint32_t c = 0; c < nc; ++c) {
    const uint32_t b = g.block_of[c];
    const int bx = int(b % uint32_t(g.width)), by = int(b / uint32_t(g.width));
    const uint32_t tile =
        uint32_t((by / GatherOperator::kTile) * op.tiles_x + bx / GatherOperator::kTile);
    op.tile_of[c] = tile;
    op.tile_coarse[tile].push_back(c);
  }
  op.sources.assign(n_tiles, {});
  // Marked in a flag per tile, then listed in order: sorting every ray's tile cost more than
  // the rest of the pass.
  parallel_for(int(n_tiles), options.threads, [&](int tile) {
    std::vector<uint8_t> seen(n_tiles, 0);
    for (uint32_t c : op.tile_coarse[size_t(tile)]) {
      const uint32_t* hits = op.hit.data() + size_t(c) * size_t(n_rays);
      for (int k = 0; k < n_rays; ++k)
        if (hits[k] != kNoTexel) seen[op.tile_of[hits[k]]] = 1;
      for (uint32_t i = op.crossing_offset[c]; i < op.crossing_offset[c + 1]; ++i) {
        const Crossing& rec = op.crossings[i];
        for (uint32_t j = rec.first; j < rec.first + rec.count; ++j)
          if (op.crossing_hits[j].coarse != kNoTexel)
            seen[op.tile_of[op.crossing_hits[j].coarse]] = 1;
      }
    }
    std::vector<uint32_t>& src = op.sources[size_t(tile)];
    for (size_t t = 0; t < n_tiles; ++t)
      if (seen[t]) src.push_back(uint32_t(t));
  });
  op.rays_traced = tracer.rays_traced() - rays0;
  return op;
}

}  // namespace lightpatch::cooker
