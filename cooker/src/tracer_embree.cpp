// The Embree 3 tracer: one top-level RTCScene for the whole cook, built once. Static geometry
// carries mask bit 1, each semi-dynamic object mask bit 2; queries pick what takes part by ray
// mask (or, where the Embree build lacks ray masks, by a context filter doing the same).
#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <type_traits>
#include <unordered_map>
#include <vector>

#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/tracer.h"

namespace lightpatch::cooker {

namespace {

constexpr unsigned kStaticMask = 1u;
constexpr unsigned kObjectMask = 2u;

const char* error_name(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE:
      return "none";
    case RTC_ERROR_INVALID_ARGUMENT:
      return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION:
      return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY:
      return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU:
      return "unsupported CPU";
    case RTC_ERROR_CANCELLED:
      return "cancelled";
    default:
      return "unknown error";
  }
}

class EmbreeTracer;

// Embree's packet types and calls by width, so one template serves 4, 8 and 16.
template <int W>
struct Packet {
  static_assert(W == 4 || W == 8 || W == 16);
  using RayHit =
      std::conditional_t<W == 4, RTCRayHit4, std::conditional_t<W == 8, RTCRayHit8, RTCRayHit16>>;
  using Ray = std::conditional_t<W == 4, RTCRay4, std::conditional_t<W == 8, RTCRay8, RTCRay16>>;
  static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHit* r) {
    if constexpr (W == 4) rtcIntersect4(v, s, c, r);
    if constexpr (W == 8) rtcIntersect8(v, s, c, r);
    if constexpr (W == 16) rtcIntersect16(v, s, c, r);
  }
  static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, Ray* r) {
    if constexpr (W == 4) rtcOccluded4(v, s, c, r);
    if constexpr (W == 8) rtcOccluded8(v, s, c, r);
    if constexpr (W == 16) rtcOccluded16(v, s, c, r);
  }
};

// Fills lane i of a packet ray from `r`; false (lane left invalid) for an empty segment.
template <typename R>
bool set_lane(R& ray, int i, const Ray& r, unsigned mask) {
  if (!(r.tmax > r.tmin)) return false;
  ray.org_x[i] = r.origin.x;
  ray.org_y[i] = r.origin.y;
  ray.org_z[i] = r.origin.z;
  ray.dir_x[i] = r.dir.x;
  ray.dir_y[i] = r.dir.y;
  ray.dir_z[i] = r.dir.z;
  ray.tnear[i] = std::max(0.0f, r.tmin);
  ray.tfar[i] = r.tmax;
  ray.time[i] = 0.0f;
  ray.mask[i] = mask;
  ray.id[i] = static_cast<unsigned>(i);
  ray.flags[i] = 0;
  return true;
}

// The intersect context a query passes to Embree; the context filter (used only where the
// Embree build lacks ray masks) reads the rest.
struct QueryContext {
  RTCIntersectContext ctx;
  const EmbreeTracer* tracer = nullptr;
  unsigned accept = kStaticMask | kObjectMask;
  bool collect = false;     // record the objects hit and let the ray go on
  bool static_hit = false;  // (no ray masks) a static hit was accepted
  int* out = nullptr;
  int max_out = 0;
  int count = 0;
};

class EmbreeTracer final : public Tracer {
 public:
  explicit EmbreeTracer(const Scene& scene) {
    device_ = rtcNewDevice(nullptr);
    if (!device_) {
      throw CookError(std::string("Embree: cannot create a device: ") +
                      error_name(rtcGetDeviceError(nullptr)));
    }
    rtcSetDeviceErrorFunction(device_, &EmbreeTracer::on_error, this);
    masks_ = rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) != 0;
    // Batch queries use the widest packet the CPU and the Embree build run natively (a wider one
    // would be emulated with narrower ones).
    if (rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0) {
      packet_width_ = 16;
    } else if (rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED) != 0) {
      packet_width_ = 8;
    }
    if (rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED) == 0) {
      rtcReleaseDevice(device_);
      throw CookError("Embree was built without filter functions, which the cooker needs");
    }
    try {
      build(scene);
    } catch (...) {
      release();
      throw;
    }
  }

  void release() {
    if (scene_) rtcReleaseScene(scene_);
    if (objects_) rtcReleaseScene(objects_);
    for (size_t c = 1; c < children_.size(); ++c) {
      if (children_[c]) rtcReleaseScene(children_[c]);
    }
    rtcReleaseDevice(device_);
  }

  ~EmbreeTracer() override { release(); }

  EmbreeTracer(const EmbreeTracer&) = delete;
  EmbreeTracer& operator=(const EmbreeTracer&) = delete;

  float epsilon() const override { return epsilon_; }

  Hit intersect(const glm::vec3& origin, const glm::vec3& dir, float tmin, float tmax,
                bool with_objects) const override {
    return intersect_one(scene_, origin, dir, tmin, tmax,
                         with_objects ? (kStaticMask | kObjectMask) : kStaticMask);
  }

  Hit intersect_objects(const glm::vec3& origin, const glm::vec3& dir, float tmin,
                        float tmax) const override {
    if (!objects_) return Hit{};
    return intersect_one(objects_, origin, dir, tmin, tmax, kObjectMask);
  }

  bool occluded_static(const glm::vec3& origin, const glm::vec3& dir, float tmin,
                       float tmax) const override {
    if (!(tmax > tmin)) return false;
    count_ray();
    return static_blocks(origin, dir, tmin, tmax);
  }

  int blocking_objects(const glm::vec3& origin, const glm::vec3& dir, float tmin, float tmax,
                       int* out, int max_out) const override {
    if (!(tmax > tmin) || max_out <= 0 || !has_objects_) return 0;
    count_ray();
    const int n = collect(origin, dir, tmin, tmax, kObjectMask, out, max_out);
    return n < 0 ? 0 : n;
  }

  // Rays that cross no object's bounds (a few slab tests, no Embree call) take the plain static
  // query; the others one traversal of static geometry and objects together, in which object
  // hits are recorded by their occlusion filter and rejected so the ray goes on, and a static hit
  // ends it.
  int shadow_query(const glm::vec3& origin, const glm::vec3& dir, float tmin, float tmax, int* out,
                   int max_out) const override {
    if (!(tmax > tmin)) return 0;
    count_ray();
    if (!has_objects_ || max_out <= 0 || !crosses_any_object(origin, dir, tmin, tmax)) {
      return static_blocks(origin, dir, tmin, tmax) ? -1 : 0;
    }
    return collect(origin, dir, tmin, tmax, kStaticMask | kObjectMask, out, max_out);
  }

  // The static part as packets (one texel's shadow rays leave one point), then one object query
  // for each unblocked ray that crosses an object's bounds. A ray counts once, as in
  // shadow_query(). Each chunk's rays are first bounded together (bundle_objects), so a ray tests
  // only the objects its chunk may cross: most chunks cross none.
  void shadow_query_many(const Ray* rays, int n, int* counts, int* objects,
                         int max_out) const override {
    constexpr int kChunk = 64;
    uint8_t blocked[kChunk];
    std::vector<int>& near = bundle_scratch();
    for (int first = 0; first < n; first += kChunk) {
      const int m = std::min(kChunk, n - first);
      occluded_batch(rays + first, m, blocked, kStaticMask);
      near.clear();
      if (has_objects_ && max_out > 0) bundle_objects(rays + first, m, near);
      for (int i = 0; i < m; ++i) {
        const Ray& r = rays[first + i];
        int& count = counts[first + i];
        if (blocked[i]) {
          count = -1;
        } else if (!near.empty() && r.tmax > r.tmin &&
                   crosses_object_of(near, r.origin, r.dir, r.tmin, r.tmax)) {
          int* out = objects + size_t(first + i) * size_t(max_out);
          count = std::max(0, collect(r.origin, r.dir, r.tmin, r.tmax, kObjectMask, out, max_out));
        } else {
          count = 0;
        }
      }
    }
  }

  void intersect_many(const Ray* rays, int n, Hit* hits, bool with_objects) const override {
    const unsigned accept = with_objects ? (kStaticMask | kObjectMask) : kStaticMask;
    intersect_batch(scene_, rays, n, hits, accept);
  }

  void intersect_objects_many(const Ray* rays, int n, Hit* hits) const override {
    if (!objects_) {
      std::fill(hits, hits + n, Hit{});
      return;
    }
    intersect_batch(objects_, rays, n, hits, kObjectMask);
  }

  void intersect_batch(RTCScene scene, const Ray* rays, int n, Hit* hits, unsigned accept) const {
    if (packet_width_ == 16) return intersect_packets<16>(scene, rays, n, hits, accept);
    if (packet_width_ == 8) return intersect_packets<8>(scene, rays, n, hits, accept);
    intersect_packets<4>(scene, rays, n, hits, accept);
  }

  void occluded_static_many(const Ray* rays, int n, uint8_t* blocked) const override {
    occluded_batch(rays, n, blocked, kStaticMask);
  }

  void occluded_many(const Ray* rays, int n, uint8_t* blocked) const override {
    occluded_batch(rays, n, blocked, kStaticMask | kObjectMask);
  }

  // A batch of a few rays (a point light's 4 texel samples) takes the narrowest packet that holds
  // it: a wide packet with idle lanes costs about as much as a full one.
  void occluded_batch(const Ray* rays, int n, uint8_t* blocked, unsigned accept) const {
    if (packet_width_ == 16 && n > 8) return occluded_packets<16>(rays, n, blocked, accept);
    if (packet_width_ >= 8 && n > 4) return occluded_packets<8>(rays, n, blocked, accept);
    occluded_packets<4>(rays, n, blocked, accept);
  }

  int batch_width() const override { return packet_width_; }

  uint64_t rays_traced() const override {
    std::lock_guard<std::mutex> lock(counters_mutex_);
    uint64_t sum = 0;
    for (const Counter& c : counters_) sum += c.value.load(std::memory_order_relaxed);
    return sum;
  }

  // Occlusion filter of object geometries: in collecting queries, record the object and reject
  // the hit so the traversal goes on.
  static void object_filter(const RTCFilterFunctionNArguments* args) {
    auto* qc = reinterpret_cast<QueryContext*>(args->context);
    if (!qc->collect) return;
    const int object = *static_cast<const int*>(args->geometryUserPtr);
    for (unsigned i = 0; i < args->N; ++i) {
      if (args->valid[i] == 0) continue;
      args->valid[i] = 0;
      const bool seen = std::find(qc->out, qc->out + qc->count, object) != qc->out + qc->count;
      if (!seen && qc->count < qc->max_out) qc->out[qc->count++] = object;
    }
  }

  // Context filter, only where the Embree build lacks ray masks: does the masking.
  static void filter(const RTCFilterFunctionNArguments* args) {
    auto* qc = reinterpret_cast<QueryContext*>(args->context);
    const EmbreeTracer* self = qc->tracer;
    for (unsigned i = 0; i < args->N; ++i) {
      if (args->valid[i] == 0) continue;
      const unsigned geom = RTCHitN_geomID(args->hit, args->N, i);
      const int object = geom < self->mesh_object_.size() ? self->mesh_object_[geom] : -1;
      const unsigned bit = object >= 0 ? kObjectMask : kStaticMask;
      if ((bit & qc->accept) == 0) {
        args->valid[i] = 0;
      } else if (object < 0) {
        qc->static_hit = true;
      }
    }
  }

 private:
  struct alignas(64) Counter {
    std::atomic<uint64_t> value{0};
  };

  static void on_error(void* user, RTCError code, const char* text) {
    auto* self = static_cast<EmbreeTracer*>(user);
    std::lock_guard<std::mutex> lock(self->error_mutex_);
    if (self->error_.empty()) {
      self->error_ = std::string(error_name(code)) + (text ? std::string(": ") + text : "");
    }
  }

  void check(const char* what) {
    std::lock_guard<std::mutex> lock(error_mutex_);
    if (!error_.empty()) throw CookError(std::string("Embree (") + what + "): " + error_);
  }

  RTCScene new_scene() {
    RTCScene sc = rtcNewScene(device_);
    check("new scene");
    rtcSetSceneFlags(sc, masks_ ? RTC_SCENE_FLAG_ROBUST
                                : (RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION));
    rtcSetSceneBuildQuality(sc, RTC_BUILD_QUALITY_HIGH);
    return sc;
  }

  // Built once: static geometry directly in the top-level scene (mask 1), each semi-dynamic object
  // in a child scene instanced (identity transform) into it with mask 2. The mask on an instance
  // prunes its whole subtree, so a static-only query does not walk the objects' BVHs (with all
  // geometry in one flat BVH it would, and pay for it), and an object off a ray's path costs
  // one box test.
  void build(const Scene& scene) {
    scene_ = new_scene();
    children_.push_back(scene_);  // static geometry: the top level itself
    for (size_t o = 0; o < scene.objects.size(); ++o) children_.push_back(new_scene());
    object_lo_.assign(scene.objects.size(), glm::vec3(std::numeric_limits<float>::max()));
    object_hi_.assign(scene.objects.size(), glm::vec3(-std::numeric_limits<float>::max()));
    std::vector<bool> child_used(children_.size(), false);
    mesh_object_.assign(scene.meshes.size(), -1);
    vertices_.assign(scene.meshes.size(), nullptr);
    indices_.assign(scene.meshes.size(), nullptr);
    float max_abs = 0.0f;
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
      const MeshInstance& mesh = scene.meshes[m];
      if (mesh.object >= static_cast<int>(scene.objects.size())) {
        throw CookError("mesh '" + mesh.name +
                        "' refers to a semi-dynamic object that does not exist");
      }
      mesh_object_[m] = mesh.object;
      const size_t tris = mesh.indices.size() / 3;
      // A mesh that casts no shadows (a light's own flame or bulb) is not an occluder at all.
      if (tris == 0 || mesh.positions.empty() || !mesh.cast_shadows) continue;
      RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
      check("new geometry");
      auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                            RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                            mesh.positions.size()));
      auto* ix = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
          geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), tris));
      if (!v || !ix) {
        rtcReleaseGeometry(geom);
        check("geometry buffers");
        throw CookError("Embree: cannot allocate geometry buffers");
      }
      for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const glm::vec3& p = mesh.positions[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
          rtcReleaseGeometry(geom);
          throw CookError("mesh '" + mesh.name + "' has a non-finite position");
        }
        v[3 * i + 0] = p.x;
        v[3 * i + 1] = p.y;
        v[3 * i + 2] = p.z;
        max_abs = std::max({max_abs, std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)});
        if (mesh.object >= 0) {
          object_lo_[static_cast<size_t>(mesh.object)] =
              glm::min(object_lo_[static_cast<size_t>(mesh.object)], p);
          object_hi_[static_cast<size_t>(mesh.object)] =
              glm::max(object_hi_[static_cast<size_t>(mesh.object)], p);
        }
      }
      for (size_t i = 0; i < tris * 3; ++i) {
        if (mesh.indices[i] >= mesh.positions.size()) {
          rtcReleaseGeometry(geom);
          throw CookError("mesh '" + mesh.name + "' has an index past its vertex count");
        }
        ix[i] = mesh.indices[i];
      }
      rtcSetGeometryUserData(geom, &mesh_object_[m]);
      vertices_[m] = v;
      indices_[m] = ix;
      rtcSetGeometryMask(geom, mesh.object >= 0 ? kObjectMask : kStaticMask);
      if (mesh.object >= 0) {
        rtcSetGeometryOccludedFilterFunction(geom, &EmbreeTracer::object_filter);
        has_objects_ = true;
      }
      rtcCommitGeometry(geom);
      const size_t child = mesh.object >= 0 ? static_cast<size_t>(mesh.object) + 1 : 0;
      // Geometry ids are mesh indices in every child scene, so a hit's geomID names the mesh.
      rtcAttachGeometryByID(children_[child], geom, static_cast<unsigned>(m));
      rtcReleaseGeometry(geom);  // the child scene holds it
      child_used[child] = true;
      check("attach geometry");
    }
    const float identity[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    // Each object is instanced twice: into the top level, and into a scene of the objects alone,
    // which object-only queries traverse without walking the static geometry's BVH (masks prune
    // only at its leaves).
    if (has_objects_) objects_ = new_scene();
    for (size_t c = 1; c < children_.size(); ++c) {
      rtcCommitScene(children_[c]);
      check("commit child scene");
      if (!child_used[c]) continue;
      for (RTCScene top : {scene_, objects_}) {
        RTCGeometry inst = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
        check("new instance");
        rtcSetGeometryInstancedScene(inst, children_[c]);
        rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, identity);
        rtcSetGeometryMask(inst, kObjectMask);
        rtcCommitGeometry(inst);
        rtcAttachGeometry(top, inst);
        rtcReleaseGeometry(inst);
        check("attach instance");
      }
    }
    rtcCommitScene(scene_);
    check("commit scene");
    if (objects_) {
      rtcCommitScene(objects_);
      check("commit object scene");
    }
    // Scene-scaled offset, but never below what float positions of this magnitude can resolve.
    const float diag = scene.scale() > 0.0f ? scene.scale() : 1.0f;
    epsilon_ = std::max(1e-5f * diag, 64.0f * FLT_EPSILON * max_abs);
    // Object bounds grow by epsilon so a segment grazing a face still reaches the object's BVH;
    // objects without triangles get no child query.
    for (size_t o = 0; o < object_lo_.size(); ++o) {
      if (!child_used[o + 1]) {
        rtcReleaseScene(children_[o + 1]);
        children_[o + 1] = nullptr;
        continue;
      }
      object_lo_[o] -= glm::vec3(epsilon_);
      object_hi_[o] += glm::vec3(epsilon_);
    }
  }

  // Packets of W lanes over the batch; the last one partly valid. Lanes of empty segments stay
  // invalid and answer "no hit".
  template <int W>
  void intersect_packets(RTCScene scene, const Ray* rays, int n, Hit* hits, unsigned accept) const {
    QueryContext qc;
    init_context(qc, accept);
    for (int first = 0; first < n; first += W) {
      const int m = std::min(W, n - first);
      alignas(64) int valid[W];
      alignas(64) typename Packet<W>::RayHit rh;
      int live = 0;
      for (int i = 0; i < W; ++i) {
        valid[i] = (i < m && set_lane(rh.ray, i, rays[first + i], accept)) ? -1 : 0;
        rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
        live += valid[i] != 0 ? 1 : 0;
      }
      if (live > 0) {
        if (scene != objects_) count_rays(static_cast<uint64_t>(live));
        Packet<W>::intersect(valid, scene, &qc.ctx, &rh);
      }
      // The hit triangles' indices, fetched for every lane before any normal is computed.
      for (int i = 0; i < m; ++i) {
        if (valid[i] != 0 && rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID)
          __builtin_prefetch(indices_[rh.hit.geomID[i]] + 3 * size_t(rh.hit.primID[i]));
      }
      for (int i = 0; i < m; ++i) {
        Hit& h = hits[first + i];
        h = Hit{};
        if (valid[i] == 0 || rh.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) continue;
        h.hit = true;
        h.t = rh.ray.tfar[i];
        h.mesh = static_cast<int>(rh.hit.geomID[i]);
        h.triangle = static_cast<int>(rh.hit.primID[i]);
        h.u = rh.hit.u[i];
        h.v = rh.hit.v[i];
        h.geometric_normal = triangle_normal(h.mesh, h.triangle);
      }
    }
  }

  template <int W>
  void occluded_packets(const Ray* rays, int n, uint8_t* blocked, unsigned accept) const {
    QueryContext qc;
    init_context(qc, accept);
    for (int first = 0; first < n; first += W) {
      const int m = std::min(W, n - first);
      alignas(64) int valid[W];
      alignas(64) typename Packet<W>::Ray ray;
      int live = 0;
      for (int i = 0; i < W; ++i) {
        valid[i] = (i < m && set_lane(ray, i, rays[first + i], accept)) ? -1 : 0;
        live += valid[i] != 0 ? 1 : 0;
      }
      if (live > 0) {
        count_rays(static_cast<uint64_t>(live));
        Packet<W>::occluded(valid, scene_, &qc.ctx, &ray);
      }
      for (int i = 0; i < m; ++i) {
        blocked[first + i] = (valid[i] != 0 && ray.tfar[i] < 0.0f) ? 1 : 0;  // -inf on a hit
      }
    }
  }

  Hit intersect_one(RTCScene scene, const glm::vec3& origin, const glm::vec3& dir, float tmin,
                    float tmax, unsigned accept) const {
    Hit hit;
    if (!(tmax > tmin)) return hit;
    if (scene != objects_) count_ray();
    QueryContext qc;
    init_context(qc, accept);
    RTCRayHit rh;
    set_ray(rh.ray, origin, dir, tmin, tmax, qc.accept);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;  // geomID names the mesh (see build())
    rtcIntersect1(scene, &qc.ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
    hit.hit = true;
    hit.t = rh.ray.tfar;
    hit.mesh = static_cast<int>(rh.hit.geomID);
    hit.triangle = static_cast<int>(rh.hit.primID);
    hit.u = rh.hit.u;
    hit.v = rh.hit.v;
    hit.geometric_normal = triangle_normal(hit.mesh, hit.triangle);
    return hit;
  }

  bool static_blocks(const glm::vec3& origin, const glm::vec3& dir, float tmin, float tmax) const {
    QueryContext qc;
    init_context(qc, kStaticMask);
    RTCRay ray;
    set_ray(ray, origin, dir, tmin, tmax, kStaticMask);
    rtcOccluded1(scene_, &qc.ctx, &ray);
    return ray.tfar < 0.0f;  // Embree sets tfar to -inf on a hit
  }

  // One occlusion traversal with the objects' filters recording them; -1 if static geometry
  // blocks (only possible when `accept` includes it).
  int collect(const glm::vec3& origin, const glm::vec3& dir, float tmin, float tmax,
              unsigned accept, int* out, int max_out) const {
    QueryContext qc;
    init_context(qc, accept);
    qc.collect = true;
    qc.out = out;
    qc.max_out = max_out;
    RTCRay ray;
    set_ray(ray, origin, dir, tmin, tmax, accept);
    rtcOccluded1(accept == kObjectMask ? objects_ : scene_, &qc.ctx, &ray);
    return (qc.static_hit || ray.tfar < 0.0f) ? -1 : qc.count;
  }

  bool crosses_any_object(const glm::vec3& origin, const glm::vec3& dir, float tmin,
                          float tmax) const {
    const glm::vec3 inv(1.0f / dir.x, 1.0f / dir.y, 1.0f / dir.z);
    for (size_t o = 0; o < object_lo_.size(); ++o) {
      if (children_[o + 1] &&
          segment_hits_box(origin, dir, inv, tmin, tmax, object_lo_[o], object_hi_[o])) {
        return true;
      }
    }
    return false;
  }

  bool crosses_object_of(const std::vector<int>& near, const glm::vec3& origin,
                         const glm::vec3& dir, float tmin, float tmax) const {
    const glm::vec3 inv(1.0f / dir.x, 1.0f / dir.y, 1.0f / dir.z);
    for (int o : near) {
      if (segment_hits_box(origin, dir, inv, tmin, tmax, object_lo_[size_t(o)],
                           object_hi_[size_t(o)])) {
        return true;
      }
    }
    return false;
  }

  // The objects (Scene::objects indices) whose bounds rays[0, n) may cross. Every point of a
  // segment from o_i to e_i lies within max(|o_i - A|, |e_i - B|) of the segment from A to B,
  // whatever A and B are: so a box the segments cross is one that segment AB crosses once the box
  // is grown by R, the largest of those distances. A and B are the means of the rays' starts and
  // ends. Rays without a finite end (a sun's) keep every object.
  void bundle_objects(const Ray* rays, int n, std::vector<int>& near) const {
    glm::vec3 a(0.0f), b(0.0f);
    for (int i = 0; i < n; ++i) {
      a += rays[i].origin;
      b += rays[i].origin + rays[i].dir * rays[i].tmax;
    }
    a /= float(n);
    b /= float(n);
    const bool finite = std::isfinite(b.x + b.y + b.z);  // an infinite end makes the sum so
    float r2 = 0.0f;
    for (int i = 0; finite && i < n; ++i) {
      const glm::vec3 o = rays[i].origin - a, e = rays[i].origin + rays[i].dir * rays[i].tmax - b;
      r2 = std::max(r2, std::max(glm::dot(o, o), glm::dot(e, e)));
    }
    const glm::vec3 d = b - a;
    const glm::vec3 inv(1.0f / d.x, 1.0f / d.y, 1.0f / d.z);
    const float r = std::sqrt(r2) * (1.0f + 1e-4f);
    const float ab_scale = std::max(max_abs(a), max_abs(b));
    for (size_t o = 0; o < object_lo_.size(); ++o) {
      if (!children_[o + 1]) continue;
      if (!finite) {
        near.push_back(int(o));
        continue;
      }
      // The slack covers float rounding of the sums above, at the scale of the coordinates.
      const float scale = std::max({ab_scale, max_abs(object_lo_[o]), max_abs(object_hi_[o])});
      const glm::vec3 grow(r + scale * 1e-5f);
      if (segment_hits_box(a, d, inv, 0.0f, 1.0f, object_lo_[o] - grow, object_hi_[o] + grow))
        near.push_back(int(o));
    }
  }

  static float max_abs(const glm::vec3& v) {
    return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
  }

  // A worker's list for bundle_objects, reused from call to call (shadow_query_many allocates
  // nothing once warm).
  static std::vector<int>& bundle_scratch() {
    thread_local std::vector<int> near;
    return near;
  }

  static bool segment_hits_box(const glm::vec3& o, const glm::vec3& d, const glm::vec3& inv,
                               float tmin, float tmax, const glm::vec3& lo, const glm::vec3& hi) {
    float t0 = tmin, t1 = tmax;
    for (int a = 0; a < 3; ++a) {
      if (d[a] == 0.0f) {
        if (o[a] < lo[a] || o[a] > hi[a]) return false;
        continue;
      }
      float ta = (lo[a] - o[a]) * inv[a], tb = (hi[a] - o[a]) * inv[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      if (t0 > t1) return false;
    }
    return true;
  }

  void init_context(QueryContext& qc, unsigned accept) const {
    rtcInitIntersectContext(&qc.ctx);
    qc.tracer = this;
    qc.accept = accept;
    // Without ray masks a context filter does the masking of any query that does not take
    // everything.
    const bool need = !masks_ && accept != (kStaticMask | kObjectMask);
    qc.ctx.filter = need ? &EmbreeTracer::filter : nullptr;
  }

  static void set_ray(RTCRay& ray, const glm::vec3& o, const glm::vec3& d, float tmin, float tmax,
                      unsigned mask) {
    ray.org_x = o.x;
    ray.org_y = o.y;
    ray.org_z = o.z;
    ray.dir_x = d.x;
    ray.dir_y = d.y;
    ray.dir_z = d.z;
    ray.tnear = std::max(0.0f, tmin);
    ray.tfar = tmax;
    ray.time = 0.0f;
    ray.mask = mask;
    ray.id = 0;
    ray.flags = 0;
  }

  glm::vec3 triangle_normal(int mesh, int tri) const {
    const float* v = vertices_[static_cast<size_t>(mesh)];
    const uint32_t* ix = indices_[static_cast<size_t>(mesh)];
    auto p = [&](int k) {
      const uint32_t i = ix[3 * tri + k];
      return glm::vec3(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
    };
    const glm::vec3 n = glm::cross(p(1) - p(0), p(2) - p(0));
    const float len = glm::length(n);
    return len > 0.0f ? n / len : glm::vec3(0.0f, 0.0f, 1.0f);
  }

  void count_ray() const { count_rays(1); }
  // Each thread counts in a counter of its own, by a plain load and store: a locked add on a
  // shared one cost a single-ray query a tenth of its time. A thread's first query on this
  // tracer registers its counter; rays_traced() sums them. parallel_for() starts new threads on
  // every call, so a counter goes to the next thread given the same id (one that has ended: ids
  // are unique among live threads), and the counters stay about as many as threads at once.
  void count_rays(uint64_t k) const {
    struct Mine {
      uint64_t tracer = 0;  // id_ of the tracer `counter` belongs to
      std::atomic<uint64_t>* counter = nullptr;
    };
    thread_local Mine mine;
    if (mine.tracer != id_) {
      std::lock_guard<std::mutex> lock(counters_mutex_);
      std::atomic<uint64_t>*& counter = counter_of_thread_[std::this_thread::get_id()];
      if (!counter) counter = &counters_.emplace_back().value;
      mine = {id_, counter};
    }
    mine.counter->store(mine.counter->load(std::memory_order_relaxed) + k,
                        std::memory_order_relaxed);
  }
  static uint64_t next_id() {
    static std::atomic<uint64_t> next{1};
    return next.fetch_add(1);
  }

  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  RTCScene objects_ = nullptr;      // the objects' instances alone (null without objects)
  std::vector<RTCScene> children_;  // [0] = scene_ (static geometry), [1 + o] object o or null
  std::vector<glm::vec3> object_lo_, object_hi_;
  bool masks_ = true;
  bool has_objects_ = false;
  int packet_width_ = 4;  // batch queries' packet width: 16, 8 or 4
  float epsilon_ = 1e-5f;
  std::vector<int> mesh_object_;        // geometry id (= mesh index) -> object or -1
  std::vector<const float*> vertices_;  // Embree-owned buffers, alive with the scene
  std::vector<const uint32_t*> indices_;
  const uint64_t id_ = next_id();         // never reused, unlike an address
  mutable std::deque<Counter> counters_;  // one per thread id that queried; never moved
  mutable std::unordered_map<std::thread::id, std::atomic<uint64_t>*> counter_of_thread_;
  mutable std::mutex counters_mutex_;
  std::mutex error_mutex_;
  std::string error_;
};

}  // namespace

std::unique_ptr<Tracer> make_embree_tracer(const Scene& scene) {
  return std::make_unique<EmbreeTracer>(scene);
}

}  // namespace lightpatch::cooker
