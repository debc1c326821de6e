// Indirect light (seed 004): photons traced from a group of emitters, stored on surfaces with the
// power they reflect (albedo-coloured), a balanced kd-tree over them whose top levels seed the
// virtual indirect lights (VPLs), photons merged into the nearest seed of similar normal, and the
// VPLs applied to texels with the area-biased form factor cosA cosB / (pi r^2 + bias A).
//
// Semi-dynamic objects. The photon paths are traced with every object absent (the group's own
// VPLs, for B and C_l). Each path segment also records, in the same pass, the objects it crosses.
// For a set of present objects, a path whose segment k first crosses a present object is cut
// there: its deposits from segment k on are removed from their VPLs, and a continuation is traced
// from the object's surface with the present objects in place (same random numbers for the same
// path in every use), its deposits on static surfaces added to the nearest VPLs and its deposits
// on objects forming the objects' own VPLs. So one object's change to a light's indirect light is
// a sparse power change of the static VPLs plus a few VPLs on the object, exactly what a direct
// bake with that object present computes with the same photons.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

#include "kd_tree.h"
#include "lightpatch/cooker/scene.h"
#include "lightpatch/cooker/tracer.h"

namespace lightpatch::cooker {

struct IndirectSettings {
  int photons = 0;          // photons emitted for the whole scene, split over groups by power
  int virtual_lights = 0;   // VPLs for the whole scene, split like the photons
  float area_bias = 1.0f;   // seed 004 §6.7.1
  float normal_cos = 0.8f;  // photons merge into a VPL only with normals this close
  int max_bounces = 512;    // guards albedo >= 1; Russian roulette ends paths long before
};

// One emitter of a light group, with its flux factor: colour * intensity for static lights (all
// static lights and emissive surfaces bake together into B), (1,1,1) for a semi-dynamic light
// alone (C_l is for colour (1,1,1) and intensity 1).
struct Emitter {
  const Light* light = nullptr;  // null: an emissive triangle
  glm::vec3 p0{0.0f}, e1{0.0f}, e2{0.0f}, normal{0.0f};
  float area = 0.0f;
  glm::vec3 scale{1.0f};  // colour * intensity, or radiance for a triangle
  glm::vec3 flux{0.0f};   // total emitted flux (power), RGB
};

// Emitter of a punctual light. `bounds_*` size a directional light's beam.
Emitter light_emitter(const Light& light, const glm::vec3& scale, const glm::vec3& bounds_min,
                      const glm::vec3& bounds_max);
// The emissive triangles of static meshes.
std::vector<Emitter> emissive_emitters(const Scene& scene);

struct VirtualLight {
  glm::vec3 position{0.0f};  // on the surface (a photon's position)
  glm::vec3 normal{0.0f};    // unit, the side the light leaves from
  glm::vec3 power{0.0f};     // reflected flux, RGB
  float area = 0.0f;         // surface the merged photons cover (m^2)
};

// A photon stored on a surface: the power it reflects there (albedo-coloured).
struct PhotonDeposit {
  glm::vec3 position, normal, power;
};

// Irradiance factor of a VPL at a texel (p, n): cosA cosB / (pi r^2 + bias A); fills the
// visibility segment (texel to VPL, both lifted by eps). 0 when the texel or the VPL faces away.
float vpl_factor(const VirtualLight& v, const glm::vec3& p, const glm::vec3& n, float bias,
                 float eps, glm::vec3* origin, glm::vec3* dir, float* tmax);

// The photons of one light group and the VPLs made from them.
class PhotonGroup {
 public:
  // Traces `photons` photons from `emitters` (counts proportional to flux) with every object
  // absent and makes about `virtual_lights` VPLs. `track_objects`: record which objects each
  // segment crosses (needed for change()). `key` separates the random streams of groups.
  PhotonGroup(const Scene& scene, const Tracer& tracer, std::vector<Emitter> emitters, int photons,
              int virtual_lights, const IndirectSettings& settings, uint64_t seed, uint64_t key,
              int threads, bool track_objects);

  const std::vector<VirtualLight>& lights() const { return lights_; }
  // Early-out power bound of static VPL i (max channel; at least the mean VPL power, so that a
  // VPL that an object brightens is not culled in one use and kept in another).
  float bound_power(size_t i) const { return bound_[i]; }
  uint64_t emitted() const { return emitted_; }
  uint64_t lost() const { return lost_; }  // photons whose first ray left the scene
  size_t deposits() const { return deposits_.size(); }
  double deposited_power() const { return deposited_power_; }  // max channel, summed
  float mean_area() const { return mean_area_; }
  // Per object: power (max channel) of the photon segments that first cross it.
  const std::vector<float>& crossing_power() const { return crossing_power_; }

  // What a set of present objects changes. Objects with `present[o] == 0` stay absent.
  struct Change {
    std::vector<glm::vec3> delta;  // per static VPL: power added minus power removed
    std::vector<VirtualLight> object_lights;
    std::vector<int> owner;  // object of each object light
    // Early-out power bound of each object light, times K / (the owner's light count): against
    // the group's per-VPL cutoff (a K-th of a texel's skip budget) an object's lights share the
    // whole budget among themselves.
    std::vector<float> object_bound;
  };
  Change change(const std::vector<uint8_t>& present) const;

 private:
  using Deposit = PhotonDeposit;
  struct Segment {
    glm::vec3 origin, dir;
    float tmin, tmax;
    glm::vec3 power;  // carried along the segment
    float range;      // > 0: the light's range window applies at the hit (first segment)
    int32_t deposit;  // index of the deposit at its end, -1 if it left the scene
  };
  struct Crossing {
    uint32_t path;
    uint32_t segment;  // global segment index
    int32_t object;
  };
  struct Path {
    uint32_t first_segment, segment_count;
  };
  struct Trace;  // per-chunk output of the tracing pass

  void trace_path(uint32_t path, Trace& out) const;
  // Continues a path from segment s hitting a present object; false if it hits none.
  bool continue_path(uint32_t path, const Segment& s, const std::vector<uint8_t>& present,
                     std::vector<Deposit>& to_static, std::vector<Deposit>& to_objects,
                     std::vector<int>& objects_hit) const;
  Hit intersect_present(const glm::vec3& o, const glm::vec3& d, float tmin, float tmax,
                        const std::vector<uint8_t>& present) const;
  int assign(const glm::vec3& p, const glm::vec3& n) const;  // nearest seed of similar normal

  const Scene& scene_;
  const Tracer& tracer_;
  std::vector<Emitter> emitters_;
  std::vector<float> emitter_cdf_;
  IndirectSettings settings_;
  uint64_t seed_ = 0;
  int threads_ = 1;
  bool track_ = false;
  float eps_ = 0.0f, extent_ = 0.0f;
  uint64_t emitted_ = 0, lost_ = 0;
  double deposited_power_ = 0.0;
  float photons_per_light_ = 1.0f;
  float mean_area_ = 0.0f;
  float min_area_ = 0.0f;

  std::vector<Path> paths_;
  std::vector<Segment> segments_;
  std::vector<Deposit> deposits_;
  std::vector<Crossing> crossings_;       // path order, then segment order
  std::vector<uint32_t> path_crossings_;  // per path: first index into crossings_ (size paths+1)
  std::vector<float> crossing_power_;

  std::vector<VirtualLight> lights_;
  std::vector<float> bound_;
  std::vector<int> cluster_;  // deposit -> static VPL
  KdTree seeds_;
  std::vector<glm::vec3> seed_normals_;
};

}  // namespace lightpatch::cooker
