// Ray casting against the whole scene, built once (Embree 3). Semi-dynamic objects are included
// or excluded per query by mask, never by rebuilding. Occluders are double-sided.
#pragma once

#include <glm/glm.hpp>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "lightpatch/cooker/scene.h"

namespace lightpatch::cooker {

struct Hit {
  bool hit = false;
  float t = 0.0f;
  int mesh = -1;                     // MeshInstance index
  int triangle = -1;                 // triangle within the mesh
  float u = 0, v = 0;                // barycentrics of vertices 1 and 2
  glm::vec3 geometric_normal{0.0f};  // unit, world space, facing per winding
};

// One ray of a batch query: the segment origin + t*dir, t in (tmin, tmax). `dir` need not be
// unit (t is then in its units); a ray with !(tmax > tmin) is skipped (no hit, not blocked, not
// counted).
struct Ray {
  glm::vec3 origin;
  float tmin;
  glm::vec3 dir;
  float tmax;
};

class Tracer {
 public:
  virtual ~Tracer() = default;
  // Scene-scaled self-intersection offset (metres).
  virtual float epsilon() const = 0;
  // Closest hit along origin + t*dir, t in (tmin, tmax). `with_objects`: semi-dynamic objects
  // take part; static geometry always does.
  virtual Hit intersect(const glm::vec3& origin, const glm::vec3& dir, float tmin, float tmax,
                        bool with_objects) const = 0;
  // True if anything static blocks the segment.
  virtual bool occluded_static(const glm::vec3& origin, const glm::vec3& dir, float tmin,
                               float tmax) const = 0;
  // Writes the indices of the semi-dynamic objects (Scene::objects) that the segment crosses,
  // ignoring static geometry, each once, at most `max_out`; returns how many were written. Used to
  // find, in one pass over a light's rays, which objects block them.
  virtual int blocking_objects(const glm::vec3& origin, const glm::vec3& dir, float tmin,
                               float tmax, int* out, int max_out) const = 0;
  // A semi-dynamic light's shadow ray in one traversal: -1 if static geometry blocks the segment,
  // otherwise what blocking_objects() would return. The default makes two queries; tracers
  // override it with one.
  virtual int shadow_query(const glm::vec3& origin, const glm::vec3& dir, float tmin, float tmax,
                           int* out, int max_out) const {
    if (occluded_static(origin, dir, tmin, tmax)) return -1;
    return blocking_objects(origin, dir, tmin, tmax, out, max_out);
  }
  // shadow_query() for each of n rays (n >= 0): counts[i] is its answer, its objects at
  // objects[i * max_out, ...). Rays are counted as shadow_query() counts them. The default loops;
  // tracers trace the static part as packets.
  virtual void shadow_query_many(const Ray* rays, int n, int* counts, int* objects,
                                 int max_out) const {
    for (int i = 0; i < n; ++i) {
      counts[i] = shadow_query(rays[i].origin, rays[i].dir, rays[i].tmin, rays[i].tmax,
                               objects + size_t(i) * size_t(std::max(0, max_out)), max_out);
    }
  }
  // Batch queries: the same answers as intersect() / occluded_static() for each ray, in fewer
  // traversal calls (Embree packets). hits[i] / blocked[i] (1 = blocked) answer rays[i]; n >= 0.
  // The defaults loop over the single-ray calls; tracers override them. Safe to call from any
  // number of threads at once; they allocate nothing.
  virtual void intersect_many(const Ray* rays, int n, Hit* hits, bool with_objects) const {
    for (int i = 0; i < n; ++i) {
      hits[i] = intersect(rays[i].origin, rays[i].dir, rays[i].tmin, rays[i].tmax, with_objects);
    }
  }
  virtual void occluded_static_many(const Ray* rays, int n, uint8_t* blocked) const {
    for (int i = 0; i < n; ++i) {
      blocked[i] = occluded_static(rays[i].origin, rays[i].dir, rays[i].tmin, rays[i].tmax) ? 1 : 0;
    }
  }
  // Blocked by static geometry or any semi-dynamic object (every object present): a shadow ray
  // of a state in which every object is visible, in one any-hit traversal.
  virtual void occluded_many(const Ray* rays, int n, uint8_t* blocked) const {
    for (int i = 0; i < n; ++i) {
      blocked[i] = intersect(rays[i].origin, rays[i].dir, rays[i].tmin, rays[i].tmax, true).hit;
    }
  }
  // Closest hit on a semi-dynamic object along the segment; static geometry takes no part. These
  // queries walk the objects' own small BVH and are not counted in rays_traced(), which would
  // otherwise flatter the cook's ray rate.
  virtual Hit intersect_objects(const glm::vec3& origin, const glm::vec3& dir, float tmin,
                                float tmax) const = 0;
  virtual void intersect_objects_many(const Ray* rays, int n, Hit* hits) const {
    for (int i = 0; i < n; ++i)
      hits[i] = intersect_objects(rays[i].origin, rays[i].dir, rays[i].tmin, rays[i].tmax);
  }
  // Rays a batch query traces together (its packet width): batches of a multiple of it waste no
  // lanes.
  virtual int batch_width() const { return 1; }
  // Rays traced so far by every query (each ray of a batch counts once), over all threads; object-
  // only intersections (intersect_objects) not counted.
  virtual uint64_t rays_traced() const = 0;
};

std::unique_ptr<Tracer> make_embree_tracer(const Scene& scene);

}  // namespace lightpatch::cooker
