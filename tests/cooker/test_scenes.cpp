#include "test_scenes.h"

#include "lightpatch/cooker/texel_builder.h"
#include "lightpatch/cooker/unwrap.h"

namespace lightpatch::test {

using namespace cooker;

int add_quad(Scene& scene, const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2,
             const glm::vec3& p3, const std::string& name, int object, int material) {
  MeshInstance m;
  m.name = name;
  m.object = object;
  m.material = material;
  m.positions = {p0, p1, p2, p3};
  const glm::vec3 n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
  m.normals = {n, n, n, n};
  m.indices = {0, 1, 2, 0, 2, 3};
  scene.meshes.push_back(std::move(m));
  const int index = static_cast<int>(scene.meshes.size()) - 1;
  if (object >= 0) scene.objects[static_cast<size_t>(object)].meshes.push_back(index);
  return index;
}

int add_box(Scene& scene, const glm::vec3& lo, const glm::vec3& hi, const std::string& name,
            int object, int material) {
  MeshInstance m;
  m.name = name;
  m.object = object;
  m.material = material;
  // Six faces, four vertices each, counter-clockwise from outside.
  const glm::vec3 c[8] = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z},
                          {lo.x, hi.y, lo.z}, {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z},
                          {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}};
  const int faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                           {3, 7, 6, 2}, {0, 4, 7, 3}, {1, 2, 6, 5}};
  for (const auto& f : faces) {
    const uint32_t base = static_cast<uint32_t>(m.positions.size());
    const glm::vec3 n = glm::normalize(glm::cross(c[f[1]] - c[f[0]], c[f[2]] - c[f[0]]));
    for (int k = 0; k < 4; ++k) {
      m.positions.push_back(c[f[k]]);
      m.normals.push_back(n);
    }
    for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m.indices.push_back(base + i);
  }
  scene.meshes.push_back(std::move(m));
  const int index = static_cast<int>(scene.meshes.size()) - 1;
  if (object >= 0) scene.objects[static_cast<size_t>(object)].meshes.push_back(index);
  return index;
}

void add_closed_room(Scene& scene, const glm::vec3& lo, const glm::vec3& hi, float wall,
                     const std::string& name) {
  // Floor, ceiling, and four walls as slabs that overlap at the edges.
  add_box(scene, {lo.x - wall, lo.y - wall, lo.z - wall}, {hi.x + wall, lo.y, hi.z + wall},
          name + "_0");
  add_box(scene, {lo.x - wall, hi.y, lo.z - wall}, {hi.x + wall, hi.y + wall, hi.z + wall},
          name + "_1");
  add_box(scene, {lo.x - wall, lo.y - wall, lo.z - wall}, {lo.x, hi.y + wall, hi.z + wall},
          name + "_2");
  add_box(scene, {hi.x, lo.y - wall, lo.z - wall}, {hi.x + wall, hi.y + wall, hi.z + wall},
          name + "_3");
  add_box(scene, {lo.x - wall, lo.y - wall, lo.z - wall}, {hi.x + wall, hi.y + wall, lo.z},
          name + "_4");
  add_box(scene, {lo.x - wall, lo.y - wall, hi.z}, {hi.x + wall, hi.y + wall, hi.z + wall},
          name + "_5");
}

int add_object_box(Scene& scene, const glm::vec3& lo, const glm::vec3& hi,
                   const std::string& name) {
  Object o;
  o.name = name;
  scene.objects.push_back(o);
  const int index = static_cast<int>(scene.objects.size()) - 1;
  add_box(scene, lo, hi, name, index);
  return index;
}

Light point_light(const std::string& name, const glm::vec3& pos, float intensity, bool semi) {
  Light l;
  l.name = name;
  l.type = LightType::kPoint;
  l.position = pos;
  l.intensity = intensity;
  l.semi_dynamic = semi;
  return l;
}

Light spot_light(const std::string& name, const glm::vec3& pos, const glm::vec3& dir,
                 float intensity, float inner, float outer, bool semi) {
  Light l = point_light(name, pos, intensity, semi);
  l.type = LightType::kSpot;
  l.direction = glm::normalize(dir);
  l.inner_cone = inner;
  l.outer_cone = outer;
  return l;
}

Light directional_light(const std::string& name, const glm::vec3& dir, float lux, bool semi) {
  Light l;
  l.name = name;
  l.type = LightType::kDirectional;
  l.direction = glm::normalize(dir);
  l.intensity = lux;
  l.semi_dynamic = semi;
  return l;
}

void finish(Scene& scene) {
  if (scene.materials.empty()) scene.materials.push_back(Material{});
  scene.compute_bounds();
}

TexelSet grid_texels(int w, int h, const glm::vec3& origin, const glm::vec3& u, const glm::vec3& v,
                     const glm::vec3& n) {
  TexelSet t;
  t.width = w;
  t.height = h;
  const size_t count = size_t(w) * size_t(h);
  t.position.resize(count);
  t.normal.assign(count, glm::normalize(n));
  t.albedo.assign(count, glm::vec3(0.8f));
  t.valid.assign(count, 1);
  t.mesh.assign(count, 0);
  t.region.assign(count, 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      t.position[t.index(x, y)] = origin +
                                  u * ((static_cast<float>(x) + 0.5f) / static_cast<float>(w)) +
                                  v * ((static_cast<float>(y) + 0.5f) / static_cast<float>(h));
    }
  }
  return t;
}

Layout bare_layout(int w, int h) {
  Layout l;
  l.width = w;
  l.height = h;
  return l;
}

Prepared prepare(const cooker::Scene& scene, int lightmap_size) {
  Prepared p;
  cooker::LayoutOptions lo;
  lo.lightmap_size = lightmap_size;
  p.layout = cooker::build_layout(scene, lo);
  p.tracer = cooker::make_embree_tracer(scene);
  p.texels = cooker::build_texels(scene, p.layout, p.tracer.get());
  return p;
}

}  // namespace lightpatch::test
