#include "lightpatch/scenegen/shapes.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace lightpatch::scenegen {
namespace {

constexpr float kPi = 3.14159265358979323846f;

// Appends a grid of quads origin + u·s + v·t, s and t in `us` / `vs` (increasing fractions in
// [0, 1]), facing u × v. `shape` maps a grid point to (position, normal).
template <typename Shape>
void add_grid(Geometry& g, glm::vec3 origin, glm::vec3 u, glm::vec3 v, const std::vector<float>& us,
              const std::vector<float>& vs, Shape shape) {
  const auto base = static_cast<std::uint32_t>(g.positions.size());
  const auto nu = static_cast<std::uint32_t>(us.size());
  for (float t : vs) {
    for (float s : us) {
      const auto [p, n] = shape(origin + u * s + v * t);
      g.positions.push_back(p);
      g.normals.push_back(n);
    }
  }
  for (std::uint32_t j = 0; j + 1 < vs.size(); ++j) {
    for (std::uint32_t i = 0; i + 1 < nu; ++i) {
      const std::uint32_t a = base + j * nu + i;
      const std::uint32_t b = a + 1;
      const std::uint32_t c = a + nu + 1;
      const std::uint32_t d = a + nu;
      g.indices.insert(g.indices.end(), {a, b, c, a, c, d});
    }
  }
}

std::vector<float> uniform_steps(int n) {
  std::vector<float> r(static_cast<std::size_t>(n) + 1);
  for (int i = 0; i <= n; ++i)
    r[static_cast<std::size_t>(i)] = static_cast<float>(i) / static_cast<float>(n);
  return r;
}

struct BoxFace {
  glm::vec3 origin_select;  // 0: take min, 1: take max, per axis
  glm::vec3 u, v;           // unit axes, u × v = outward normal
};

constexpr BoxFace kBoxFaces[6] = {
    {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},  // +X
    {{0, 0, 0}, {0, 0, 1}, {0, 1, 0}},  // -X
    {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}},  // +Y
    {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}},  // -Y
    {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},  // +Z
    {{0, 0, 0}, {0, 1, 0}, {1, 0, 0}},  // -Z
};

void require(bool ok, const char* what) {
  if (!ok) throw std::invalid_argument(what);
}

}  // namespace

Geometry make_box(glm::vec3 min, glm::vec3 max, Facing facing, int subdivisions) {
  require(subdivisions >= 1, "make_box: subdivisions must be >= 1");
  require(min.x < max.x && min.y < max.y && min.z < max.z, "make_box: min must be below max");
  const glm::vec3 size = max - min;
  const std::vector<float> steps = uniform_steps(subdivisions);
  Geometry g;
  for (const BoxFace& f : kBoxFaces) {
    const glm::vec3 origin = min + f.origin_select * size;
    const glm::vec3 normal = glm::cross(f.u, f.v);
    add_grid(g, origin, f.u * size, f.v * size, steps, steps, [&](glm::vec3 p) {
      return std::pair{p, normal};
    });
  }
  if (facing == Facing::kInward) g.flip();
  return g;
}

Geometry make_rounded_box(glm::vec3 min, glm::vec3 max, float bevel, int segments) {
  require(segments >= 1, "make_rounded_box: segments must be >= 1");
  require(min.x < max.x && min.y < max.y && min.z < max.z,
          "make_rounded_box: min must be below max");
  const glm::vec3 size = max - min;
  const float r = std::min(bevel, 0.45f * std::min({size.x, size.y, size.z}));
  if (!(r > 0.0f)) return make_box(min, max);
  const glm::vec3 inner_min = min + r;
  const glm::vec3 inner_max = max - r;
  Geometry g;
  for (const BoxFace& f : kBoxFaces) {
    const glm::vec3 origin = min + f.origin_select * size;
    const float len_u = glm::dot(f.u, size);
    const float len_v = glm::dot(f.v, size);
    // Steps spaced so that the projected bevel vertices are evenly spread in angle (0..45° on
    // each face; the neighbouring face covers the other half of the edge).
    auto steps = [&](float len) {
      std::vector<float> s;
      for (int i = 0; i <= segments; ++i) {
        const float angle =
            0.25f * kPi * static_cast<float>(segments - i) / static_cast<float>(segments);
        s.push_back((r - r * std::tan(angle)) / len);
      }
      for (int i = segments; i >= 0; --i) {
        const float angle =
            0.25f * kPi * static_cast<float>(segments - i) / static_cast<float>(segments);
        s.push_back(1.0f - (r - r * std::tan(angle)) / len);
      }
      s.front() = 0.0f;
      s.back() = 1.0f;
      return s;
    };
    add_grid(g, origin, f.u * size, f.v * size, steps(len_u), steps(len_v), [&](glm::vec3 p) {
      const glm::vec3 c = glm::clamp(p, inner_min, inner_max);
      const glm::vec3 n = glm::normalize(p - c);
      return std::pair{c + n * r, n};
    });
  }
  return g;
}

Geometry make_quad(glm::vec3 p0, glm::vec3 p1, glm::vec3 p2, glm::vec3 p3, int nu, int nv,
                   bool with_uv) {
  require(nu >= 1 && nv >= 1, "make_quad: subdivisions must be >= 1");
  const glm::vec3 c = glm::cross(p1 - p0, p3 - p0) + glm::cross(p3 - p2, p1 - p2);
  require(glm::length(c) > 0.0f, "make_quad: degenerate quad");
  const glm::vec3 normal = glm::normalize(c);
  Geometry g;
  const std::vector<float> us = uniform_steps(nu);
  const std::vector<float> vs = uniform_steps(nv);
  for (float t : vs) {
    for (float s : us) {
      const glm::vec3 bottom = p0 + (p1 - p0) * s;
      const glm::vec3 top = p3 + (p2 - p3) * s;
      g.positions.push_back(bottom + (top - bottom) * t);
      g.normals.push_back(normal);
      if (with_uv) g.uv0.emplace_back(s, t);
    }
  }
  const auto w = static_cast<std::uint32_t>(nu + 1);
  for (std::uint32_t j = 0; j < static_cast<std::uint32_t>(nv); ++j) {
    for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(nu); ++i) {
      const std::uint32_t a = j * w + i;
      g.indices.insert(g.indices.end(), {a, a + 1, a + w + 1, a, a + w + 1, a + w});
    }
  }
  return g;
}

Geometry make_plane(float size_x, float size_z, int nx, int nz, bool with_uv) {
  const float hx = 0.5f * size_x;
  const float hz = 0.5f * size_z;
  return make_quad({-hx, 0, hz}, {hx, 0, hz}, {hx, 0, -hz}, {-hx, 0, -hz}, nx, nz, with_uv);
}

Geometry make_lathe(const std::vector<glm::vec2>& profile, int segments) {
  require(segments >= 3, "make_lathe: segments must be >= 3");
  require(profile.size() >= 2, "make_lathe: profile needs at least two points");
  for (const glm::vec2& p : profile) require(p.x >= 0.0f, "make_lathe: negative radius");
  Geometry g;
  const auto seg = static_cast<std::uint32_t>(segments);
  // Split the profile into smooth runs at repeated points (creases).
  std::size_t start = 0;
  while (start + 1 < profile.size()) {
    std::size_t end = start + 1;
    while (end < profile.size() && glm::length(profile[end] - profile[end - 1]) > 1e-7f) ++end;
    // Run is profile[start, end).
    const std::size_t n = end - start;
    if (n >= 2) {
      std::vector<glm::vec2> seg_normals(n - 1);
      for (std::size_t i = 0; i + 1 < n; ++i) {
        const glm::vec2 d = profile[start + i + 1] - profile[start + i];
        seg_normals[i] = glm::normalize(glm::vec2(d.y, -d.x));
      }
      const auto base = static_cast<std::uint32_t>(g.positions.size());
      for (std::size_t i = 0; i < n; ++i) {
        glm::vec2 n2;
        if (i == 0) {
          n2 = seg_normals[0];
        } else if (i + 1 == n) {
          n2 = seg_normals[n - 2];
        } else {
          const glm::vec2 sum = seg_normals[i - 1] + seg_normals[i];
          n2 = glm::length(sum) > 1e-6f ? glm::normalize(sum) : seg_normals[i];
        }
        const glm::vec2 p = profile[start + i];
        for (std::uint32_t s = 0; s < seg; ++s) {
          const float phi = 2.0f * kPi * static_cast<float>(s) / static_cast<float>(seg);
          const float c = std::cos(phi);
          const float si = std::sin(phi);
          g.positions.emplace_back(p.x * c, p.y, -p.x * si);
          g.normals.push_back(glm::normalize(glm::vec3(n2.x * c, n2.y, -n2.x * si)));
        }
      }
      for (std::uint32_t i = 0; i + 1 < n; ++i) {
        const bool low_apex = profile[start + i].x <= 0.0f;
        const bool high_apex = profile[start + i + 1].x <= 0.0f;
        if (low_apex && high_apex) continue;
        for (std::uint32_t s = 0; s < seg; ++s) {
          const std::uint32_t s1 = (s + 1) % seg;
          const std::uint32_t a = base + i * seg + s;
          const std::uint32_t b = base + i * seg + s1;
          const std::uint32_t c = base + (i + 1) * seg + s1;
          const std::uint32_t d = base + (i + 1) * seg + s;
          if (!low_apex) g.indices.insert(g.indices.end(), {a, b, c});
          if (!high_apex) g.indices.insert(g.indices.end(), {a, c, d});
        }
      }
    }
    start = end;
  }
  // Drop vertices no triangle uses (apex rings of fully degenerate runs are rare; keep it simple
  // by compacting whatever is unused so that every vertex belongs to a triangle).
  std::vector<std::uint32_t> remap(g.positions.size(), UINT32_MAX);
  Geometry out;
  for (std::uint32_t i : g.indices) {
    if (remap[i] == UINT32_MAX) {
      remap[i] = static_cast<std::uint32_t>(out.positions.size());
      out.positions.push_back(g.positions[i]);
      out.normals.push_back(g.normals[i]);
    }
    out.indices.push_back(remap[i]);
  }
  return out;
}

Geometry make_cylinder(float radius, float height, int segments, int rings, bool caps) {
  require(radius > 0.0f && height > 0.0f, "make_cylinder: radius and height must be positive");
  require(rings >= 1, "make_cylinder: rings must be >= 1");
  std::vector<glm::vec2> profile;
  if (caps) profile.insert(profile.end(), {{0.0f, 0.0f}, {radius, 0.0f}});
  for (int i = 0; i <= rings; ++i) {
    profile.emplace_back(radius, height * static_cast<float>(i) / static_cast<float>(rings));
  }
  if (caps) profile.insert(profile.end(), {{radius, height}, {0.0f, height}});
  return make_lathe(profile, segments);
}

Geometry make_frustum(float r0, float r1, float height, int segments, bool caps) {
  require(r0 >= 0.0f && r1 >= 0.0f && r0 + r1 > 0.0f && height > 0.0f,
          "make_frustum: bad dimensions");
  std::vector<glm::vec2> profile;
  if (caps && r0 > 0.0f) profile.insert(profile.end(), {{0.0f, 0.0f}, {r0, 0.0f}});
  profile.insert(profile.end(), {{r0, 0.0f}, {r1, height}});
  if (caps && r1 > 0.0f) profile.insert(profile.end(), {{r1, height}, {0.0f, height}});
  return make_lathe(profile, segments);
}

Geometry make_sphere(float radius, int segments, int rings) {
  require(radius > 0.0f, "make_sphere: radius must be positive");
  require(rings >= 2, "make_sphere: rings must be >= 2");
  Geometry g;
  const auto seg = static_cast<std::uint32_t>(segments);
  require(segments >= 3, "make_sphere: segments must be >= 3");
  // Rings 1..rings-1 are full; the poles are single vertices.
  g.positions.emplace_back(0.0f, -radius, 0.0f);
  g.normals.emplace_back(0.0f, -1.0f, 0.0f);
  for (int j = 1; j < rings; ++j) {
    const float theta = kPi * static_cast<float>(j) / static_cast<float>(rings);
    for (std::uint32_t s = 0; s < seg; ++s) {
      const float phi = 2.0f * kPi * static_cast<float>(s) / static_cast<float>(seg);
      const glm::vec3 n(std::sin(theta) * std::cos(phi), -std::cos(theta),
                        -std::sin(theta) * std::sin(phi));
      g.positions.push_back(n * radius);
      g.normals.push_back(n);
    }
  }
  const auto top = static_cast<std::uint32_t>(g.positions.size());
  g.positions.emplace_back(0.0f, radius, 0.0f);
  g.normals.emplace_back(0.0f, 1.0f, 0.0f);
  const auto full = static_cast<std::uint32_t>(rings - 1);
  for (std::uint32_t s = 0; s < seg; ++s) {
    const std::uint32_t s1 = (s + 1) % seg;
    g.indices.insert(g.indices.end(), {0, 1 + s1, 1 + s});
    for (std::uint32_t j = 0; j + 1 < full; ++j) {
      const std::uint32_t a = 1 + j * seg + s;
      const std::uint32_t b = 1 + j * seg + s1;
      const std::uint32_t c = 1 + (j + 1) * seg + s1;
      const std::uint32_t d = 1 + (j + 1) * seg + s;
      g.indices.insert(g.indices.end(), {a, b, c, a, c, d});
    }
    const std::uint32_t last = 1 + (full - 1) * seg;
    g.indices.insert(g.indices.end(), {last + s, last + s1, top});
  }
  return g;
}

Geometry make_torus(float major, float minor, int segments, int tube_segments) {
  require(major > minor && minor > 0.0f, "make_torus: need major > minor > 0");
  require(segments >= 3 && tube_segments >= 3, "make_torus: segments must be >= 3");
  Geometry g;
  const auto seg = static_cast<std::uint32_t>(segments);
  const auto tube = static_cast<std::uint32_t>(tube_segments);
  for (std::uint32_t s = 0; s < seg; ++s) {
    const float phi = 2.0f * kPi * static_cast<float>(s) / static_cast<float>(seg);
    const glm::vec3 radial(std::cos(phi), 0.0f, -std::sin(phi));
    for (std::uint32_t t = 0; t < tube; ++t) {
      const float theta = 2.0f * kPi * static_cast<float>(t) / static_cast<float>(tube);
      const glm::vec3 n = radial * std::cos(theta) + glm::vec3(0.0f, std::sin(theta), 0.0f);
      g.positions.push_back(radial * major + n * minor);
      g.normals.push_back(n);
    }
  }
  for (std::uint32_t s = 0; s < seg; ++s) {
    const std::uint32_t s1 = (s + 1) % seg;
    for (std::uint32_t t = 0; t < tube; ++t) {
      const std::uint32_t t1 = (t + 1) % tube;
      const std::uint32_t a = s * tube + t;
      const std::uint32_t b = s1 * tube + t;
      const std::uint32_t c = s1 * tube + t1;
      const std::uint32_t d = s * tube + t1;
      g.indices.insert(g.indices.end(), {a, b, c, a, c, d});
    }
  }
  return g;
}

}  // namespace lightpatch::scenegen
