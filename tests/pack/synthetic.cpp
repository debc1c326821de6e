#include "synthetic.h"

#include <algorithm>
#include <cmath>

#include "lightpatch/cooker/pack_builder.h"
#include "lightpatch/cooker/report.h"

namespace lightpatch::test {

using namespace cooker;

namespace {

// Small deterministic generator (no <random>: identical sequences on every standard library).
struct Lcg {
  uint64_t s;
  float next() {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    return float((s >> 40) & 0xFFFFFF) / float(0x1000000);
  }
};

}  // namespace

Synthetic make_synthetic(const SyntheticOptions& o) {
  Synthetic s;
  Lcg rng{o.seed * 0x9E3779B97F4A7C15ull + 7};
  const int w = o.width, h = o.height;
  s.layout.width = w;
  s.layout.height = h;
  // Four regions in a 2x2 grid with a one-texel empty border; the bottom-right one stays black in
  // the base map.
  const int hw = w / 2, hh = h / 2;
  const Rect rects[4] = {{1, 1, hw - 2, hh - 2},
                         {hw + 1, 1, w - hw - 2, hh - 2},
                         {1, hh + 1, hw - 2, h - hh - 2},
                         {hw + 1, hh + 1, w - hw - 2, h - hh - 2}};
  for (int r = 0; r < 4; ++r) {
    Region region;
    region.name = "region_" + std::to_string(r);
    region.object = r < o.objects ? r : -1;
    region.rect = rects[r];
    region.meshes = {r};
    s.layout.regions.push_back(region);
    if (o.with_meshes) {
      MeshInstance mi;
      mi.name = region.name;
      mi.node_index = r;
      mi.object = region.object;
      mi.positions = {glm::vec3(0), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(1, 1, 0)};
      mi.indices = {0, 1, 2, 2, 1, 3};
      s.scene.meshes.push_back(mi);
      MeshLayout ml;
      ml.source_vertex = {0, 1, 2, 3};
      const float u0 = float(rects[r].x) / w, v0 = float(rects[r].y) / h;
      const float u1 = float(rects[r].x + rects[r].w) / w, v1 = float(rects[r].y + rects[r].h) / h;
      ml.uv = {{u0, v0}, {u1, v0}, {u0, v1}, {u1, v1}};
      ml.indices = mi.indices;
      if (r % 2 == 1) {  // placed by its own TEXCOORD_1 (the unit square), scale and offset
        s.scene.meshes.back().uv1 = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
        ml.from_uv1 = true;
        ml.uv1_scale_offset = glm::vec4(u1 - u0, v1 - v0, u0, v0);
      }
      s.layout.meshes.push_back(ml);
    }
  }
  for (int i = 0; i < o.objects; ++i) {
    Object obj;
    obj.name = "object_" + std::string(1, char('a' + i));
    obj.node_index = i;
    if (o.with_meshes && i < 4) obj.meshes = {i};
    s.scene.objects.push_back(obj);
  }
  // A static light (not semi-dynamic) and the semi-dynamic ones, very bright beside dim.
  Light fixed;
  fixed.name = "sun";
  fixed.intensity = 2.0f;
  s.scene.lights.push_back(fixed);
  for (int i = 0; i < o.lights; ++i) {
    Light l;
    l.name = "lamp_" + std::to_string(i);
    l.semi_dynamic = true;
    // Two statements: the order of evaluation of function arguments differs between compilers.
    const float green = 0.5f + 0.5f * rng.next();
    const float blue = 0.3f + 0.7f * rng.next();
    l.color = glm::vec3(1.0f, green, blue);
    l.intensity = i == 0 ? 40.0f : 1.0f + 4.0f * rng.next();
    s.scene.lights.push_back(l);
    s.maps.lights.push_back(int(s.scene.lights.size()) - 1);
  }

  // Base: a gradient over the first three regions, black in the last.
  s.maps.base = FloatImage(w, h, 3);
  float base_max = 0.0f;
  for (int r = 0; r < 3; ++r) {
    const Rect& rc = rects[r];
    for (int y = rc.y; y < rc.y + rc.h; ++y) {
      for (int x = rc.x; x < rc.x + rc.w; ++x) {
        const float t = 0.2f + 0.8f * float(x - rc.x + y - rc.y) / float(rc.w + rc.h);
        s.maps.base.at(x, y, 0) = 0.5f * t;
        s.maps.base.at(x, y, 1) = 0.45f * t;
        s.maps.base.at(x, y, 2) = 0.3f * t * t;
        base_max = std::max(base_max, 0.5f * t);
      }
    }
  }
  s.maps.output_step = base_max / 255.0f;

  // Contributions: an inverse-square blob per light, clipped to zero at a radius (the light's
  // reach), inside every region; the first tinted_lights optionally tinted (3 channels).
  for (int i = 0; i < o.lights; ++i) {
    const int ch = (i < o.tinted_lights && o.three_channel_light) ? 3 : 1;
    FloatImage c(w, h, ch);
    const float cx = w * (0.2f + 0.6f * rng.next()), cy = h * (0.2f + 0.6f * rng.next());
    const float radius = 0.35f * float(std::min(w, h)) * (0.6f + 0.8f * rng.next());
    for (const Region& region : s.layout.regions) {
      const Rect& rc = region.rect;
      for (int y = rc.y; y < rc.y + rc.h; ++y) {
        for (int x = rc.x; x < rc.x + rc.w; ++x) {
          const float dx = x + 0.5f - cx, dy = y + 0.5f - cy;
          const float d2 = dx * dx + dy * dy;
          if (d2 > radius * radius) continue;
          const float e = 0.02f / (1.0f + d2 / 16.0f) * (1.0f - d2 / (radius * radius));
          for (int k = 0; k < ch; ++k) c.at(x, y, k) = e * (k == 0 ? 1.0f : k == 1 ? 0.8f : 0.6f);
        }
      }
    }
    s.maps.contribution.push_back(c);
  }
  // Shadows: object o darkens a disc of light l's contribution, with a negative bounce rim.
  for (int l = 0; l < o.lights; ++l) {
    for (int ob = 0; ob < o.objects; ++ob) {
      if ((l + ob) % 3 == 2) continue;  // a pair that does not interact
      const FloatImage& c = s.maps.contribution[size_t(l)];
      ShadowMap sm;
      sm.light = l;
      sm.object = ob;
      sm.map = FloatImage(w, h, c.channels);
      const float cx = w * (0.2f + 0.6f * rng.next()), cy = h * (0.2f + 0.6f * rng.next());
      const float r0 = 3.0f + 6.0f * rng.next(), r1 = r0 + 2.0f;
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          const float d = std::hypot(x + 0.5f - cx, y + 0.5f - cy);
          for (int k = 0; k < c.channels; ++k) {
            const float v = c.at(x, y, k);
            if (d < r0)
              sm.map.at(x, y, k) = 0.9f * v;
            else if (d < r1)
              sm.map.at(x, y, k) = -0.1f * v;  // bounce off the object
          }
        }
      }
      s.maps.shadows.push_back(sm);
    }
  }
  s.scene.compute_bounds();
  return s;
}

std::vector<uint8_t> build_small_pack() {
  const Synthetic s = make_synthetic(SyntheticOptions{});
  Report report;
  return build_pack(s.scene, s.layout, s.maps, PackOptions{}, report);
}

std::vector<uint8_t> build_tiny_pack() {
  SyntheticOptions o;
  o.width = 16;
  o.height = 8;
  o.lights = 1;
  o.objects = 1;
  o.three_channel_light = false;
  o.with_meshes = false;
  o.seed = 3;
  const Synthetic s = make_synthetic(o);
  Report report;
  return build_pack(s.scene, s.layout, s.maps, PackOptions{}, report);
}

}  // namespace lightpatch::test
