#include "indirect_light.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "direct_light.h"
#include "surface_albedo.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

namespace {

constexpr float kPi = 3.14159265358979f;
constexpr uint32_t kChunk = 512;              // photons (or paths) per work item
constexpr float kObjectLightSparsity = 2.0f;  // photons per object VPL / photons per static VPL
// Random-number slots of one photon's bounce (sample_hash's last argument).
enum Slot : uint64_t {
  kEmit = 0,
  kEmitDir = 1,
  kRoulette = 2,
  kBounce = 3,
  kAltRoulette = 4,
  kAltBounce = 5
};

float max3(const glm::vec3& v) {
  return std::max({v.x, v.y, v.z});
}

float unit(uint64_t h) {
  return hash_to_unit(h);
}
float unit2(uint64_t h) {
  return hash_to_unit(sample_hash(h, 1, 2, 3));
}

glm::vec3 cosine_dir(const glm::vec3& n, uint64_t h) {
  return cosine_direction(n, unit(h), unit2(h));
}

glm::vec3 cone_dir(const glm::vec3& axis, float cos_max, uint64_t h) {
  const float c = 1.0f - unit(h) * (1.0f - cos_max);
  const float s = std::sqrt(std::max(0.0f, 1.0f - c * c));
  const float phi = 2.0f * kPi * unit2(h);
  glm::vec3 t, b;
  orthonormal_basis(axis, t, b);
  return glm::normalize(t * (s * std::cos(phi)) + b * (s * std::sin(phi)) + axis * c);
}

// Integral of the spot cone's attenuation over solid angle (steradians), midpoint rule in cos.
float spot_solid_angle(const Light& light) {
  const float cos_outer = std::cos(light.outer_cone);
  constexpr int kSteps = 256;
  double sum = 0.0;
  for (int i = 0; i < kSteps; ++i) {
    const float c = 1.0f - (static_cast<float>(i) + 0.5f) / kSteps * (1.0f - cos_outer);
    const float s = std::sqrt(std::max(0.0f, 1.0f - c * c));
    glm::vec3 t, b;
    orthonormal_basis(light.direction, t, b);
    sum += spot_attenuation(light, light.direction * c + t * s);
  }
  return static_cast<float>(2.0 * kPi * (1.0 - cos_outer) * sum / kSteps);
}

// Beam of a directional light: a disc around the scene bounds' sphere.
float beam_radius(const glm::vec3& lo, const glm::vec3& hi) {
  return 0.5f * glm::length(hi - lo) * 1.01f;
}

// Photons merged into virtual lights (seed 004 §2 steps 3-5): the top levels of a balanced
// kd-tree over the photons are the seeds; every photon goes to the nearest seed whose normal is
// within `normal_cos` (failing that, the nearest facing the same side, then the nearest), so each
// photon's power lands in exactly one light and the total is conserved.
struct Clusters {
  std::vector<VirtualLight> lights;
  std::vector<int> assignment;  // deposit -> light
  KdTree tree;                  // over the seeds
  std::vector<glm::vec3> normals;
  float mean_area = 0.0f;
};

int nearest_seed(const KdTree& tree, const std::vector<glm::vec3>& normals, const glm::vec3& p,
                 const glm::vec3& n, float normal_cos) {
  int best = tree.nearest(
      p, [&](int i) { return glm::dot(normals[static_cast<size_t>(i)], n) >= normal_cos; });
  if (best < 0)
    best =
        tree.nearest(p, [&](int i) { return glm::dot(normals[static_cast<size_t>(i)], n) > 0.0f; });
  if (best < 0) best = tree.nearest(p, [](int) { return true; });
  return best;
}

// `area_cap` > 0: a lone photon's area is at most this (the static lights' mean), so an object's
// few photons do not get a huge bias area.
Clusters cluster_photons(const std::vector<PhotonDeposit>& deposits, size_t count, float normal_cos,
                         int threads, float min_area, float area_cap) {
  Clusters out;
  const size_t n = deposits.size();
  if (n == 0 || count == 0) return out;
  std::vector<glm::vec3> positions(n);
  for (size_t i = 0; i < n; ++i) positions[i] = deposits[i].position;
  const std::vector<int> top = KdTree::top_levels_of(positions, std::min(count, n));
  std::vector<glm::vec3> seed_pos;
  for (int i : top) {
    seed_pos.push_back(deposits[static_cast<size_t>(i)].position);
    out.normals.push_back(deposits[static_cast<size_t>(i)].normal);
  }
  out.tree = KdTree(seed_pos);
  out.assignment.resize(n);
  const int chunks = static_cast<int>((n + kChunk - 1) / kChunk);
  parallel_for(chunks, threads, [&](int c) {
    const size_t first = static_cast<size_t>(c) * kChunk;
    for (size_t i = first; i < std::min(n, first + kChunk); ++i) {
      out.assignment[i] =
          nearest_seed(out.tree, out.normals, deposits[i].position, deposits[i].normal, normal_cos);
    }
  });
  const size_t k = top.size();
  std::vector<double> r2(k, 0.0);
  std::vector<uint32_t> members(k, 0);
  out.lights.resize(k);
  for (size_t j = 0; j < k; ++j) {
    out.lights[j].position = seed_pos[j];
    out.lights[j].normal = out.normals[j];
  }
  for (size_t i = 0; i < n; ++i) {
    const size_t j = static_cast<size_t>(out.assignment[i]);
    out.lights[j].power += deposits[i].power;
    const glm::vec3 d = deposits[i].position - seed_pos[j];
    r2[j] += static_cast<double>(glm::dot(d, d));
    members[j]++;
  }
  // Area the merged photons cover, as a disc: mean r^2 = R^2 / 2 for a uniform disc of radius R.
  double sum = 0.0;
  int with_area = 0;
  for (size_t j = 0; j < k; ++j) {
    if (members[j] < 2) continue;
    out.lights[j].area = static_cast<float>(2.0 * kPi * r2[j] / members[j]);
    if (out.lights[j].area > 0.0f) {
      sum += out.lights[j].area;
      ++with_area;
    }
  }
  // A lone photon (or photons at one point) stands for the mean cluster's area.
  float fallback = with_area > 0 ? static_cast<float>(sum / with_area) : area_cap;
  if (area_cap > 0.0f) fallback = std::min(fallback, area_cap);
  fallback = std::max(fallback, min_area);
  double total = 0.0;
  for (VirtualLight& v : out.lights) {
    if (!(v.area > 0.0f)) v.area = fallback;
    v.area = std::max(v.area, min_area);
    total += v.area;
  }
  out.mean_area = static_cast<float>(total / static_cast<double>(k));
  return out;
}

}  // namespace

Emitter light_emitter(const Light& light, const glm::vec3& scale, const glm::vec3& bounds_min,
                      const glm::vec3& bounds_max) {
  Emitter e;
  e.light = &light;
  e.scale = scale;
  switch (light.type) {
    case LightType::kPoint:
      e.flux = scale * (4.0f * kPi);
      break;
    case LightType::kSpot:
      e.flux = scale * spot_solid_angle(light);
      break;
    case LightType::kDirectional: {
      const float r = beam_radius(bounds_min, bounds_max);
      e.flux = scale * (kPi * r * r);
      break;
    }
  }
  return e;
}

std::vector<Emitter> emissive_emitters(const Scene& scene) {
  std::vector<Emitter> out;
  for (const MeshInstance& mesh : scene.meshes) {
    if (mesh.object >= 0) continue;  // semi-dynamic emitters are not baked as lights
    if (mesh.material < 0 || static_cast<size_t>(mesh.material) >= scene.materials.size()) continue;
    const glm::vec3 L = scene.materials[static_cast<size_t>(mesh.material)].emissive;
    if (!(max3(L) > 0.0f) || !std::isfinite(max3(L))) continue;
    for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
      const uint32_t a = mesh.indices[i], b = mesh.indices[i + 1], c = mesh.indices[i + 2];
      Emitter e;
      e.p0 = mesh.positions[a];
      e.e1 = mesh.positions[b] - e.p0;
      e.e2 = mesh.positions[c] - e.p0;
      const glm::vec3 cr = glm::cross(e.e1, e.e2);
      const float len = glm::length(cr);
      if (!(len > 0.0f)) continue;
      e.area = 0.5f * len;
      e.normal = cr / len;
      if (!mesh.normals.empty()) {
        const glm::vec3 sn = mesh.normals[a] + mesh.normals[b] + mesh.normals[c];
        if (glm::dot(sn, e.normal) < 0.0f) e.normal = -e.normal;
      }
      e.scale = L;
      e.flux = L * (kPi * e.area);
      out.push_back(e);
    }
  }
  return out;
}

float vpl_factor(const VirtualLight& v, const glm::vec3& p, const glm::vec3& n, float bias,
                 float eps, glm::vec3* origin, glm::vec3* dir, float* tmax) {
  const glm::vec3 o = p + n * eps;
  const glm::vec3 to = v.position + v.normal * eps - o;
  const float d2 = glm::dot(to, to);
  const float d = std::sqrt(d2);
  if (!(d > 2.0f * eps)) return 0.0f;
  const glm::vec3 w = to / d;
  const float cos_a = glm::dot(n, w);
  const float cos_b = -glm::dot(v.normal, w);
  if (cos_a <= 0.0f || cos_b <= 0.0f) return 0.0f;
  *origin = o;
  *dir = w;
  *tmax = d - eps;
  // eps^2 keeps the denominator positive for a zero-area VPL at zero bias.
  return cos_a * cos_b / (kPi * d2 + bias * v.area + eps * eps);
}

struct PhotonGroup::Trace {
  std::vector<Path> paths;
  std::vector<Segment> segments;
  std::vector<Deposit> deposits;
  std::vector<Crossing> crossings;
  std::vector<uint32_t> crossing_count;  // per path
  std::vector<float> crossing_power;     // per object
  uint64_t lost = 0;
  std::vector<int> hit_buffer;
};

PhotonGroup::PhotonGroup(const Scene& scene, const Tracer& tracer, std::vector<Emitter> emitters,
                         int photons, int virtual_lights, const IndirectSettings& settings,
                         uint64_t seed, uint64_t key, int threads, bool track_objects)
    : scene_(scene), tracer_(tracer), emitters_(std::move(emitters)), settings_(settings) {
  seed_ = sample_hash(seed, key, 0x1d1ec7, 0);
  threads_ = std::max(1, threads);
  track_ = track_objects && !scene.objects.empty();
  eps_ = tracer.epsilon();
  extent_ = 3.0f * scene.scale() + 4.0f * eps_;  // any segment inside the bounds is shorter
  crossing_power_.assign(scene.objects.size(), 0.0f);

  // Emitter selection proportional to power (max channel of the flux).
  double total = 0.0;
  for (const Emitter& e : emitters_) {
    const float p = max3(e.flux);
    total += std::isfinite(p) && p > 0.0f ? p : 0.0f;
    emitter_cdf_.push_back(static_cast<float>(total));
  }
  if (!(total > 0.0) || photons <= 0) return;
  for (float& c : emitter_cdf_) c = static_cast<float>(c / total);
  emitter_cdf_.back() = 1.0f;
  emitted_ = static_cast<uint64_t>(photons);

  const uint32_t n = static_cast<uint32_t>(photons);
  const int chunks = static_cast<int>((n + kChunk - 1) / kChunk);
  std::vector<Trace> traces(static_cast<size_t>(chunks));
  parallel_for(chunks, threads_, [&](int c) {
    Trace& t = traces[static_cast<size_t>(c)];
    t.crossing_power.assign(scene_.objects.size(), 0.0f);
    t.hit_buffer.assign(std::max<size_t>(1, scene_.objects.size()), 0);
    const uint32_t first = static_cast<uint32_t>(c) * kChunk;
    for (uint32_t i = first; i < std::min(n, first + kChunk); ++i) trace_path(i, t);
  });
  // Merge in photon order: deterministic whatever the thread count.
  size_t total_segments = 0, total_deposits = 0, total_crossings = 0;
  for (const Trace& t : traces) {
    total_segments += t.segments.size();
    total_deposits += t.deposits.size();
    total_crossings += t.crossings.size();
  }
  segments_.reserve(total_segments);
  deposits_.reserve(total_deposits);
  crossings_.reserve(total_crossings);
  paths_.reserve(n);
  path_crossings_.reserve(size_t(n) + 1);
  path_crossings_.push_back(0);
  for (Trace& t : traces) {
    const uint32_t seg0 = static_cast<uint32_t>(segments_.size());
    const int32_t dep0 = static_cast<int32_t>(deposits_.size());
    for (Path p : t.paths) {
      p.first_segment += seg0;
      paths_.push_back(p);
    }
    for (Segment s : t.segments) {
      if (s.deposit >= 0) s.deposit += dep0;
      segments_.push_back(s);
    }
    deposits_.insert(deposits_.end(), t.deposits.begin(), t.deposits.end());
    for (Crossing x : t.crossings) {
      x.segment += seg0;
      crossings_.push_back(x);
    }
    for (uint32_t k : t.crossing_count) path_crossings_.push_back(path_crossings_.back() + k);
    for (size_t o = 0; o < crossing_power_.size(); ++o) crossing_power_[o] += t.crossing_power[o];
    lost_ += t.lost;
    t = Trace();  // free as we go
  }
  traces.clear();
  for (const Deposit& d : deposits_) deposited_power_ += max3(d.power);

  // Virtual lights from the top levels of the photons' kd-tree.
  const size_t k = std::clamp<size_t>(static_cast<size_t>(std::max(1, virtual_lights)), 1,
                                      std::max<size_t>(1, deposits_.size()));
  min_area_ = std::max(std::pow(1e-3f * scene.scale(), 2.0f), eps_ * eps_);
  Clusters clusters =
      cluster_photons(deposits_, k, settings_.normal_cos, threads_, min_area_, 0.0f);
  lights_ = std::move(clusters.lights);
  cluster_ = std::move(clusters.assignment);
  seeds_ = std::move(clusters.tree);
  seed_normals_ = std::move(clusters.normals);
  mean_area_ = clusters.mean_area;
  photons_per_light_ =
      lights_.empty() ? 1.0f
                      : static_cast<float>(deposits_.size()) / static_cast<float>(lights_.size());
  float mean = 0.0f;
  for (const VirtualLight& v : lights_) mean += max3(v.power);
  mean = lights_.empty() ? 0.0f : mean / static_cast<float>(lights_.size());
  bound_.resize(lights_.size());
  for (size_t i = 0; i < lights_.size(); ++i) bound_[i] = std::max(max3(lights_[i].power), mean);
}

void PhotonGroup::trace_path(uint32_t path, Trace& out) const {
  const uint64_t h0 = sample_hash(seed_, path, 0, kEmit);
  const float u = (static_cast<float>(path) + unit(h0)) / static_cast<float>(emitted_);
  const size_t ei =
      std::min(emitter_cdf_.size() - 1,
               static_cast<size_t>(std::upper_bound(emitter_cdf_.begin(), emitter_cdf_.end(), u) -
                                   emitter_cdf_.begin()));
  const float pe = emitter_cdf_[ei] - (ei > 0 ? emitter_cdf_[ei - 1] : 0.0f);
  Path p{static_cast<uint32_t>(out.segments.size()), 0};
  out.crossing_count.push_back(0);
  auto finish = [&] {
    p.segment_count = static_cast<uint32_t>(out.segments.size()) - p.first_segment;
    out.paths.push_back(p);
  };
  if (!(pe > 0.0f)) {
    finish();
    return;
  }
  const Emitter& e = emitters_[ei];
  const float inv = 1.0f / (static_cast<float>(emitted_) * pe);
  const uint64_t hd = sample_hash(seed_, path, 0, kEmitDir);
  glm::vec3 origin, dir, power;
  float tmin = 0.0f, range = 0.0f;
  if (e.light == nullptr) {
    float r1 = unit(hd), r2 = unit2(hd);
    if (r1 + r2 > 1.0f) {
      r1 = 1.0f - r1;
      r2 = 1.0f - r2;
    }
    origin = e.p0 + e.e1 * r1 + e.e2 * r2 + e.normal * eps_;
    dir = cosine_dir(e.normal, sample_hash(hd, 7, 7, 7));
    power = e.flux * inv;
    tmin = eps_;
  } else {
    const Light& l = *e.light;
    range = l.range > 0.0f ? l.range : 0.0f;
    if (l.type == LightType::kPoint) {
      origin = l.position;
      dir = cone_dir(glm::vec3(0, 0, 1), -1.0f, hd);
      power = e.flux * inv;
    } else if (l.type == LightType::kSpot) {
      origin = l.position;
      const float cos_outer = std::cos(l.outer_cone);
      dir = cone_dir(l.direction, cos_outer, hd);
      const float omega = 2.0f * kPi * (1.0f - cos_outer);
      power = e.scale * (omega * spot_attenuation(l, dir) * inv);
    } else {
      const float r = beam_radius(scene_.bounds_min, scene_.bounds_max);
      const glm::vec3 c = 0.5f * (scene_.bounds_min + scene_.bounds_max);
      glm::vec3 t, b;
      orthonormal_basis(l.direction, t, b);
      const float rr = r * std::sqrt(unit(hd)), phi = 2.0f * kPi * unit2(hd);
      origin = c - l.direction * (2.0f * r) + t * (rr * std::cos(phi)) + b * (rr * std::sin(phi));
      dir = l.direction;
      power = e.flux * inv;
    }
  }
  if (!(max3(power) > 0.0f)) {
    finish();
    return;
  }
  std::vector<int>& hits = out.hit_buffer;
  const uint32_t path_crossing0 = static_cast<uint32_t>(out.crossings.size());
  for (int bounce = 0; bounce <= settings_.max_bounces; ++bounce) {
    const Hit h = tracer_.intersect(origin, dir, tmin, extent_, false);
    Segment s{origin, dir, tmin, h.hit ? h.t : extent_, power, range, -1};
    const uint32_t seg_index = static_cast<uint32_t>(out.segments.size());
    if (track_) {
      const int k = tracer_.blocking_objects(origin, dir, tmin, s.tmax, hits.data(),
                                             static_cast<int>(hits.size()));
      for (int j = 0; j < k; ++j) {
        const int o = hits[static_cast<size_t>(j)];
        bool seen = false;
        for (size_t x = path_crossing0; x < out.crossings.size(); ++x)
          seen |= out.crossings[x].object == o;
        if (seen) continue;
        out.crossings.push_back({path, seg_index, o});
        out.crossing_count.back()++;
        out.crossing_power[static_cast<size_t>(o)] += max3(power);
      }
    }
    if (!h.hit) {
      if (bounce == 0) out.lost++;
      out.segments.push_back(s);
      break;
    }
    glm::vec3 n = h.geometric_normal;
    if (glm::dot(n, dir) > 0.0f) n = -n;
    const glm::vec3 pos = origin + dir * h.t;
    const glm::vec3 incident = range > 0.0f ? power * range_window(range, h.t) : power;
    const glm::vec3 albedo = surface_albedo(scene_, h);
    const glm::vec3 reflected = incident * albedo;
    if (max3(reflected) > 0.0f) {
      s.deposit = static_cast<int32_t>(out.deposits.size());
      out.deposits.push_back({pos, n, reflected});
    }
    out.segments.push_back(s);
    // Russian roulette on the albedo: survivors carry reflected / q, so the expectation holds.
    const float q = std::min(1.0f, max3(albedo));
    if (!(unit(sample_hash(seed_, path, static_cast<uint64_t>(bounce) + 1, kRoulette)) < q)) break;
    power = reflected / q;
    range = 0.0f;
    dir = cosine_dir(n, sample_hash(seed_, path, static_cast<uint64_t>(bounce) + 1, kBounce));
    origin = pos + n * eps_;
    tmin = eps_;
  }
  finish();
}

Hit PhotonGroup::intersect_present(const glm::vec3& o, const glm::vec3& d, float tmin, float tmax,
                                   const std::vector<uint8_t>& present) const {
  // Objects not present are stepped over; a few steps, then static geometry only.
  for (int step = 0; step < 16; ++step) {
    const Hit h = tracer_.intersect(o, d, tmin, tmax, true);
    if (!h.hit) return h;
    const int obj = scene_.meshes[static_cast<size_t>(h.mesh)].object;
    if (obj < 0 || present[static_cast<size_t>(obj)]) return h;
    tmin = h.t + eps_;
    if (!(tmax > tmin)) return Hit{};
  }
  return tracer_.intersect(o, d, tmin, tmax, false);
}

bool PhotonGroup::continue_path(uint32_t path, const Segment& s,
                                const std::vector<uint8_t>& present,
                                std::vector<Deposit>& to_static, std::vector<Deposit>& to_objects,
                                std::vector<int>& objects_hit) const {
  Hit h = intersect_present(s.origin, s.dir, s.tmin, s.tmax, present);
  if (!h.hit || scene_.meshes[static_cast<size_t>(h.mesh)].object < 0) return false;
  glm::vec3 power = s.range > 0.0f ? s.power * range_window(s.range, h.t) : s.power;
  glm::vec3 origin = s.origin, dir = s.dir;
  for (int depth = 0; depth <= settings_.max_bounces; ++depth) {
    glm::vec3 n = h.geometric_normal;
    if (glm::dot(n, dir) > 0.0f) n = -n;
    const glm::vec3 pos = origin + dir * h.t;
    const glm::vec3 albedo = surface_albedo(scene_, h);
    const glm::vec3 reflected = power * albedo;
    const int obj = scene_.meshes[static_cast<size_t>(h.mesh)].object;
    if (max3(reflected) > 0.0f) {
      if (obj >= 0) {
        to_objects.push_back({pos, n, reflected});
        objects_hit.push_back(obj);
      } else {
        to_static.push_back({pos, n, reflected});
      }
    }
    const float q = std::min(1.0f, max3(albedo));
    if (!(unit(sample_hash(seed_, path, static_cast<uint64_t>(depth), kAltRoulette)) < q)) break;
    power = reflected / q;
    dir = cosine_dir(n, sample_hash(seed_, path, static_cast<uint64_t>(depth), kAltBounce));
    origin = pos + n * eps_;
    h = intersect_present(origin, dir, eps_, extent_, present);
    if (!h.hit) break;
  }
  return true;
}

int PhotonGroup::assign(const glm::vec3& p, const glm::vec3& n) const {
  return nearest_seed(seeds_, seed_normals_, p, n, settings_.normal_cos);
}

PhotonGroup::Change PhotonGroup::change(const std::vector<uint8_t>& present) const {
  Change c;
  c.delta.assign(lights_.size(), glm::vec3(0.0f));
  if (!track_ || lights_.empty()) return c;
  struct Out {
    std::vector<std::pair<int, glm::vec3>> removed, added;
    std::vector<Deposit> on_objects;
    std::vector<int> owner;
  };
  const uint32_t n = static_cast<uint32_t>(paths_.size());
  const int chunks = static_cast<int>((n + kChunk - 1) / kChunk);
  std::vector<Out> outs(static_cast<size_t>(chunks));
  parallel_for(chunks, threads_, [&](int ci) {
    Out& o = outs[static_cast<size_t>(ci)];
    std::vector<Deposit> to_static;
    const uint32_t first = static_cast<uint32_t>(ci) * kChunk;
    for (uint32_t p = first; p < std::min(n, first + kChunk); ++p) {
      uint32_t seg = std::numeric_limits<uint32_t>::max();
      for (uint32_t x = path_crossings_[p]; x < path_crossings_[p + 1]; ++x) {
        if (present[static_cast<size_t>(crossings_[x].object)])
          seg = std::min(seg, crossings_[x].segment);
      }
      if (seg == std::numeric_limits<uint32_t>::max()) continue;
      to_static.clear();
      const size_t objects0 = o.on_objects.size();
      if (!continue_path(p, segments_[seg], present, to_static, o.on_objects, o.owner)) {
        o.on_objects.resize(objects0);
        o.owner.resize(objects0);
        continue;
      }
      const Path& path = paths_[p];
      for (uint32_t s = seg; s < path.first_segment + path.segment_count; ++s) {
        const int32_t d = segments_[s].deposit;
        if (d >= 0)
          o.removed.emplace_back(cluster_[static_cast<size_t>(d)],
                                 deposits_[static_cast<size_t>(d)].power);
      }
      for (const Deposit& d : to_static)
        o.added.emplace_back(assign(d.position, d.normal), d.power);
    }
  });
  std::vector<std::vector<Deposit>> per_object(scene_.objects.size());
  for (const Out& o : outs) {
    for (const auto& [k, pw] : o.removed) c.delta[static_cast<size_t>(k)] -= pw;
    for (const auto& [k, pw] : o.added) c.delta[static_cast<size_t>(k)] += pw;
    for (size_t i = 0; i < o.on_objects.size(); ++i)
      per_object[static_cast<size_t>(o.owner[i])].push_back(o.on_objects[i]);
  }
  for (size_t obj = 0; obj < per_object.size(); ++obj) {
    const std::vector<Deposit>& d = per_object[obj];
    if (d.empty()) continue;
    // Half the static VPLs' density: the object's bounce is a change to the light's indirect
    // light, usually small next to it, and each of these VPLs adds a ray per texel.
    const size_t want = static_cast<size_t>(
        std::ceil(static_cast<float>(d.size()) / (kObjectLightSparsity * photons_per_light_)));
    const size_t k = std::clamp<size_t>(want, std::min<size_t>(2, d.size()), d.size());
    const size_t first = c.object_lights.size();
    Clusters cl = cluster_photons(d, k, settings_.normal_cos, threads_, min_area_, mean_area_);
    c.object_lights.insert(c.object_lights.end(), cl.lights.begin(), cl.lights.end());
    float mean = 0.0f;
    for (size_t i = first; i < c.object_lights.size(); ++i) mean += max3(c.object_lights[i].power);
    mean /= static_cast<float>(std::max<size_t>(1, c.object_lights.size() - first));
    // The group's per-VPL cutoff is its budget over all its K lights; an object's few lights
    // share the same budget among themselves, so their bound is scaled by K / (their count).
    const float share = static_cast<float>(lights_.size()) /
                        static_cast<float>(std::max<size_t>(1, c.object_lights.size() - first));
    for (size_t i = first; i < c.object_lights.size(); ++i) {
      c.owner.push_back(static_cast<int>(obj));
      c.object_bound.push_back(std::max(max3(c.object_lights[i].power), mean) * share);
    }
  }
  return c;
}

}  // namespace lightpatch::cooker
