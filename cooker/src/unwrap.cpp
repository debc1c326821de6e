// Light-map parameterization (seed 004 §6.1-6.2, §6.9). A region is one glTF node's meshes. Its
// light-map UVs are either its own TEXCOORD_1 (each node's UVs in [0,1], as Blender's Lightmap
// Pack, Unity and Godot write them), checked for overlaps and placed whole with one scale and
// offset, or an automatic unwrap: per mesh, charts grown across shared edges while the face
// normal stays within kChartCos of the chart's seed, projected on the seed's plane with overlap
// rejection, rotated to their tightest box, and packed in the region's rectangle. Regions are
// packed into one page, tallest first. When every node has TEXCOORD_1 and no two overlap, the
// UVs are one layout over the whole scene and are used as they are. Everything is ordered by
// index, so the same scene and options give the same layout.
#include "lightpatch/cooker/unwrap.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <numeric>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "lightpatch/cooker/error.h"
#include "uv_overlap.h"

namespace lightpatch::cooker {

namespace {

// A face joins a chart while its normal is within ~37 degrees of the chart's seed: planar
// projection then stretches texels by at most 1/0.8 and never flips a triangle.
constexpr float kChartCos = 0.8f;
// Target surface texels of the default density: a room-sized scene gets a page of about 512².
constexpr double kDefaultSurfaceTexels = 512.0 * 512.0 * 0.6;
constexpr int kMinPage = 16;
// Each retry at a lower density shrinks it by this factor.
constexpr float kDensityStep = 0.9f;

struct Chart {
  int mesh = 0;
  std::vector<uint32_t> triangles;   // triangle indices in the mesh
  std::vector<glm::vec2> corner_uv;  // 3 per triangle: world-unit plane coordinates, min at 0
  glm::vec2 size{0.0f};              // world units
  // Placement, filled by packing (texels).
  int rect_w = 0, rect_h = 0;
  int x = 0, y = 0;
};

// A region (one glTF node's meshes) on its way into the page: either unwrapped charts packed in
// its rectangle, or its own TEXCOORD_1 layout placed whole (scaled uniformly, as Unity's
// lightmapScaleOffset places a renderer's UV2).
struct RegionCharts {
  Region region;
  float density = 1.0f;     // extras.lightmapScale
  std::vector<int> charts;  // unwrapped charts, into the chart list
  bool uv1 = false;
  glm::vec2 uv_lo{0.0f}, uv_size{0.0f};  // bounding box of its TEXCOORD_1
  float texels_per_uv = 0.0f;  // at 1 texel per metre: sqrt(world area / UV area) per UV unit
  float uv_gap = 0.0f;         // smallest UV distance between two of its charts (0: unknown)
  float scale = 0.0f;          // texels per UV unit used (placement)
  int w = 0, h = 0;            // packed size (texels)
  int x = 0, y = 0;            // in the page
};

float triangle_area(const MeshInstance& m, size_t t) {
  const glm::vec3 a = m.positions[m.indices[3 * t]], b = m.positions[m.indices[3 * t + 1]],
                  c = m.positions[m.indices[3 * t + 2]];
  return 0.5f * glm::length(glm::cross(b - a, c - a));
}

glm::vec3 face_normal(const MeshInstance& m, size_t t) {
  const glm::vec3 a = m.positions[m.indices[3 * t]], b = m.positions[m.indices[3 * t + 1]],
                  c = m.positions[m.indices[3 * t + 2]];
  const glm::vec3 n = glm::cross(b - a, c - a);
  const float len = glm::length(n);
  // Import drops zero-area triangles; a scene built in code may still hold one.
  return len > 0.0f ? n / len : glm::vec3(0.0f, 0.0f, 1.0f);
}

// Orthonormal tangent frame of a plane normal, chosen from the world axis least aligned with it so
// that axis-aligned walls get axis-aligned charts.
void plane_basis(const glm::vec3& n, glm::vec3* t, glm::vec3* b) {
  const glm::vec3 a =
      std::abs(n.x) <= std::abs(n.y) && std::abs(n.x) <= std::abs(n.z)
          ? glm::vec3(1, 0, 0)
          : (std::abs(n.y) <= std::abs(n.z) ? glm::vec3(0, 1, 0) : glm::vec3(0, 0, 1));
  *t = glm::normalize(glm::cross(a, n));
  *b = glm::cross(n, *t);
}

// Vertex welding by exact position so charts grow across edges of split vertices.
struct PositionKey {
  float x, y, z;
  bool operator==(const PositionKey& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct PositionHash {
  size_t operator()(const PositionKey& k) const {
    uint32_t bits[3];
    std::memcpy(bits, &k, sizeof(bits));
    uint64_t h = 1469598103934665603ull;
    for (uint32_t b : bits) h = (h ^ b) * 1099511628211ull;
    return static_cast<size_t>(h);
  }
};

// Triangle adjacency through shared (welded) edges: for each triangle edge, the other triangles.
std::vector<std::vector<uint32_t>> build_adjacency(const MeshInstance& m) {
  std::unordered_map<PositionKey, uint32_t, PositionHash> weld;
  std::vector<uint32_t> id(m.positions.size());
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const glm::vec3 p = m.positions[i];
    id[i] =
        weld.emplace(PositionKey{p.x, p.y, p.z}, static_cast<uint32_t>(weld.size())).first->second;
  }
  const size_t nt = m.indices.size() / 3;
  std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>> edges;
  for (size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = id[m.indices[3 * t + k]], b = id[m.indices[3 * t + (k + 1) % 3]];
      if (a > b) std::swap(a, b);
      if (a != b) edges[{a, b}].push_back(static_cast<uint32_t>(t));
    }
  std::vector<std::vector<uint32_t>> adj(nt);
  for (const auto& [key, tris] : edges)
    for (uint32_t a : tris)
      for (uint32_t b : tris)
        if (a != b) adj[a].push_back(b);
  for (auto& a : adj) {
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
  }
  return adj;
}

// Rotates a chart's plane coordinates to the tightest axis-aligned box among the directions of its
// edges, then moves its minimum to the origin.
void fit_chart_box(Chart& c) {
  std::vector<std::pair<float, glm::vec2>> dirs;
  for (size_t i = 0; i < c.corner_uv.size(); i += 3)
    for (int k = 0; k < 3; ++k) {
      const glm::vec2 d = c.corner_uv[i + (k + 1) % 3] - c.corner_uv[i + k];
      const float len = glm::length(d);
      if (len > 0.0f) dirs.push_back({len, d / len});
    }
  std::stable_sort(dirs.begin(), dirs.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  if (dirs.size() > 32) dirs.resize(32);
  glm::vec2 best_axis(1.0f, 0.0f);
  float best_area = std::numeric_limits<float>::max();
  for (const auto& [len, d] : dirs) {
    glm::vec2 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (const glm::vec2& p : c.corner_uv) {
      const glm::vec2 q(d.x * p.x + d.y * p.y, -d.y * p.x + d.x * p.y);
      lo = glm::min(lo, q);
      hi = glm::max(hi, q);
    }
    const float area = (hi.x - lo.x) * (hi.y - lo.y);
    // Strictly smaller by a margin, so near-ties keep the earlier (longer) edge's direction.
    if (area < best_area * 0.999f) {
      best_area = area;
      best_axis = d;
    }
  }
  glm::vec2 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (glm::vec2& p : c.corner_uv) {
    p = glm::vec2(best_axis.x * p.x + best_axis.y * p.y, -best_axis.y * p.x + best_axis.x * p.y);
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  // Keep the longer side horizontal: shelves pack flat charts better.
  const bool swap = (hi.y - lo.y) > (hi.x - lo.x);
  for (glm::vec2& p : c.corner_uv) {
    p -= lo;
    if (swap) p = glm::vec2(p.y, p.x);
  }
  c.size = swap ? glm::vec2(hi.y - lo.y, hi.x - lo.x) : hi - lo;
  // A swap mirrors the chart; restore the winding so every chart keeps the same orientation.
  if (swap)
    for (glm::vec2& p : c.corner_uv) p.y = c.size.y - p.y;
}

// Grows the charts of one mesh.
void grow_charts(const MeshInstance& m, int mesh_index, std::vector<Chart>& out) {
  const size_t nt = m.indices.size() / 3;
  const auto adj = build_adjacency(m);
  std::vector<float> area(nt);
  std::vector<glm::vec3> normal(nt);
  for (size_t t = 0; t < nt; ++t) {
    area[t] = triangle_area(m, t);
    normal[t] = face_normal(m, t);
  }
  // Seeds in order of decreasing area (ties by index): big flat faces anchor charts.
  std::vector<uint32_t> order(nt);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return area[a] > area[b]; });
  std::vector<uint8_t> taken(nt, 0);
  for (uint32_t seed : order) {
    if (taken[seed]) continue;
    Chart c;
    c.mesh = mesh_index;
    const glm::vec3 n = normal[seed];
    glm::vec3 tu, tv;
    plane_basis(n, &tu, &tv);
    auto project = [&](uint32_t t, glm::vec2 out3[3]) {
      for (int k = 0; k < 3; ++k) {
        const glm::vec3 p = m.positions[m.indices[3 * t + k]];
        out3[k] = glm::vec2(glm::dot(p, tu), glm::dot(p, tv));
      }
    };
    UvOverlapGrid grid;
    std::vector<uint32_t> queue{seed};
    taken[seed] = 1;
    size_t head = 0;
    while (head < queue.size()) {
      const uint32_t t = queue[head++];
      glm::vec2 tri[3];
      project(t, tri);
      if (t != seed && grid.overlaps(tri)) {
        taken[t] = 0;  // rejected: it will seed or join another chart
        continue;
      }
      grid.insert(tri);
      c.triangles.push_back(t);
      c.corner_uv.insert(c.corner_uv.end(), tri, tri + 3);
      for (uint32_t nb : adj[t]) {
        if (taken[nb] || glm::dot(normal[nb], n) < kChartCos) continue;
        taken[nb] = 1;
        queue.push_back(nb);
      }
    }
    // Rejected neighbours were released; later seeds pick them up.
    fit_chart_box(c);
    out.push_back(std::move(c));
  }
}

// Shelf packing of rectangles (largest height first, ties by index) into a strip `width` wide.
// Returns the height used, or -1 if some rectangle is wider than the strip.
int shelf_pack(std::vector<std::pair<int, int>>& sizes, std::vector<std::pair<int, int>>& pos,
               int width) {
  std::vector<size_t> order(sizes.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    if (sizes[a].second != sizes[b].second) return sizes[a].second > sizes[b].second;
    return sizes[a].first > sizes[b].first;
  });
  pos.assign(sizes.size(), {0, 0});
  int x = 0, y = 0, shelf_h = 0;
  for (size_t i : order) {
    const auto [w, h] = sizes[i];
    if (w > width) return -1;
    if (x + w > width) {
      y += shelf_h;
      x = 0;
      shelf_h = 0;
    }
    pos[i] = {x, y};
    x += w;
    shelf_h = std::max(shelf_h, h);
  }
  return y + shelf_h;
}

struct Packed {
  bool fits = false;
  int page = 0;    // width (texels)
  int height = 0;  // the page's rows actually used, rounded up to 4 (the square page when fixed)
};

// Charts of a TEXCOORD_1 layout closer than this (texels) share texels: conservative
// rasterization reaches 0.7 texel past each, and bilinear filtering half a texel more. The cook
// says so (the node's lightmapScale or the UVs' margin is the author's to raise: raising it here
// would cost the whole node's texels for a margin).
constexpr float kChartGapTexels = 2.0f;

// Sizes every chart and TEXCOORD_1 region at density `tpu` (a region's UV area spread over its
// surface), packs charts per region and regions into the smallest square page (a multiple of 4)
// that holds them, at most `max_page`, or exactly `fixed_page`.
Packed pack_all(std::vector<Chart>& charts, std::vector<RegionCharts>& regions, float tpu,
                int border, int align, int fixed_page, int max_page) {
  // Rectangles on whole blocks with a block of border of their own (LayoutOptions::align).
  border = std::max(border, align);
  auto whole = [&](int texels) { return (texels + align - 1) / align * align; };
  const int step = std::max(4, align);  // the page is a multiple of this
  int64_t total = 0;
  for (RegionCharts& r : regions) {
    if (r.uv1) {
      r.scale = tpu * r.density * r.texels_per_uv;
      r.w = whole(std::max(1, static_cast<int>(std::ceil(r.uv_size.x * r.scale))) + 2 * border);
      r.h = whole(std::max(1, static_cast<int>(std::ceil(r.uv_size.y * r.scale))) + 2 * border);
      total += int64_t(r.w) * r.h;
      continue;
    }
    std::vector<std::pair<int, int>> sizes, pos;
    int64_t area = 0;
    int widest = 0;
    for (int ci : r.charts) {
      Chart& c = charts[size_t(ci)];
      const float density = tpu * r.density;
      c.rect_w = whole(std::max(1, static_cast<int>(std::ceil(c.size.x * density))) + 2 * border);
      c.rect_h = whole(std::max(1, static_cast<int>(std::ceil(c.size.y * density))) + 2 * border);
      sizes.push_back({c.rect_w, c.rect_h});
      area += int64_t(c.rect_w) * c.rect_h;
      widest = std::max(widest, c.rect_w);
    }
    const int strip = std::max(widest, static_cast<int>(std::ceil(std::sqrt(double(area) * 1.15))));
    r.h = shelf_pack(sizes, pos, strip);
    r.w = 0;
    for (size_t k = 0; k < r.charts.size(); ++k) {
      Chart& c = charts[size_t(r.charts[k])];
      c.x = pos[k].first;
      c.y = pos[k].second;
      r.w = std::max(r.w, c.x + c.rect_w);
    }
    total += int64_t(r.w) * r.h;
  }
  std::vector<std::pair<int, int>> sizes, pos;
  for (const RegionCharts& r : regions) sizes.push_back({r.w, r.h});
  int used = 0;
  auto fits = [&](int page) {
    used = shelf_pack(sizes, pos, page);
    return used >= 0 && used <= page;
  };
  Packed result;
  if (fixed_page > 0) {
    result.page = fixed_page;
    result.fits = fits(fixed_page);
  } else {
    int page = std::max(
        kMinPage, (static_cast<int>(std::ceil(std::sqrt(double(total)))) + step - 1) / step * step);
    while (page <= max_page && !fits(page)) page += std::max(step, page / 32 / step * step);
    result.page = std::min(page, max_page);
    result.fits = page <= max_page && fits(result.page);
  }
  // A page of fixed size stays square; a derived one ends below its last shelf.
  result.height = fixed_page > 0 ? fixed_page : std::max(kMinPage, (used + step - 1) / step * step);
  if (result.fits)
    for (size_t i = 0; i < regions.size(); ++i) {
      regions[i].x = pos[i].first;
      regions[i].y = pos[i].second;
    }
  return result;
}

double mesh_area(const MeshInstance& m) {
  double a = 0.0;
  for (size_t t = 0; t < m.indices.size() / 3; ++t) a += triangle_area(m, t);
  return a;
}

// Surface of the meshes in the light map, each weighted by its density factor squared: the
// texels the default density spends.
double weighted_area(const Scene& scene) {
  double a = 0.0;
  for (const MeshInstance& m : scene.meshes)
    if (!m.lightmap_exclude) a += mesh_area(m) * double(m.lightmap_scale) * m.lightmap_scale;
  return a;
}

// Regions: one per glTF node (meshes sharing node_index), one per mesh for scenes built in code;
// meshes kept out of the light map belong to none.
std::vector<Region> make_regions(const Scene& scene) {
  std::vector<Region> regions;
  std::map<int, size_t> by_node;
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    const MeshInstance& m = scene.meshes[i];
    if (m.lightmap_exclude) continue;
    if (m.node_index >= 0) {
      auto it = by_node.find(m.node_index);
      if (it != by_node.end()) {
        regions[it->second].meshes.push_back(int(i));
        continue;
      }
      by_node[m.node_index] = regions.size();
    }
    Region r;
    r.name = m.name;
    r.object = m.object;
    r.meshes.push_back(int(i));
    regions.push_back(std::move(r));
  }
  return regions;
}

// A mesh as the user knows it: its node's name, or the node's index when the node has no name.
std::string mesh_label(const MeshInstance& m) {
  if (!m.name.empty()) return "mesh '" + m.name + "'";
  return m.node_index >= 0 ? "the mesh of node " + std::to_string(m.node_index)
                           : std::string("an unnamed mesh");
}

std::string overlap_error(const MeshInstance& m, size_t triangle, const MeshInstance& other) {
  return "TEXCOORD_1 of " + mesh_label(m) + " (primitive " + std::to_string(m.primitive_index) +
         ") has triangle " + std::to_string(triangle) + " overlapping " +
         (&other == &m
              ? std::string("another of its own triangles")
              : mesh_label(other) + " (primitive " + std::to_string(other.primitive_index) + ")") +
         "; a node's light-map UVs must not overlap (--unwrap always ignores them)";
}

// The triangles of `meshes` in TEXCOORD_1 inserted into `grid`, `owner` recording each one's
// mesh. Returns the mesh index of the first triangle overlapping an earlier one (-1: none);
// `first` and `second` receive the two meshes and `triangle` the later triangle's index.
struct Uv1Overlap {
  int first = -1, second = -1;
  size_t triangle = 0;
};
Uv1Overlap insert_uv1(const Scene& scene, const std::vector<int>& meshes, UvOverlapGrid& grid,
                      std::vector<int>& owner) {
  for (int mi : meshes) {
    const MeshInstance& m = scene.meshes[size_t(mi)];
    for (size_t t = 0; t < m.indices.size() / 3; ++t) {
      glm::vec2 tri[3];
      for (int k = 0; k < 3; ++k) tri[k] = m.uv1[m.indices[3 * t + k]];
      int other = -1;
      if (grid.overlaps(tri, &other)) return Uv1Overlap{owner[size_t(other)], mi, t};
      grid.insert(tri);
      owner.push_back(mi);
    }
  }
  return {};
}

// Distance between two triangles in the plane that do not overlap (0 where they touch).
float triangle_distance(const glm::vec2* a, const glm::vec2* b) {
  auto point_segment = [](glm::vec2 p, glm::vec2 s0, glm::vec2 s1) {
    const glm::vec2 e = s1 - s0;
    const float len2 = glm::dot(e, e);
    const float t = len2 > 0.0f ? std::clamp(glm::dot(p - s0, e) / len2, 0.0f, 1.0f) : 0.0f;
    return glm::length(p - (s0 + e * t));
  };
  float d = std::numeric_limits<float>::max();
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      d = std::min(d, point_segment(a[i], b[k], b[(k + 1) % 3]));
      d = std::min(d, point_segment(b[i], a[k], a[(k + 1) % 3]));
    }
  return d;
}

// The smallest TEXCOORD_1 distance between two charts (sets of triangles joined by shared UV
// corners) of a region, looked for up to `reach` (UV units); 0 if none is that close.
float chart_gap(const Scene& scene, const std::vector<int>& meshes, float reach) {
  std::vector<glm::vec2> tris;
  std::vector<uint32_t> chart;
  {
    // Union-find over corners welded by exact UV, per mesh (primitives do not share vertices).
    std::vector<uint32_t> parent;
    auto find = [&](uint32_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    for (int mi : meshes) {
      const MeshInstance& m = scene.meshes[size_t(mi)];
      const size_t nt = m.indices.size() / 3;
      const uint32_t base = uint32_t(parent.size());
      for (size_t t = 0; t < nt; ++t) parent.push_back(uint32_t(base + t));
      std::map<std::pair<float, float>, uint32_t> corner;  // UV -> a triangle using it
      for (size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) {
          const glm::vec2 uv = m.uv1[m.indices[3 * t + k]];
          tris.push_back(uv);
          auto [it, fresh] = corner.emplace(std::make_pair(uv.x, uv.y), uint32_t(base + t));
          if (!fresh) parent[find(uint32_t(base + t))] = find(it->second);
        }
    }
    for (uint32_t t = 0; t < parent.size(); ++t) chart.push_back(find(t));
  }
  if (!(reach > 0.0f)) return 0.0f;
  // Triangles binned by their boxes grown by reach/2; pairs of different charts sharing a cell.
  std::map<std::pair<int64_t, int64_t>, std::vector<uint32_t>> cells;
  for (uint32_t t = 0; t < chart.size(); ++t) {
    const glm::vec2* p = &tris[size_t(t) * 3];
    const glm::vec2 lo = glm::min(p[0], glm::min(p[1], p[2])) - 0.5f * reach;
    const glm::vec2 hi = glm::max(p[0], glm::max(p[1], p[2])) + 0.5f * reach;
    const int64_t x0 = int64_t(std::floor(lo.x / reach)), x1 = int64_t(std::floor(hi.x / reach));
    const int64_t y0 = int64_t(std::floor(lo.y / reach)), y1 = int64_t(std::floor(hi.y / reach));
    if ((x1 - x0 + 1) * (y1 - y0 + 1) > 4096) continue;  // a triangle far larger than the gap
    for (int64_t y = y0; y <= y1; ++y)
      for (int64_t x = x0; x <= x1; ++x) cells[{x, y}].push_back(t);
  }
  float gap = reach;
  for (const auto& [cell, list] : cells)
    for (size_t i = 0; i < list.size(); ++i)
      for (size_t j = i + 1; j < list.size(); ++j)
        if (chart[list[i]] != chart[list[j]])
          gap = std::min(gap,
                         triangle_distance(&tris[size_t(list[i]) * 3], &tris[size_t(list[j]) * 3]));
  return gap < reach ? gap : 0.0f;
}

// Fills a TEXCOORD_1 region's UV box, area ratio and chart gap; throws if its UVs overlap.
void measure_uv1(const Scene& scene, RegionCharts& r) {
  UvOverlapGrid grid;
  std::vector<int> owner;
  const Uv1Overlap o = insert_uv1(scene, r.region.meshes, grid, owner);
  if (o.second >= 0)
    throw CookError(
        overlap_error(scene.meshes[size_t(o.second)], o.triangle, scene.meshes[size_t(o.first)]));
  glm::vec2 lo(1.0f), hi(0.0f);
  double uv_area = 0.0, world_area = 0.0;
  for (int mi : r.region.meshes) {
    const MeshInstance& m = scene.meshes[size_t(mi)];
    world_area += mesh_area(m);
    for (size_t t = 0; t < m.indices.size() / 3; ++t) {
      const glm::vec2 a = m.uv1[m.indices[3 * t]], b = m.uv1[m.indices[3 * t + 1]],
                      c = m.uv1[m.indices[3 * t + 2]];
      uv_area += 0.5 * std::abs(double((b - a).x) * (c - a).y - double((b - a).y) * (c - a).x);
      lo = glm::min(lo, glm::min(a, glm::min(b, c)));
      hi = glm::max(hi, glm::max(a, glm::max(b, c)));
    }
  }
  if (!(uv_area > 1e-12))
    throw CookError("TEXCOORD_1 of " + mesh_label(scene.meshes[size_t(r.region.meshes[0])]) +
                    " has no area (every triangle collapses in the light-map UVs)");
  r.uv1 = true;
  r.uv_lo = lo;
  r.uv_size = hi - lo;
  r.texels_per_uv = static_cast<float>(std::sqrt(world_area / uv_area));
  // Gaps narrower than 1/32 of the layout matter below 64 texels across.
  r.uv_gap = chart_gap(scene, r.region.meshes, std::max(r.uv_size.x, r.uv_size.y) / 32.0f);
}

Layout verbatim_layout(const Scene& scene, const std::vector<Region>& regions,
                       const LayoutOptions& options) {
  Layout layout;
  layout.verbatim_uv1 = true;
  layout.uv1_regions = int(regions.size());
  // The page: the requested size, or one that gives the requested (or default) density to the
  // scene's surface if its UVs fill the page.
  int page = options.lightmap_size;
  double area = 0.0;
  for (const MeshInstance& m : scene.meshes)
    if (!m.lightmap_exclude) area += mesh_area(m);
  area = std::max(area, 1e-30);
  if (page <= 0) {
    const double tpu = options.texels_per_unit > 0.0f ? options.texels_per_unit
                                                      : std::sqrt(kDefaultSurfaceTexels / area);
    page = static_cast<int>(std::ceil(std::sqrt(area) * tpu * 1.3));
    const int step = std::max(4, options.align);
    page = std::clamp((page + step - 1) / step * step, kMinPage,
                      options.max_lightmap_size / step * step);
  }
  layout.width = layout.height = page;
  // The UVs are used as they are, so charts are not on blocks: the pack still splits each map
  // into an indirect and a light-map part where that is smaller, the light map holding whatever
  // the interpolation mixes across charts.
  layout.align = options.align;
  while (page % layout.align != 0) layout.align /= 2;
  layout.texels_per_unit = static_cast<float>(page / std::sqrt(area) / 1.3);
  layout.meshes.resize(scene.meshes.size());
  for (const Region& r : regions)
    for (int mi : r.meshes) {
      const MeshInstance& m = scene.meshes[size_t(mi)];
      MeshLayout& ml = layout.meshes[size_t(mi)];
      ml.source_vertex.resize(m.positions.size());
      std::iota(ml.source_vertex.begin(), ml.source_vertex.end(), 0u);
      ml.uv = m.uv1;
      ml.indices = m.indices;
      ml.from_uv1 = true;
      ml.uv1_scale_offset = glm::vec4(1.0f, 1.0f, 0.0f, 0.0f);
    }

  // Regions: the texel bounding box of each node's triangles, one texel of margin for filtering;
  // overlapping boxes are merged so that no texel belongs to two regions.
  std::vector<Region> merged_regions = regions;
  for (Region& r : merged_regions) {
    glm::vec2 lo(1.0f), hi(0.0f);
    for (int mi : r.meshes)
      for (uint32_t i : scene.meshes[size_t(mi)].indices) {
        lo = glm::min(lo, scene.meshes[size_t(mi)].uv1[i]);
        hi = glm::max(hi, scene.meshes[size_t(mi)].uv1[i]);
      }
    const int x0 = std::max(0, static_cast<int>(std::floor(lo.x * page)) - 1);
    const int y0 = std::max(0, static_cast<int>(std::floor(lo.y * page)) - 1);
    const int x1 = std::min(page, static_cast<int>(std::ceil(hi.x * page)) + 1);
    const int y1 = std::min(page, static_cast<int>(std::ceil(hi.y * page)) + 1);
    r.rect = Rect{x0, y0, std::max(1, x1 - x0), std::max(1, y1 - y0)};
  }
  auto overlap = [](const Rect& a, const Rect& b) {
    return a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
  };
  bool merged = true;
  int merges = 0;
  while (merged) {
    merged = false;
    for (size_t i = 0; i < merged_regions.size() && !merged; ++i)
      for (size_t j = i + 1; j < merged_regions.size() && !merged; ++j) {
        if (!overlap(merged_regions[i].rect, merged_regions[j].rect)) continue;
        Region& a = merged_regions[i];
        const Region& b = merged_regions[j];
        const int x0 = std::min(a.rect.x, b.rect.x), y0 = std::min(a.rect.y, b.rect.y);
        const int x1 = std::max(a.rect.x + a.rect.w, b.rect.x + b.rect.w);
        const int y1 = std::max(a.rect.y + a.rect.h, b.rect.y + b.rect.h);
        a.rect = Rect{x0, y0, x1 - x0, y1 - y0};
        a.name += "+" + b.name;
        if (a.object != b.object) a.object = -1;
        a.meshes.insert(a.meshes.end(), b.meshes.begin(), b.meshes.end());
        merged_regions.erase(merged_regions.begin() + std::ptrdiff_t(j));
        merged = true;
        ++merges;
      }
  }
  if (merges > 0)
    layout.notes.push_back("TEXCOORD_1: " + std::to_string(merges) +
                           " node(s) share light-map bounding boxes and were merged into one "
                           "patch region");
  layout.regions = std::move(merged_regions);
  return layout;
}

// Smooth-surface cuts: edges whose two triangles share both corners, normals included (source
// vertices welded by position and normal, as exporters split vertices at UV seams), that the
// layout gives different UVs on each side.
std::vector<SeamEdge> find_seams(const Scene& scene, const Layout& layout) {
  std::vector<SeamEdge> seams;
  for (size_t mi = 0; mi < scene.meshes.size(); ++mi) {
    const MeshInstance& m = scene.meshes[mi];
    const MeshLayout& ml = layout.meshes[mi];
    if (ml.indices.empty()) continue;  // not in the light map
    std::map<std::array<float, 6>, uint32_t> weld_ids;
    std::vector<uint32_t> weld(m.positions.size());
    for (size_t v = 0; v < m.positions.size(); ++v) {
      const glm::vec3 p = m.positions[v], n = m.normals[v];
      weld[v] =
          weld_ids.emplace(std::array{p.x, p.y, p.z, n.x, n.y, n.z}, uint32_t(weld_ids.size()))
              .first->second;
    }
    // Welded edge (sorted) -> the first triangle's layout vertices: edge start, edge end (oriented
    // as the welded edge) and the opposite corner.
    std::map<std::pair<uint32_t, uint32_t>, std::array<uint32_t, 3>> first;
    for (size_t t = 0; t < m.indices.size() / 3; ++t)
      for (int k = 0; k < 3; ++k) {
        uint32_t s0 = weld[m.indices[3 * t + k]], s1 = weld[m.indices[3 * t + (k + 1) % 3]];
        uint32_t l0 = ml.indices[3 * t + k], l1 = ml.indices[3 * t + (k + 1) % 3];
        const uint32_t l2 = ml.indices[3 * t + (k + 2) % 3];
        if (s0 == s1) continue;
        if (s0 > s1) {
          std::swap(s0, s1);
          std::swap(l0, l1);
        }
        auto [it, inserted] = first.emplace(std::make_pair(s0, s1), std::array{l0, l1, l2});
        const auto& [f0, f1, f2] = it->second;
        if (inserted || (ml.uv[f0] == ml.uv[l0] && ml.uv[f1] == ml.uv[l1])) continue;
        seams.push_back(SeamEdge{ml.uv[f0], ml.uv[f1], ml.uv[l0], ml.uv[l1], ml.uv[f2], ml.uv[l2]});
      }
  }
  return seams;
}

}  // namespace

Layout build_layout(const Scene& scene, const LayoutOptions& options) {
  if (options.align != 1 && options.align != 2 && options.align != 4 && options.align != 8)
    throw CookError("layout: the indirect scale must be 1, 2, 4 or 8, not " +
                    std::to_string(options.align));
  if (options.align_required && options.lightmap_size > 0 &&
      options.lightmap_size % options.align != 0)
    throw CookError("--lightmap-size " + std::to_string(options.lightmap_size) +
                    " is not a multiple of the indirect scale " + std::to_string(options.align) +
                    " (the indirect map must tile the light map)");
  if (scene.meshes.empty()) throw CookError("the scene has no meshes to bake");
  std::vector<Region> base_regions = make_regions(scene);
  if (base_regions.empty())
    throw CookError("every mesh is kept out of the light map (extras.lightmapExclude)");

  // Which regions keep their TEXCOORD_1.
  std::vector<uint8_t> keeps_uv1(base_regions.size(), 0);
  bool all_uv1 = true, any_density = false;
  for (size_t r = 0; r < base_regions.size(); ++r) {
    bool has = true;
    for (int mi : base_regions[r].meshes) {
      const MeshInstance& m = scene.meshes[size_t(mi)];
      any_density |= m.lightmap_scale != 1.0f;
      if (!m.uv1.empty()) continue;
      has = false;
      if (options.unwrap == UnwrapMode::kNever)
        throw CookError(mesh_label(m) + " (primitive " + std::to_string(m.primitive_index) +
                        ") has no TEXCOORD_1, which --unwrap never requires");
    }
    keeps_uv1[r] = has && options.unwrap != UnwrapMode::kAlways;
    all_uv1 &= keeps_uv1[r] != 0;
  }

  // One layout over the whole scene, used as it is, where no node asks for its own density and
  // no two nodes' UVs overlap (else each node's UVs are its own, placed by scale and offset).
  if (all_uv1 && !any_density) {
    UvOverlapGrid grid;
    std::vector<int> owner;
    bool across = false;
    for (const Region& r : base_regions) {
      const Uv1Overlap o = insert_uv1(scene, r.meshes, grid, owner);
      if (o.second < 0) continue;
      const MeshInstance &a = scene.meshes[size_t(o.first)], &b = scene.meshes[size_t(o.second)];
      const bool same_node =
          o.first == o.second || (a.node_index >= 0 && a.node_index == b.node_index);
      if (same_node) throw CookError(overlap_error(b, o.triangle, a));
      across = true;
      break;
    }
    if (!across) {
      Layout layout = verbatim_layout(scene, base_regions, options);
      layout.seams = find_seams(scene, layout);
      return layout;
    }
  }

  Layout layout;
  std::vector<Chart> charts;
  std::vector<RegionCharts> regions;
  for (size_t r = 0; r < base_regions.size(); ++r) {
    RegionCharts rc;
    rc.region = std::move(base_regions[r]);
    rc.density = scene.meshes[size_t(rc.region.meshes[0])].lightmap_scale;
    if (keeps_uv1[r]) {
      measure_uv1(scene, rc);
    } else {
      for (int mi : rc.region.meshes) {
        const size_t first = charts.size();
        grow_charts(scene.meshes[size_t(mi)], mi, charts);
        for (size_t c = first; c < charts.size(); ++c) rc.charts.push_back(int(c));
      }
    }
    regions.push_back(std::move(rc));
  }

  const double area = std::max(weighted_area(scene), 1e-30);
  const float requested = options.texels_per_unit > 0.0f
                              ? options.texels_per_unit
                              : static_cast<float>(std::sqrt(kDefaultSurfaceTexels / area));
  // An automatic alignment halves until the charts fit the page (LayoutOptions::align_required).
  int align = options.align;
  float tpu = requested;
  Packed packed;
  for (;;) {
    const int max_page = std::clamp(options.max_lightmap_size, kMinPage, 16384) /
                         std::max(4, align) * std::max(4, align);
    tpu = requested;
    const bool page_divides = options.lightmap_size <= 0 || options.lightmap_size % align == 0;
    for (int attempt = 0; page_divides && attempt < 200; ++attempt) {
      packed = pack_all(charts, regions, tpu, options.border_texels, align, options.lightmap_size,
                        max_page);
      if (packed.fits) break;
      tpu *= kDensityStep;
    }
    if ((page_divides && packed.fits) || align == 1 || options.align_required) {
      if (!packed.fits) {
        throw CookError(
            "the light-map charts (" + std::to_string(charts.size()) + " charts, " +
            std::to_string(regions.size()) + " nodes) do not fit a " +
            std::to_string(options.lightmap_size > 0 ? options.lightmap_size : max_page) +
            "² page even at a very low density" +
            (align > 1 ? " with charts on " + std::to_string(align) + "x" + std::to_string(align) +
                             " blocks (--indirect-scale)"
                       : std::string()) +
            "; raise --lightmap-size");
      }
      break;
    }
    layout.notes.push_back("charts on " + std::to_string(align) + "x" + std::to_string(align) +
                           " blocks do not fit the page: indirect scale lowered to " +
                           std::to_string(align / 2));
    align /= 2;
  }
  layout.align = align;
  if (tpu < requested) {
    char buf[256];
    std::snprintf(buf, sizeof(buf),
                  "texel density lowered from %.4g to %.4g texels/m so that %zu charts fit a %dx%d "
                  "light map",
                  double(requested), double(tpu),
                  charts.size() + size_t(std::count_if(regions.begin(), regions.end(),
                                                       [](const auto& r) { return r.uv1; })),
                  packed.page, packed.height);
    layout.notes.push_back(buf);
  }
  layout.width = packed.page;
  layout.height = packed.height;
  layout.texels_per_unit = tpu;
  layout.meshes.resize(scene.meshes.size());

  const glm::vec2 inv(1.0f / float(layout.width), 1.0f / float(layout.height));
  const int border = std::max(options.border_texels, layout.align);
  layout.border = border;
  std::vector<std::vector<uint32_t>> tri_indices(scene.meshes.size());
  std::string close_charts;  // TEXCOORD_1 regions whose charts share texels
  for (RegionCharts& r : regions) {
    if (r.uv1) {
      ++layout.uv1_regions;
      // page texel = (uv - lo) * scale + origin, as one scale and offset per node.
      const glm::vec2 origin(float(r.x + border), float(r.y + border));
      const glm::vec2 scale = glm::vec2(r.scale) * inv;
      const glm::vec2 offset = (origin - r.uv_lo * r.scale) * inv;
      for (int mi : r.region.meshes) {
        const MeshInstance& m = scene.meshes[size_t(mi)];
        MeshLayout& ml = layout.meshes[size_t(mi)];
        ml.source_vertex.resize(m.positions.size());
        std::iota(ml.source_vertex.begin(), ml.source_vertex.end(), 0u);
        ml.uv.resize(m.uv1.size());
        for (size_t v = 0; v < m.uv1.size(); ++v) ml.uv[v] = m.uv1[v] * scale + offset;
        ml.indices = m.indices;
        ml.from_uv1 = true;
        ml.uv1_scale_offset = glm::vec4(scale, offset);
      }
      const float gap_texels = r.uv_gap * r.scale;
      if (r.uv_gap > 0.0f && gap_texels < kChartGapTexels - 1e-3f) {
        char buf[160];
        std::snprintf(buf, sizeof(buf), "%s'%s' (%.2f)", close_charts.empty() ? "" : ", ",
                      r.region.name.c_str(), double(gap_texels));
        close_charts += buf;
      }
      r.region.charts.push_back(Rect{r.x, r.y, r.w, r.h});
    } else {
      ++layout.unwrapped_regions;
      for (int ci : r.charts) {
        const Chart& c = charts[size_t(ci)];
        r.region.charts.push_back(Rect{r.x + c.x, r.y + c.y, c.rect_w, c.rect_h});
        const MeshInstance& m = scene.meshes[size_t(c.mesh)];
        MeshLayout& ml = layout.meshes[size_t(c.mesh)];
        std::vector<uint32_t>& tri = tri_indices[size_t(c.mesh)];
        tri.resize(m.indices.size(), 0);
        // Layout vertices: one per (chart, source vertex), so vertices split where charts cut.
        std::map<uint32_t, uint32_t> local;
        const glm::vec2 origin(float(r.x + c.x + border), float(r.y + c.y + border));
        const float density = tpu * r.density;
        for (size_t k = 0; k < c.triangles.size(); ++k) {
          const uint32_t t = c.triangles[k];
          for (int j = 0; j < 3; ++j) {
            const uint32_t src = m.indices[3 * t + j];
            auto [it, inserted] = local.emplace(src, uint32_t(ml.uv.size()));
            if (inserted) {
              ml.source_vertex.push_back(src);
              ml.uv.push_back((origin + c.corner_uv[3 * k + j] * density) * inv);
            }
            tri[3 * t + j] = it->second;
          }
        }
      }
    }
  }
  if (!close_charts.empty())
    layout.notes.push_back(
        "TEXCOORD_1 charts closer than 2 texels at this density, so light may bleed between "
        "them, in node(s) " +
        close_charts +
        " texels apart); give them a larger extras.lightmapScale or their UVs a larger margin");
  for (size_t mi = 0; mi < scene.meshes.size(); ++mi)
    if (!tri_indices[mi].empty()) layout.meshes[mi].indices = std::move(tri_indices[mi]);
  layout.seams = find_seams(scene, layout);
  for (RegionCharts& r : regions) {
    r.region.rect = Rect{r.x, r.y, r.w, r.h};
    layout.regions.push_back(std::move(r.region));
  }
  return layout;
}

}  // namespace lightpatch::cooker
