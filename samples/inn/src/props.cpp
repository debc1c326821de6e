#include "props.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace lightpatch::inn {

using scenegen::Geometry;
using scenegen::make_box;
using scenegen::make_cylinder;
using scenegen::make_frustum;
using scenegen::make_lathe;
using scenegen::make_quad;
using scenegen::make_sphere;
using scenegen::make_torus;

namespace {

constexpr float kPi = 3.14159265358979323846f;

glm::mat4 at(glm::vec3 p) {
  return glm::translate(glm::mat4(1.0f), p);
}
glm::mat4 scaled(glm::vec3 p, glm::vec3 s) {
  return glm::scale(at(p), s);
}
glm::mat4 rot_x(float a) {
  return glm::rotate(glm::mat4(1.0f), a, glm::vec3(1, 0, 0));
}
glm::mat4 rot_z(float a) {
  return glm::rotate(glm::mat4(1.0f), a, glm::vec3(0, 0, 1));
}

int segs(const Detail& d, int full) {
  return std::max(6, full * d.round_segments / 16);
}

// A dinner plate, 24 cm across (lathed; on the table and standing on the dresser's shelves).
Geometry make_plate(const Detail& d) {
  return make_lathe({{0, 0},
                     {0.07f, 0},
                     {0.07f, 0},
                     {0.11f, 0.015f},
                     {0.12f, 0.02f},
                     {0.115f, 0.022f},
                     {0.06f, 0.008f},
                     {0, 0.008f}},
                    segs(d, 24));
}

}  // namespace

std::uint64_t Rng::next() {
  std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

float Rng::uniform(float lo, float hi) {
  const float t = static_cast<float>(next() >> 40) / static_cast<float>(1ull << 24);
  return lo + (hi - lo) * t;
}

int Rng::below(int n) {
  return static_cast<int>(next() % static_cast<std::uint64_t>(n));
}

void Parts::add(int material, const Geometry& g, const glm::mat4& m) {
  by_material[material].append(g, m);
}

void Parts::append(const Parts& other, const glm::mat4& m) {
  for (const auto& [mat, g] : other.by_material) add(mat, g, m);
}

std::size_t Parts::triangle_count() const {
  std::size_t n = 0;
  for (const auto& [mat, g] : by_material) n += g.triangle_count();
  return n;
}

std::vector<scenegen::Primitive> Parts::primitives() const {
  std::vector<scenegen::Primitive> out;
  for (const auto& [mat, g] : by_material) {
    if (!g.empty()) out.push_back({g, mat, scenegen::IndexType::kAuto});
  }
  return out;
}

glm::mat4 place(glm::vec3 position, float yaw) {
  return glm::rotate(at(position), yaw, glm::vec3(0, 1, 0));
}

Geometry rbox(const Detail& d, glm::vec3 min, glm::vec3 max, float bevel) {
  if (d.bevel_segments <= 0) return make_box(min, max);
  return scenegen::make_rounded_box(min, max, bevel, d.bevel_segments);
}

void add_table(Parts& p, const Detail& d, const glm::mat4& m, float w, float depth, float h) {
  p.add(kWoodLight, rbox(d, {-w / 2, h - 0.05f, -depth / 2}, {w / 2, h, depth / 2}, 0.015f), m);
  const Geometry leg = make_cylinder(0.035f, h - 0.05f, segs(d, 12));
  for (int sx : {-1, 1}) {
    for (int sz : {-1, 1}) {
      p.add(kWoodDark, leg, m * at({sx * (w / 2 - 0.1f), 0, sz * (depth / 2 - 0.1f)}));
    }
  }
}

void add_chair(Parts& p, const Detail& d, const glm::mat4& m) {
  p.add(kWoodLight, rbox(d, {-0.22f, 0.43f, -0.22f}, {0.22f, 0.47f, 0.22f}, 0.01f), m);
  p.add(kWoodLight, rbox(d, {-0.22f, 0.47f, -0.24f}, {0.22f, 0.95f, -0.2f}, 0.01f), m);
  const Geometry leg = make_cylinder(0.02f, 0.43f, segs(d, 8));
  for (int sx : {-1, 1}) {
    for (int sz : {-1, 1}) p.add(kWoodDark, leg, m * at({sx * 0.19f, 0, sz * 0.19f}));
  }
}

void add_place_setting(Parts& p, const Detail& d, const glm::mat4& m) {
  const Geometry plate = make_plate(d);
  p.add(kCeramic, plate, m);
  const Geometry cup = make_lathe({{0, 0},
                                   {0.035f, 0},
                                   {0.035f, 0},
                                   {0.04f, 0.09f},
                                   {0.036f, 0.09f},
                                   {0.031f, 0.01f},
                                   {0, 0.01f}},
                                  segs(d, 16));
  p.add(kCeramic, cup, m * at({0.17f, 0, -0.1f}));
  const Geometry blade = rbox(d, {-0.008f, 0, -0.09f}, {0.008f, 0.005f, 0.09f}, 0.002f);
  p.add(kMetal, blade, m * at({-0.15f, 0, 0}));
  p.add(kMetal, blade, m * at({0.15f, 0, 0}));
  p.add(kMetal, blade, m * at({0.18f, 0, 0.02f}));
  p.add(kMetal, make_sphere(1.0f, segs(d, 8), 4),
        m * scaled({0.18f, 0.006f, -0.08f}, {0.02f, 0.006f, 0.03f}));
}

void add_bowl(Parts& p, const Detail& d, const glm::mat4& m) {
  p.add(kCeramic,
        make_lathe({{0, 0},
                    {0.05f, 0},
                    {0.05f, 0},
                    {0.1f, 0.07f},
                    {0.095f, 0.072f},
                    {0.045f, 0.01f},
                    {0, 0.01f}},
                   segs(d, 24)),
        m);
  // Apples in the bowl.
  const Geometry apple = make_sphere(0.035f, segs(d, 10), 6);
  for (int i = 0; i < 3; ++i) {
    const float a = 2.0f * kPi * static_cast<float>(i) / 3.0f;
    p.add(kClothRed, apple, m * at({0.035f * std::cos(a), 0.045f, 0.035f * std::sin(a)}));
  }
}

glm::vec3 add_candle(Parts& p, const Detail& d, const glm::mat4& m, float height) {
  p.add(kMetal,
        make_lathe({{0, 0},
                    {0.05f, 0},
                    {0.05f, 0},
                    {0.055f, 0.012f},
                    {0.05f, 0.014f},
                    {0.02f, 0.006f},
                    {0.02f, 0.006f},
                    {0.018f, 0.02f},
                    {0, 0.02f}},
                   segs(d, 16)),
        m);
  p.add(kWax, make_cylinder(0.018f, height, segs(d, 12), 1), m * at({0, 0.02f, 0}));
  const float top = 0.02f + height;
  p.add(kFlame, make_sphere(1.0f, segs(d, 8), 4),
        m * scaled({0, top + 0.02f, 0}, {0.007f, 0.018f, 0.007f}));
  return {0.0f, top + 0.025f, 0.0f};
}

glm::vec3 add_torch(Parts& p, const Detail& d, const glm::mat4& m) {
  p.add(kMetal, rbox(d, {-0.05f, -0.12f, 0}, {0.05f, 0.12f, 0.03f}, 0.005f), m);
  p.add(kMetal, rbox(d, {-0.015f, -0.02f, 0.03f}, {0.015f, 0.02f, 0.14f}, 0.005f), m);
  // Stick tilted away from the wall.
  const glm::mat4 local_stick = at({0, -0.15f, 0.14f}) * rot_x(0.35f);
  const glm::mat4 stick = m * local_stick;
  p.add(kWoodDark, make_frustum(0.015f, 0.025f, 0.4f, segs(d, 10)), stick);
  p.add(kMetal, make_torus(0.03f, 0.006f, segs(d, 12), 6), stick * at({0, 0.34f, 0}));
  p.add(kFlame, make_sphere(1.0f, segs(d, 10), 6),
        stick * scaled({0, 0.42f, 0}, {0.035f, 0.06f, 0.035f}));
  return glm::vec3(local_stick * glm::vec4(0, 0.45f, 0, 1));
}

void add_bookshelf(Parts& p, const Detail& d, Rng& rng, const glm::mat4& m, float w, float h,
                   int shelves, glm::vec3* slot) {
  const float depth = 0.3f;
  const float t = 0.03f;
  p.add(kWoodDark, rbox(d, {-w / 2, 0, 0}, {-w / 2 + t, h, depth}, 0.006f), m);
  p.add(kWoodDark, rbox(d, {w / 2 - t, 0, 0}, {w / 2, h, depth}, 0.006f), m);
  p.add(kWoodDark, make_box({-w / 2 + t, 0, 0}, {w / 2 - t, h, 0.015f}), m);
  const float spacing = (h - t) / static_cast<float>(shelves);
  for (int s = 0; s <= shelves; ++s) {
    const float y = static_cast<float>(s) * spacing;
    p.add(kWoodDark, rbox(d, {-w / 2 + t, y, 0.015f}, {w / 2 - t, y + t, depth}, 0.005f), m);
  }
  constexpr int kBookMats[] = {kBookRed, kBookGreen, kBookBlue, kBookBrown, kClothCream};
  const int slot_shelf = shelves / 2;
  for (int s = 0; s < shelves; ++s) {
    const float y = static_cast<float>(s) * spacing + t;
    float x = -w / 2 + t + 0.01f;
    const float end = w / 2 - t - 0.01f;
    const float slot_x = -0.1f * w;
    bool slot_done = slot == nullptr || s != slot_shelf;
    while (true) {
      if (!slot_done && x >= slot_x) {
        *slot = {x + 0.04f, y, 0.16f};
        x += 0.09f;
        slot_done = true;
        continue;
      }
      const float thick = rng.uniform(0.025f, 0.055f);
      if (x + thick > end) break;
      const float bh = std::min(spacing - t - 0.03f, rng.uniform(0.17f, 0.3f));
      const float bd = rng.uniform(0.15f, 0.24f);
      const int mat = kBookMats[rng.below(5)];
      if (rng.below(12) == 0 && x + bh < end) {
        // A book lying flat.
        p.add(mat, rbox(d, {x, y, 0.03f}, {x + bh, y + thick, 0.03f + bd}, 0.003f), m);
        x += bh + 0.005f;
      } else {
        p.add(mat, rbox(d, {x, y, 0.03f}, {x + thick, y + bh, 0.03f + bd}, 0.003f), m);
        x += thick + 0.002f;
      }
    }
  }
}

void add_bed(Parts& p, const Detail& d, const glm::mat4& m, int blanket_material) {
  // Head at local z = 0 (against the wall), foot at z = 2.0, 1.4 wide.
  p.add(kWoodDark, rbox(d, {-0.7f, 0.2f, 0.0f}, {0.7f, 0.4f, 2.0f}, 0.02f), m);
  p.add(kWoodDark, rbox(d, {-0.75f, 0.0f, 0.0f}, {0.75f, 1.1f, 0.08f}, 0.02f), m);
  p.add(kWoodDark, rbox(d, {-0.75f, 0.0f, 1.95f}, {0.75f, 0.7f, 2.03f}, 0.02f), m);
  const Geometry post = make_cylinder(0.05f, 0.2f, segs(d, 12));
  for (float x : {-0.65f, 0.65f}) p.add(kWoodDark, post, m * at({x, 0, 1.85f}));
  p.add(kClothCream, rbox(d, {-0.66f, 0.4f, 0.1f}, {0.66f, 0.58f, 1.93f}, 0.05f), m);
  p.add(blanket_material, rbox(d, {-0.7f, 0.45f, 0.7f}, {0.7f, 0.62f, 1.96f}, 0.05f), m);
  const Geometry pillow = make_sphere(1.0f, segs(d, 16), 8);
  p.add(kClothCream, pillow, m * scaled({-0.3f, 0.63f, 0.35f}, {0.26f, 0.07f, 0.17f}));
  p.add(kClothCream, pillow, m * scaled({0.3f, 0.63f, 0.35f}, {0.26f, 0.07f, 0.17f}));
}

void add_barrel(Parts& p, const Detail& d, const glm::mat4& m) {
  std::vector<glm::vec2> profile = {{0, 0}, {0.24f, 0}, {0.24f, 0}};
  const int rings = d.bevel_segments > 0 ? 8 : 3;
  for (int i = 0; i <= rings; ++i) {
    const float t = static_cast<float>(i) / static_cast<float>(rings);
    profile.emplace_back(0.24f + 0.05f * std::sin(kPi * t), 0.8f * t);
  }
  profile.insert(profile.end(), {{0.24f, 0.8f}, {0, 0.8f}});
  p.add(kWoodLight, make_lathe(profile, segs(d, 20)), m);
  for (float y : {0.12f, 0.68f}) {
    const float r = 0.24f + 0.05f * std::sin(kPi * y / 0.8f);
    p.add(kMetal, make_torus(r, 0.008f, segs(d, 20), 4), m * at({0, y, 0}));
  }
}

void add_crate(Parts& p, const Detail& d, const glm::mat4& m, float size) {
  const float s = size / 2;
  p.add(kWoodLight, rbox(d, {-s, 0, -s}, {s, size, s}, 0.01f), m);
  for (float z : {-s - 0.01f, s - 0.01f}) {
    p.add(kWoodDark, rbox(d, {-s, size * 0.45f, z}, {s, size * 0.55f, z + 0.02f}, 0.004f), m);
  }
}

void add_cupboard(Parts& p, const Detail& d, Rng& rng, const glm::mat4& m, float w, float h) {
  const float depth = 0.45f;
  // Closed lower part with doors, open shelves above with plates standing.
  p.add(kWoodDark, rbox(d, {-w / 2, 0, 0}, {w / 2, 0.9f, depth}, 0.015f), m);
  for (int i = 0; i < 2; ++i) {
    const float x0 = -w / 2 + 0.05f + static_cast<float>(i) * (w / 2 - 0.05f);
    p.add(kWoodLight,
          rbox(d, {x0, 0.08f, depth}, {x0 + w / 2 - 0.1f, 0.82f, depth + 0.02f}, 0.008f), m);
    p.add(kMetal, make_sphere(0.015f, segs(d, 8), 4),
          m * at({x0 + (i == 0 ? w / 2 - 0.16f : 0.06f), 0.5f, depth + 0.035f}));
  }
  const float t = 0.03f;
  p.add(kWoodDark, make_box({-w / 2, 0.9f, 0}, {w / 2, h, 0.02f}), m);
  p.add(kWoodDark, rbox(d, {-w / 2, 0.9f, 0}, {-w / 2 + t, h, 0.3f}, 0.005f), m);
  p.add(kWoodDark, rbox(d, {w / 2 - t, 0.9f, 0}, {w / 2, h, 0.3f}, 0.005f), m);
  const Geometry plate = make_plate(d);
  for (int s = 0; s < 3; ++s) {
    const float y = 0.9f + 0.04f + static_cast<float>(s) * (h - 0.95f) / 3.0f;
    p.add(kWoodDark, rbox(d, {-w / 2 + t, y - 0.03f, 0.02f}, {w / 2 - t, y, 0.3f}, 0.005f), m);
    // Plates standing on edge, leaning on the back.
    const int n = static_cast<int>((w - 0.2f) / 0.26f);
    for (int i = 0; i < n; ++i) {
      const float x = -w / 2 + 0.15f + static_cast<float>(i) * 0.26f + rng.uniform(0.0f, 0.02f);
      p.add(kCeramic, plate, m * at({x, y + 0.12f, 0.08f}) * rot_x(-1.35f) * at({0, -0.01f, 0}));
    }
  }
  p.add(kWoodDark, rbox(d, {-w / 2 - 0.02f, h, -0.0f}, {w / 2 + 0.02f, h + 0.05f, 0.34f}, 0.01f),
        m);
}

void add_armchair(Parts& p, const Detail& d, const glm::mat4& m, int cloth_material) {
  p.add(kWoodDark, rbox(d, {-0.4f, 0.0f, -0.4f}, {0.4f, 0.25f, 0.4f}, 0.03f), m);
  p.add(cloth_material, rbox(d, {-0.36f, 0.25f, -0.3f}, {0.36f, 0.42f, 0.38f}, 0.05f), m);
  p.add(cloth_material, rbox(d, {-0.4f, 0.25f, -0.42f}, {0.4f, 1.0f, -0.26f}, 0.05f), m);
  for (float x : {-0.4f, 0.28f}) {
    p.add(cloth_material, rbox(d, {x, 0.25f, -0.35f}, {x + 0.12f, 0.62f, 0.4f}, 0.04f), m);
  }
}

void add_carpet(Parts& p, const Detail& d, const glm::mat4& m, float w, float depth, int material) {
  p.add(material, rbox(d, {-w / 2, 0.0f, -depth / 2}, {w / 2, 0.012f, depth / 2}, 0.005f), m);
  // Fringes along the short sides.
  const Geometry fringe = make_box({-0.004f, 0, 0}, {0.004f, 0.004f, 0.06f});
  const int n = d.bevel_segments > 0 ? static_cast<int>(w / 0.05f) : 4;
  for (int i = 0; i < n; ++i) {
    const float x = -w / 2 + (static_cast<float>(i) + 0.5f) * w / static_cast<float>(n);
    p.add(kClothCream, fringe, m * at({x, 0.0f, depth / 2}));
    p.add(kClothCream, fringe, m * at({x, 0.0f, -depth / 2 - 0.06f}));
  }
}

void add_curtain(Parts& p, const Detail& d, const glm::mat4& m, float w, float y0, float y1,
                 int material) {
  const int nu = d.bevel_segments > 0 ? static_cast<int>(w / 0.02f) : 8;
  const int nv = d.bevel_segments > 0 ? 16 : 2;
  Geometry g = make_quad({-w / 2, y0, 0}, {w / 2, y0, 0}, {w / 2, y1, 0}, {-w / 2, y1, 0}, nu, nv);
  const float amp = 0.03f;
  const float k = 2.0f * kPi / 0.16f;
  for (std::size_t i = 0; i < g.positions.size(); ++i) {
    const float u = g.positions[i].x;
    g.positions[i].z += amp * (1.0f + std::sin(k * u));
    g.normals[i] = glm::normalize(glm::vec3(-amp * k * std::cos(k * u), 0.0f, 1.0f));
  }
  p.add(material, g, m);
  p.add(kMetal, make_cylinder(0.012f, w + 0.1f, segs(d, 8)),
        m * at({w / 2 + 0.05f, y1 + 0.03f, 0.04f}) * rot_z(kPi / 2));
}

Fireplace add_fireplace(Parts& p, const Detail& d, const glm::mat4& m, float w, float ceiling) {
  const float depth = 0.6f;
  const float pillar = 0.45f;
  const float opening_h = 0.9f;
  const float top = 1.4f;
  const float bw = 0.22f, bh = 0.1f, gap = 0.012f;
  const int rows = static_cast<int>(top / (bh + gap));
  for (int r = 0; r < rows; ++r) {
    const float y0 = static_cast<float>(r) * (bh + gap);
    const bool lintel = y0 >= opening_h;
    const float offset = (r % 2) ? bw / 2 : 0.0f;
    auto lay = [&](float xa, float xb) {
      float x = xa - offset;
      while (x < xb) {
        const float b0 = std::max(x, xa);
        const float b1 = std::min(x + bw, xb);
        if (b1 - b0 > 0.04f) {
          p.add(kBrick,
                rbox(d, {b0 + gap / 2, y0 + gap / 2, 0}, {b1 - gap / 2, y0 + bh + gap / 2, depth},
                     0.01f),
                m);
        }
        x += bw + gap;
      }
    };
    if (lintel) {
      lay(-w / 2, w / 2);
    } else {
      lay(-w / 2, -w / 2 + pillar);
      lay(w / 2 - pillar, w / 2);
    }
  }
  const float wall_top = static_cast<float>(rows) * (bh + gap);
  const float lintel_y = std::ceil(opening_h / (bh + gap)) * (bh + gap);  // first lintel row
  // Mortar core behind the bricks (closes the gaps), back of the hearth, hearth slab.
  // The core runs behind the pillars and the lintel only, leaving the hearth opening free.
  p.add(kStone,
        make_box({-w / 2 + 0.02f, 0, 0}, {-w / 2 + pillar - 0.02f, lintel_y, depth - 0.02f}), m);
  p.add(kStone, make_box({w / 2 - pillar + 0.02f, 0, 0}, {w / 2 - 0.02f, lintel_y, depth - 0.02f}),
        m);
  p.add(kStone,
        make_box({-w / 2 + 0.02f, lintel_y + 0.01f, 0}, {w / 2 - 0.02f, wall_top, depth - 0.02f}),
        m);
  p.add(kStone, make_box({-w / 2 + pillar, 0.05f, 0}, {w / 2 - pillar, lintel_y, 0.05f}), m);
  p.add(kStone, make_box({-w / 2 + pillar, -0.001f, 0}, {w / 2 - pillar, 0.05f, depth + 0.4f}), m);
  // Mantel and chimney breast.
  p.add(
      kWoodDark,
      rbox(d, {-w / 2 - 0.1f, wall_top, 0}, {w / 2 + 0.1f, wall_top + 0.08f, depth + 0.1f}, 0.015f),
      m);
  p.add(kPlaster,
        make_box({-w / 2 + 0.1f, wall_top + 0.08f, 0}, {w / 2 - 0.1f, ceiling, depth - 0.1f}), m);
  // Logs.
  const Geometry log = make_cylinder(0.06f, w - 2 * pillar - 0.3f, segs(d, 10));
  for (int i = 0; i < 3; ++i) {
    const glm::mat4 lm = m *
                         at({-(w - 2 * pillar - 0.3f) / 2, 0.11f + (i == 2 ? 0.1f : 0.0f),
                             0.25f + (i == 1 ? 0.14f : 0.0f) + (i == 2 ? 0.07f : 0.0f)}) *
                         rot_z(-kPi / 2);
    p.add(i == 2 ? kWoodDark : kEmber, log, lm);
  }
  return {{0.0f, 0.45f, 0.45f}, {0.0f, 0.12f, 0.35f}, wall_top + 0.08f, depth + 0.1f};
}

void add_bathtub(Parts& p, const Detail& d, const glm::mat4& m) {
  const float w = 1.6f, dp = 0.8f, h = 0.62f, t = 0.06f;
  p.add(kWoodLight, make_box({-w / 2 + t, 0, -dp / 2 + t}, {w / 2 - t, 0.45f, dp / 2 - t}), m);
  p.add(kWater,
        make_quad({-w / 2 + t, 0.5f, dp / 2 - t}, {w / 2 - t, 0.5f, dp / 2 - t},
                  {w / 2 - t, 0.5f, -dp / 2 + t}, {-w / 2 + t, 0.5f, -dp / 2 + t}, 4, 2),
        m);
  p.add(kWoodLight, rbox(d, {-w / 2, 0, -dp / 2}, {w / 2, h, -dp / 2 + t}, 0.02f), m);
  p.add(kWoodLight, rbox(d, {-w / 2, 0, dp / 2 - t}, {w / 2, h, dp / 2}, 0.02f), m);
  p.add(kWoodLight, rbox(d, {-w / 2, 0, -dp / 2 + t}, {-w / 2 + t, h, dp / 2 - t}, 0.02f), m);
  p.add(kWoodLight, rbox(d, {w / 2 - t, 0, -dp / 2 + t}, {w / 2, h, dp / 2 - t}, 0.02f), m);
  for (float y : {0.1f, 0.5f}) {
    p.add(
        kMetal,
        rbox(d, {-w / 2 - 0.01f, y, -dp / 2 - 0.01f}, {w / 2 + 0.01f, y + 0.03f, -dp / 2}, 0.004f),
        m);
    p.add(kMetal,
          rbox(d, {-w / 2 - 0.01f, y, dp / 2}, {w / 2 + 0.01f, y + 0.03f, dp / 2 + 0.01f}, 0.004f),
          m);
  }
}

void add_bucket(Parts& p, const Detail& d, const glm::mat4& m) {
  p.add(kWoodLight,
        make_lathe({{0, 0},
                    {0.13f, 0},
                    {0.13f, 0},
                    {0.16f, 0.3f},
                    {0.14f, 0.3f},
                    {0.11f, 0.03f},
                    {0, 0.03f}},
                   segs(d, 16)),
        m);
  p.add(kMetal, make_torus(0.148f, 0.006f, segs(d, 16), 4), m * at({0, 0.2f, 0}));
}

void add_stool(Parts& p, const Detail& d, const glm::mat4& m) {
  p.add(kWoodLight, make_cylinder(0.18f, 0.04f, segs(d, 16)), m * at({0, 0.42f, 0}));
  const Geometry leg = make_cylinder(0.02f, 0.42f, segs(d, 8));
  for (int i = 0; i < 3; ++i) {
    const float a = 2.0f * kPi * static_cast<float>(i) / 3.0f;
    p.add(kWoodDark, leg, m * at({0.12f * std::cos(a), 0, 0.12f * std::sin(a)}));
  }
}

void add_towel_rack(Parts& p, const Detail& d, const glm::mat4& m) {
  const Geometry post = make_cylinder(0.02f, 1.1f, segs(d, 8));
  p.add(kWoodDark, post, m * at({-0.4f, 0, 0}));
  p.add(kWoodDark, post, m * at({0.4f, 0, 0}));
  p.add(kWoodDark, make_cylinder(0.015f, 0.8f, segs(d, 8)),
        m * at({0.4f, 1.0f, 0}) * rot_z(kPi / 2));
  // A towel draped over the bar: two curtain-like halves.
  Parts towel;
  add_curtain(towel, d, glm::mat4(1.0f), 0.5f, 0.45f, 1.0f, kClothBlue);
  p.add(kClothBlue, towel.by_material[kClothBlue], m * at({0, 0, 0.02f}));
  p.add(kClothBlue, towel.by_material[kClothBlue],
        m * glm::rotate(glm::mat4(1.0f), kPi, glm::vec3(0, 1, 0)) * at({0, 0, 0.02f}));
}

void add_wine_rack(Parts& p, const Detail& d, Rng& rng, const glm::mat4& m, float w, float h) {
  const float depth = 0.35f;
  p.add(kWoodDark, rbox(d, {-w / 2, 0, 0}, {-w / 2 + 0.04f, h, depth}, 0.006f), m);
  p.add(kWoodDark, rbox(d, {w / 2 - 0.04f, 0, 0}, {w / 2, h, depth}, 0.006f), m);
  p.add(kWoodDark, make_box({-w / 2 + 0.04f, 0, 0}, {w / 2 - 0.04f, h, 0.015f}), m);
  const Geometry bottle = make_lathe({{0, 0},
                                      {0.038f, 0},
                                      {0.038f, 0},
                                      {0.038f, 0.2f},
                                      {0.014f, 0.25f},
                                      {0.013f, 0.31f},
                                      {0, 0.31f}},
                                     segs(d, 12));
  const int shelves = 4;
  for (int s = 0; s <= shelves; ++s) {
    const float y = static_cast<float>(s) * (h - 0.03f) / static_cast<float>(shelves);
    p.add(kWoodDark,
          rbox(d, {-w / 2 + 0.04f, y, 0.015f}, {w / 2 - 0.04f, y + 0.03f, depth}, 0.005f), m);
    if (s == shelves) break;
    for (float x = -w / 2 + 0.1f; x < w / 2 - 0.1f; x += 0.09f) {
      if (rng.below(5) == 0) continue;
      p.add(rng.below(3) == 0 ? kGlass : kBookGreen, bottle, m * at({x, y + 0.03f, 0.18f}));
    }
  }
}

Parts make_spell_book(const Detail& d) {
  Parts p;
  // Standing on the shelf: 0.06 thick (x), 0.28 tall, 0.21 deep (z), origin at the bottom centre.
  p.add(kBookPurple, rbox(d, {-0.03f, 0, -0.105f}, {0.03f, 0.28f, 0.105f}, 0.004f));
  p.add(kMetal, rbox(d, {-0.032f, 0.12f, 0.09f}, {0.032f, 0.16f, 0.108f}, 0.002f));
  return p;
}

const char* item_name(int which) {
  static constexpr const char* kNames[kItemCount] = {
      "herb_bundle", "silver_chalice", "dragon_scale", "mortar_pestle", "crystal_flask", "wand"};
  return kNames[which];
}

Parts make_item(const Detail& d, int which) {
  Parts p;
  const int s = segs(d, 16);
  switch (which) {
    case 0: {  // herb bundle lying on its side
      const Geometry stem = make_cylinder(0.006f, 0.22f, 6, 1);
      for (int i = 0; i < 5; ++i) {
        const float a = 2.0f * kPi * static_cast<float>(i) / 5.0f;
        p.add(kHerb, stem,
              at({0, 0.03f + 0.012f * std::sin(a), 0.012f * std::cos(a)}) * rot_z(-kPi / 2) *
                  at({0, -0.11f, 0}) * rot_x(0.1f * std::cos(a)));
      }
      p.add(kHerb, make_sphere(1.0f, s, 6), scaled({0.1f, 0.04f, 0}, {0.06f, 0.04f, 0.05f}));
      p.add(kClothCream, make_torus(0.02f, 0.004f, s, 4), at({-0.02f, 0.03f, 0}) * rot_z(kPi / 2));
      break;
    }
    case 1:  // silver chalice
      p.add(kMetal,
            make_lathe({{0, 0},
                        {0.045f, 0},
                        {0.045f, 0},
                        {0.04f, 0.008f},
                        {0.008f, 0.03f},
                        {0.008f, 0.09f},
                        {0.045f, 0.13f},
                        {0.05f, 0.18f},
                        {0.045f, 0.18f},
                        {0.0f, 0.12f}},
                       s),
            glm::mat4(1.0f));
      break;
    case 2:  // dragon scale: a flattened, tilted disc
      p.add(kScale, make_sphere(1.0f, s, 8), scaled({0, 0.02f, 0}, {0.11f, 0.02f, 0.08f}));
      break;
    case 3:  // mortar and pestle
      p.add(kStone,
            make_lathe({{0, 0},
                        {0.07f, 0},
                        {0.07f, 0},
                        {0.08f, 0.08f},
                        {0.065f, 0.085f},
                        {0.05f, 0.03f},
                        {0, 0.03f}},
                       s),
            glm::mat4(1.0f));
      p.add(kStone, make_frustum(0.012f, 0.02f, 0.16f, s / 2 + 4),
            at({0.02f, 0.04f, 0}) * rot_z(-0.4f));
      break;
    case 4:  // crystal flask
      p.add(kGlass,
            make_lathe({{0, 0},
                        {0.05f, 0},
                        {0.05f, 0},
                        {0.07f, 0.06f},
                        {0.05f, 0.12f},
                        {0.018f, 0.15f},
                        {0.018f, 0.22f},
                        {0, 0.22f}},
                       s),
            glm::mat4(1.0f));
      p.add(kWoodLight, make_cylinder(0.015f, 0.03f, 8), at({0, 0.22f, 0}));
      break;
    default:  // wand lying on the surface
      p.add(kWoodDark, make_frustum(0.008f, 0.004f, 0.32f, 8),
            at({-0.16f, 0.008f, 0}) * rot_z(-kPi / 2));
      p.add(kScale, make_sphere(0.012f, 8, 5), at({0.165f, 0.01f, 0}));
      break;
  }
  return p;
}

}  // namespace lightpatch::inn
