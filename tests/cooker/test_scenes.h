// Scenes built in code for the cooker's tests: quads, boxes, closed rooms, and texel grids that
// sample a rectangle directly (for analytic checks that need no unwrap).
#pragma once

#include <glm/glm.hpp>

#include <memory>
#include <string>

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/scene.h"
#include "lightpatch/cooker/texels.h"
#include "lightpatch/cooker/tracer.h"

namespace lightpatch::test {

// Adds a quad p0 p1 p2 p3 (counter-clockwise seen from the side its normal faces) as one mesh.
// Returns the mesh index. `object` >= 0 attaches it to Scene::objects[object].
int add_quad(cooker::Scene& scene, const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2,
             const glm::vec3& p3, const std::string& name, int object = -1, int material = 0);

// Adds an axis-aligned box (12 triangles, normals facing out) as one mesh.
int add_box(cooker::Scene& scene, const glm::vec3& lo, const glm::vec3& hi, const std::string& name,
            int object = -1, int material = 0);

// Adds a closed room: six inward-facing walls of a box (one mesh per wall, named name_0..5) with
// walls of thickness `wall` (each wall is a solid slab, so the room is sealed).
void add_closed_room(cooker::Scene& scene, const glm::vec3& lo, const glm::vec3& hi, float wall,
                     const std::string& name);

// Adds a semi-dynamic object made of one box; returns its object index.
int add_object_box(cooker::Scene& scene, const glm::vec3& lo, const glm::vec3& hi,
                   const std::string& name);

cooker::Light point_light(const std::string& name, const glm::vec3& pos, float intensity,
                          bool semi_dynamic = false);
cooker::Light spot_light(const std::string& name, const glm::vec3& pos, const glm::vec3& dir,
                         float intensity, float inner, float outer, bool semi_dynamic = false);
cooker::Light directional_light(const std::string& name, const glm::vec3& dir, float lux,
                                bool semi_dynamic = false);

// Ensures a default material and computes the bounds. Call after adding geometry.
void finish(cooker::Scene& scene);

// A w x h grid of texels covering the rectangle origin + [0,1]*u + [0,1]*v, all valid, with
// normal n (texel (x, y) at origin + (x+0.5)/w u + (y+0.5)/h v).
cooker::TexelSet grid_texels(int w, int h, const glm::vec3& origin, const glm::vec3& u,
                             const glm::vec3& v, const glm::vec3& n);

// A layout of the given size with no meshes (the bake reads only the texel set).
cooker::Layout bare_layout(int w, int h);

// What `lightpatch cook` makes before baking: the layout (a `lightmap_size` page), the tracer and
// the texels of every surface (bounce light gathers from the light map, so every surface it
// reflects from needs texels).
struct Prepared {
  cooker::Layout layout;
  std::unique_ptr<cooker::Tracer> tracer;
  cooker::TexelSet texels;
};
Prepared prepare(const cooker::Scene& scene, int lightmap_size);

}  // namespace lightpatch::test
