#include "panes/pane_cluster.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "lightpatch/cooker/error.h"
#include "lightpatch/moving_lights.h"
#include "worker_pool.h"

namespace lightpatch::cooker {
namespace {

// Along its normal's dominant axis a pane's extent counts this many times: two parallel surfaces
// (a floor and the ceiling's top above it, a wall's two faces) are parted before anything else.
constexpr float kAcrossWeight = 8.0f;
// The refinement splits a pane whose spread (describe()) is beyond this: a light in front of it
// lights its entry points, on the mean, more than this share of their mean away from it. On every
// scene measured (docs/moving_lights.md) the limit of four times as many ends the refinement
// first, even at 512 panes asked for on the two-room scene.
constexpr float kSplitSpread = 0.25f;

struct Cluster {
  std::vector<uint32_t> texels;  // ascending after every split (determinism)
  glm::vec3 lo{std::numeric_limits<float>::max()}, hi{-std::numeric_limits<float>::max()};
  int axis = 0;          // the dominant axis of its texels' normals
  bool sees_eye = true;  // set by describe()
  float spread = 0.0f;   // set by describe(): how unevenly a nearby light lights its entry points
  glm::vec3 size() const {
    glm::vec3 s = hi - lo;
    s[axis] *= kAcrossWeight;
    return s;
  }
  float extent() const { return glm::length(size()); }
};

void bound(Cluster& c, const TexelSet& texels) {
  c.lo = glm::vec3(std::numeric_limits<float>::max());
  c.hi = glm::vec3(-std::numeric_limits<float>::max());
  for (uint32_t t : c.texels) {
    c.lo = glm::min(c.lo, texels.position[t]);
    c.hi = glm::max(c.hi, texels.position[t]);
  }
}

// Splits at the median along the longest side of its bounds; false when it cannot be split.
bool split(Cluster& c, Cluster& other, const TexelSet& texels) {
  if (c.texels.size() < 2) return false;
  other.axis = c.axis;
  const glm::vec3 size = c.size();
  const int axis = size.x >= size.y && size.x >= size.z ? 0 : (size.y >= size.z ? 1 : 2);
  std::vector<uint32_t> order = c.texels;
  const size_t half = order.size() / 2;
  std::nth_element(order.begin(), order.begin() + long(half), order.end(),
                   [&](uint32_t a, uint32_t b) {
                     const float pa = texels.position[a][axis], pb = texels.position[b][axis];
                     return pa < pb || (pa == pb && a < b);
                   });
  other.texels.assign(order.begin() + long(half), order.end());
  c.texels.assign(order.begin(), order.begin() + long(half));
  std::sort(c.texels.begin(), c.texels.end());
  std::sort(other.texels.begin(), other.texels.end());
  bound(c, texels);
  bound(other, texels);
  return true;
}

// Splits cluster i, its second half appended.
void split_off(std::vector<Cluster>& clusters, size_t i, const TexelSet& texels) {
  Cluster other;
  split(clusters[i], other, texels);
  clusters.push_back(std::move(other));
}

// Splits the widest cluster that can be split, its second half appended; false when there is
// none.
bool split_widest(std::vector<Cluster>& clusters, const TexelSet& texels) {
  int best = -1;
  for (size_t i = 0; i < clusters.size(); ++i) {
    if (clusters[i].texels.size() < 2) continue;
    if (best < 0 || clusters[i].extent() > clusters[size_t(best)].extent()) best = int(i);
  }
  if (best < 0) return false;
  split_off(clusters, size_t(best), texels);
  return true;
}

// The member (texel index) nearest the members' mean position, which goes to `centre`.
uint32_t nearest_to_centre(const std::vector<uint32_t>& members, const TexelSet& texels,
                           glm::vec3* centre) {
  glm::dvec3 sum(0.0);
  for (uint32_t t : members) sum += glm::dvec3(texels.position[t]);
  *centre = glm::vec3(sum / double(members.size()));
  uint32_t nearest = members[0];
  float best = std::numeric_limits<float>::max();
  for (uint32_t t : members) {
    const float d = glm::length(texels.position[t] - *centre);
    if (d < best) {
      best = d;
      nearest = t;
    }
  }
  return nearest;
}

// The pane's record from its texels: eye, normal, radius, entry points and depth map; whether all
// its entry points see its eye; *spread, how unevenly a light in front of it lights its entry
// points (below).
bool describe(const std::vector<uint32_t>& members, const TexelSet& texels, const Tracer& tracer,
              float scene_scale, pack::PaneRecord& r, float* spread) {
  *spread = 0.0f;
  r = pack::PaneRecord{};
  glm::dvec3 nsum(0.0);
  for (uint32_t t : members) nsum += glm::dvec3(texels.normal[t]);
  // The eye starts on the member nearest the centre (a centre may float in the air or lie inside
  // a wall), a few tracer epsilons above it.
  glm::vec3 centre;
  const uint32_t e = nearest_to_centre(members, texels, &centre);
  double sq = 0.0;
  for (uint32_t t : members) {
    const glm::vec3 d = texels.position[t] - centre;
    sq += double(glm::dot(d, d));
  }
  const float rms_radius = float(std::sqrt(sq / double(members.size())));
  glm::vec3 normal = glm::vec3(nsum);
  normal = glm::length(normal) > 0.1f * float(members.size()) ? glm::normalize(normal)
                                                              : texels.normal[e];
  const float eps = tracer.epsilon();
  const float lift = 16.0f * eps;
  // Entry points stand for equal shares of the pane (the runtime weighs them 1/M each): the
  // pane cut by median splits into M parts of equal texel counts, each part's member nearest
  // its centre. (Farthest points, tried first, sit on the pane's rim and read a nearby light
  // 2-3x too dim.)
  std::vector<std::vector<uint32_t>> parts{members};
  while (parts.size() < pack::kMaxPanePoints) {
    size_t widest_part = parts.size();
    float widest_extent = -1.0f;
    for (size_t i = 0; i < parts.size(); ++i) {
      if (parts[i].size() < 2) continue;
      glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
      for (uint32_t t : parts[i]) {
        lo = glm::min(lo, texels.position[t]);
        hi = glm::max(hi, texels.position[t]);
      }
      // The most members first (M a power of two: equal shares), the widest among equals.
      const float ext = float(parts[i].size()) * 1e6f + std::min(glm::length(hi - lo), 1e5f);
      if (ext > widest_extent) {
        widest_extent = ext;
        widest_part = i;
      }
    }
    if (widest_part == parts.size()) break;
    Cluster a, b;
    const glm::vec3 an = glm::abs(normal);
    a.axis = an.x >= an.y && an.x >= an.z ? 0 : (an.y >= an.z ? 1 : 2);
    a.texels = std::move(parts[widest_part]);
    bound(a, texels);
    split(a, b, texels);
    parts[widest_part] = std::move(a.texels);
    parts.push_back(std::move(b.texels));
  }
  std::vector<uint32_t> chosen;
  for (const std::vector<uint32_t>& part : parts) {
    glm::vec3 part_centre;
    chosen.push_back(nearest_to_centre(part, texels, &part_centre));
  }
  // The eye: of the member nearest the centre and the entry points, the one that sees the most
  // entry points (a centre member buried under a partition sees none).
  auto lifted = [&](uint32_t t) { return texels.position[t] + texels.normal[t] * lift; };
  auto seen_from = [&](const glm::vec3& from) {
    int n = 0;
    for (uint32_t t : chosen) {
      const glm::vec3 d = lifted(t) - from;
      const float len = glm::length(d);
      if (!(len > 2.0f * eps) || !tracer.occluded_static(from, d / len, eps, len - eps)) ++n;
    }
    return n;
  };
  glm::vec3 eye = lifted(e);
  int best_seen = seen_from(eye);
  for (uint32_t t : chosen) {
    if (best_seen == int(chosen.size())) break;
    const int n = seen_from(lifted(t));
    if (n > best_seen) {
      best_seen = n;
      eye = lifted(t);
    }
  }
  const bool sees = best_seen == int(chosen.size());
  r.point_count = uint32_t(chosen.size());
  for (size_t i = 0; i < chosen.size(); ++i) {
    const uint32_t t = chosen[i];
    for (int k = 0; k < 3; ++k) {
      r.points[i].position[k] = texels.position[t][k];
      r.points[i].normal[k] = texels.normal[t][k];
    }
  }
  for (int k = 0; k < 3; ++k) {
    r.eye[k] = eye[k];
    r.normal[k] = normal[k];
  }
  // The squared-distance floor is one entry point's share of the pane: a disc of the pane's
  // area / M (the pane's RMS radius times sqrt(2 / M)), not the whole pane, whose radius would
  // dim a light a metre from a 3 m wall by half.
  r.radius = std::max(rms_radius * std::sqrt(2.0f / float(chosen.size())), 1e-4f * scene_scale);
  r.depth_range = std::max(scene_scale, 1e-3f);
  const uint32_t n = pack::kPaneDepthSize;
  for (uint32_t y = 0; y < n; ++y) {
    for (uint32_t x = 0; x < n; ++x) {
      float dir[3];
      pane_depth_direction(r.normal, x, y, dir);
      r.depth[y * n + x] = depth_code(tracer, eye, dir, eps, r.depth_range);
    }
  }
  // How evenly a light in front of the pane lights it: lights stand halfway from each entry point
  // to the first surface along a few directions of its hemisphere, and each lights the entry
  // points by the runtime's rule (cosine over squared distance floored at the share radius) with
  // visibility. The pane's weight is the mean over its points; the spread is the mean absolute
  // deviation from it over the mean, summed over the lights. A wall running through a doorway
  // into the next room, or a floor whose far end is a metre from a light standing by its near
  // end, spreads much; the refinement splits where it is largest.
  std::vector<glm::vec3> places;
  for (uint32_t t : chosen) {
    const glm::vec3 from = lifted(t);
    const float nrm[3] = {texels.normal[t].x, texels.normal[t].y, texels.normal[t].z};
    for (uint32_t y = 2; y < n; y += 4)
      for (uint32_t x = 2; x < n; x += 4) {
        float dir[3];
        pane_depth_direction(nrm, x, y, dir);
        const glm::vec3 d(dir[0], dir[1], dir[2]);
        const Hit h = tracer.intersect(from, d, eps, r.depth_range, /*with_objects=*/false);
        const float reach = h.hit ? h.t : r.depth_range;
        if (reach > 4.0f * lift) places.push_back(from + d * (0.5f * reach));
      }
  }
  double deviation = 0.0, total = 0.0;
  std::vector<float> lit(chosen.size());
  const float r2 = r.radius * r.radius;
  for (const glm::vec3& to : places) {
    double mean = 0.0;
    for (size_t i = 0; i < chosen.size(); ++i) {
      const uint32_t t = chosen[i];
      const glm::vec3 from = lifted(t);
      const glm::vec3 d = to - from;
      const float len2 = glm::dot(d, d);
      const float len = std::sqrt(len2);
      const float c = len > 0.0f ? glm::dot(texels.normal[t], d) / len : 0.0f;
      lit[i] = 0.0f;
      if (c > 0.0f && len > 2.0f * eps && !tracer.occluded_static(from, d / len, eps, len - eps))
        lit[i] = c / std::max(len2, r2);
      mean += lit[i];
    }
    mean /= double(chosen.size());
    for (float v : lit) deviation += std::fabs(double(v) - mean);
    total += mean * double(chosen.size());
  }
  *spread = total > 0.0 ? float(deviation / total) : 0.0f;
  return sees;
}

}  // namespace

float strongest_moving_light(const Scene& scene) {
  float strongest = 0.0f;
  for (const Light& l : scene.lights) {
    if (l.moving)
      strongest = std::max(strongest, std::max({l.color.x, l.color.y, l.color.z}) * l.intensity);
  }
  return strongest > 0.0f && std::isfinite(strongest) ? strongest : 1.0f;
}

std::vector<int32_t> pane_of_texels(const std::vector<PaneMap>& panes, size_t texel_count) {
  std::vector<int32_t> pane_of(texel_count, -1);
  for (size_t k = 0; k < panes.size(); ++k) {
    for (uint32_t t : panes[k].texels) {
      if (t >= pane_of.size() || pane_of[t] >= 0)
        throw CookError("pane " + std::to_string(k) + ": texel " + std::to_string(t) +
                        " out of range or in two panes");
      pane_of[t] = int32_t(k);
    }
  }
  return pane_of;
}

uint16_t depth_code(const Tracer& tracer, const glm::vec3& eye, const float dir[3], float eps,
                    float depth_range) {
  const Hit h = tracer.intersect(eye, glm::vec3(dir[0], dir[1], dir[2]), eps, depth_range,
                                 /*with_objects=*/false);
  if (!h.hit) return 65535;
  const double v = std::ceil(double(h.t) / double(depth_range) * 65535.0);
  return uint16_t(std::clamp(v, 0.0, 65534.0));
}

float pane_significance(const Scene& scene, float step) {
  return step / strongest_moving_light(scene);
}

std::vector<PaneMap> cluster_panes(const Scene& scene, const TexelSet& texels, const Tracer& tracer,
                                   const PaneClusterOptions& options) {
  // The six classes of dominant normal axis.
  std::vector<Cluster> clusters(6);
  for (size_t t = 0; t < texels.valid.size(); ++t) {
    if (!texels.valid[t]) continue;
    if (options.senders && (t >= options.senders->size() || !(*options.senders)[t])) continue;
    const int32_t m = t < texels.mesh.size() ? texels.mesh[t] : -1;
    if (m < 0 || size_t(m) >= scene.meshes.size()) continue;
    const MeshInstance& mesh = scene.meshes[size_t(m)];
    if (mesh.object >= 0 || !mesh.cast_shadows) continue;
    const glm::vec3 n = texels.normal[t], a = glm::abs(n);
    const int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
    clusters[size_t(axis * 2 + (n[axis] < 0.0f ? 1 : 0))].texels.push_back(uint32_t(t));
  }
  for (size_t i = 0; i < clusters.size(); ++i) clusters[i].axis = int(i / 2);
  clusters.erase(std::remove_if(clusters.begin(), clusters.end(),
                                [](const Cluster& c) { return c.texels.empty(); }),
                 clusters.end());
  for (Cluster& c : clusters) bound(c, texels);
  const size_t target = size_t(std::max(options.panes, 1));
  while (clusters.size() < target) {
    if (!split_widest(clusters, texels)) break;
  }
  const float scale = scene.scale();
  std::vector<pack::PaneRecord> records(clusters.size());
  auto describe_one = [&](size_t i) {
    clusters[i].sees_eye =
        describe(clusters[i].texels, texels, tracer, scale, records[i], &clusters[i].spread);
  };
  parallel_for(int(clusters.size()), options.threads, [&](int i) { describe_one(size_t(i)); });
  // Refinement, up to four times as many: split the pane a light lights most unevenly, by its
  // spread times its texels (its share of the error), among those spread beyond kSplitSpread or
  // whose entry points do not all see its eye (the runtime's visibility is the eye's).
  const size_t limit = 4 * target;
  while (clusters.size() < limit) {
    int i = -1;
    float best_score = 0.0f;
    for (size_t k = 0; k < clusters.size(); ++k) {
      const Cluster& c = clusters[k];
      if (c.texels.size() < 2 || !(c.spread > kSplitSpread || !c.sees_eye)) continue;
      const float score = std::max(c.spread, kSplitSpread) * float(c.texels.size());
      if (score > best_score) {
        best_score = score;
        i = int(k);
      }
    }
    if (i < 0) break;
    split_off(clusters, size_t(i), texels);
    records.resize(clusters.size());
    describe_one(size_t(i));
    describe_one(clusters.size() - 1);
  }
  std::vector<PaneMap> panes(clusters.size());
  for (size_t i = 0; i < clusters.size(); ++i) {
    panes[i].record = records[i];
    panes[i].texels = std::move(clusters[i].texels);
  }
  return panes;
}

}  // namespace lightpatch::cooker
