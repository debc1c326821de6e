// The pass over one light group's shadow rays (DESIGN.md, "The method in one screen"): each ray
// is traced once against the static scene and, in the same traversal, collects the semi-dynamic
// objects it crosses; an unblocked sample adds to the group's map and to the shadow map of every
// candidate slot it crosses (T = map minus what the slot's objects block), and light that two
// slots both block goes to their pair's overlap map. So a semi-dynamic bake costs about one bake.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "context.h"
#include "lightpatch/cooker/maps.h"
#include "lightpatch/cooker/progress.h"

namespace lightpatch::cooker {

// What one pass traces: slots, each a set of objects whose joint presence the slot's map measures.
struct Candidates {
  explicit Candidates(size_t objects) : slots_of(objects) {}
  void add(std::vector<int> set) {
    for (int o : set) slots_of[size_t(o)].push_back(int(sets.size()));
    objects.push_back(set.front());
    sets.push_back(std::move(set));
  }
  void add(int o) { add(std::vector<int>{o}); }
  std::vector<std::vector<int>> sets;      // slot -> Scene::objects indices
  std::vector<int> objects;                // slot -> its first object
  std::vector<std::vector<int>> slots_of;  // Scene::objects index -> slots holding it
};

// A map whose rows are allocated when first written. A shadow usually darkens a corner of the
// light map: as dense images, a pass's candidates cost (objects x light map) of zeroed memory,
// written and scanned again; this costs the rows they touch. Each row is written by the one
// worker that traces it (parallel_for over rows), so allocation needs no lock.
class SparseMap {
 public:
  SparseMap(int width, int height, int channels)
      : width_(width), height_(height), channels_(channels), rows_(size_t(height)) {}
  int channels() const { return channels_; }
  // Row y, zeros until written; y is the caller's own row.
  float* row(int y);
  float at(size_t texel, int channel) const {
    const std::unique_ptr<float[]>& r = rows_[texel / size_t(width_)];
    return r ? r[(texel % size_t(width_)) * size_t(channels_) + size_t(channel)] : 0.0f;
  }
  bool row_written(int y) const { return rows_[size_t(y)] != nullptr; }
  int width() const { return width_; }
  int height() const { return height_; }
  FloatImage dense() const;

 private:
  int width_, height_, channels_;
  std::vector<std::unique_ptr<float[]>> rows_;
};

struct DirectPass {
  FloatImage map;                 // the group's own map (B or C_l), direct light only
  std::vector<SparseMap> shadow;  // per slot: the direct light its objects block
  std::map<std::pair<int, int>, FloatImage> pairs;  // slots a < b: light both block
  double doubly_blocked = 0.0;  // energy (max channel, summed over texels) blocked by 2 objects
  double triply_blocked = 0.0;  // ... by 3 or more
  // The same at the integrator's DirectPoints (IndirectIntegrator::direct_points()), as images of
  // its layout; null when it has none. Its slots are the same candidates'.
  std::unique_ptr<DirectPass> points;
};

// Shadow samples of one texel and one light traced as a batch (Tracer::shadow_query_many): they
// leave one small patch, so Embree traces them as packets. Buffers are reused from call to call.
struct SampleRays {
  void trace(const Tracer& tracer, const std::vector<LightSample>& samples, int max_objects);
  // Sample i's answer: -1 blocked by static geometry, else how many objects it crosses,
  // listed at objects_of(i).
  std::vector<int> counts;
  const int* objects_of(size_t i) const { return objects.data() + i * stride; }
  // Whether samples [first, first + count) of one light at one receiver are a penumbra: some
  // clear of everything, some blocked or crossing an object. Such a receiver's light is drawn
  // again denser (BakeContext::penumbra_light_samples) by the groups' direct passes and by
  // bake_state alike: the decision reads no state, so the decomposition stays exact.
  bool penumbra(size_t first, size_t count) const {
    bool clear = false, other = false;
    for (size_t i = first; i < first + count; ++i) (counts[i] == 0 ? clear : other) = true;
    return clear && other;
  }

 private:
  std::vector<Ray> rays;
  std::vector<int> objects;
  size_t stride = 0;
};

// light < 0: the static group (every static light at its authored colour and intensity, and the
// emissive surfaces); otherwise scene light `light` at intensity 1, white. `channels`: 1 or 3.
// The integrator's DirectPoints too, where it has them.
DirectPass trace_direct(const BakeContext& b, int light, const Candidates& cand, int channels,
                        Progress& progress);

// Largest |value| of a map over valid texels.
float peak_of(const FloatImage& map, const TexelSet& texels);

}  // namespace lightpatch::cooker
