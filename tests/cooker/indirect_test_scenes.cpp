#include "indirect_test_scenes.h"

#include <cmath>

namespace lightpatch::test {

using namespace cooker;

Scene furnace_box(float rho) {
  Scene s;
  Material m;
  m.albedo = glm::vec3(rho);
  s.materials.push_back(m);
  add_closed_room(s, {-1, -1, -1}, {1, 1, 1}, 0.2f, "box");
  finish(s);
  return s;
}

Light furnace_lamp(bool semi_dynamic) {
  return point_light("lamp", {0.13f, 0.21f, -0.17f}, 1.0f, semi_dynamic);
}

Scene emissive_panel(const glm::vec3& radiance, float panel_albedo) {
  Scene scene;
  Material plain;
  Material glow;
  glow.albedo = glm::vec3(panel_albedo);
  glow.emissive = radiance;
  scene.materials = {plain, glow};
  add_quad(scene, {-5, 0, -5}, {-5, 0, 5}, {5, 0, 5}, {5, 0, -5}, "floor");
  add_quad(scene, {-1, 1, -1}, {1, 1, -1}, {1, 1, 1}, {-1, 1, 1}, "panel", -1, 1);
  finish(scene);
  return scene;
}

double emissive_panel_irradiance(double radiance) {
  const double pi = 3.14159265358979323846;
  const double corner = (1.0 / pi) * (1.0 / std::sqrt(2.0)) * std::atan(1.0 / std::sqrt(2.0));
  return pi * 4.0 * corner * radiance;
}

namespace {

struct Face {
  glm::vec3 o, u, v, n;
};

void faces(const glm::vec3& lo, const glm::vec3& hi, Face out[6]) {
  const glm::vec3 d = hi - lo;
  out[0] = {lo, {d.x, 0, 0}, {0, 0, d.z}, {0, 1, 0}};
  out[1] = {{lo.x, hi.y, lo.z}, {d.x, 0, 0}, {0, 0, d.z}, {0, -1, 0}};
  out[2] = {lo, {0, d.y, 0}, {0, 0, d.z}, {1, 0, 0}};
  out[3] = {{hi.x, lo.y, lo.z}, {0, d.y, 0}, {0, 0, d.z}, {-1, 0, 0}};
  out[4] = {lo, {d.x, 0, 0}, {0, d.y, 0}, {0, 0, 1}};
  out[5] = {{lo.x, lo.y, hi.z}, {d.x, 0, 0}, {0, d.y, 0}, {0, 0, -1}};
}

}  // namespace

TexelSet box_texels(const glm::vec3& lo, const glm::vec3& hi, int n) {
  Face f[6];
  faces(lo, hi, f);
  TexelSet all;
  all.width = n;
  all.height = 6 * n;
  for (const Face& face : f) {
    const TexelSet t = grid_texels(n, n, face.o, face.u, face.v, face.n);
    all.position.insert(all.position.end(), t.position.begin(), t.position.end());
    all.normal.insert(all.normal.end(), t.normal.begin(), t.normal.end());
    all.albedo.insert(all.albedo.end(), t.albedo.begin(), t.albedo.end());
    all.valid.insert(all.valid.end(), t.valid.begin(), t.valid.end());
    all.mesh.insert(all.mesh.end(), t.mesh.begin(), t.mesh.end());
    all.region.insert(all.region.end(), t.region.begin(), t.region.end());
  }
  return all;
}

float box_texel_area(const glm::vec3& lo, const glm::vec3& hi, int n, size_t t) {
  Face f[6];
  faces(lo, hi, f);
  const Face& face = f[t / (size_t(n) * size_t(n))];
  return glm::length(glm::cross(face.u, face.v)) / float(n * n);
}

}  // namespace lightpatch::test
