// bench_ray_rate: how close the cook comes to the ray rate Embree allows, on one scene in one run.
// Measures, per CPU-second:
//   - the cook: bake_maps at a quality preset, Tracer::rays_traced() over the process's CPU time
//     (all threads);
//   - a naive loop: one flat Embree scene of the same triangles (default build), rtcOccluded1 on
//     random rays (origin uniform in the scene's bounds, direction uniform, as long as the bounds'
//     diagonal), on one thread;
//   - the same rays as packets (rtcOccluded4/8/16 at the widest native width) and as a stream
//     (rtcOccluded1M), and through the cook's Tracer (occluded_static one by one and
//     occluded_static_many; intersect and intersect_many);
//   - texel rays: from valid texels along cosine-distributed directions, 64 per texel (what a
//     gather from one texel traces), single and batched;
//   - the reference path tracer (bake_reference, 16 samples per texel), all threads.
// Prints each rate and its ratio to the naive rtcOccluded1 rate. The cook's target is >= 0.8x
// the naive rate per thread. Times are reported, never checked.
// Usage: bench_ray_rate [SCENE.gltf|.glb] [--quality draft|preview|production] [--rays N]
//                       [--lightmap-size N]
// Without a scene: a 8 x 3 x 8 m room with furniture and four lights, unwrapped by the cooker.
#include <embree3/rtcore.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/import.h"
#include "lightpatch/cooker/reference_integrator.h"
#include "lightpatch/cooker/texel_builder.h"
#include "lightpatch/cooker/tracer.h"
#include "lightpatch/cooker/unwrap.h"
#include "test_scenes.h"

using namespace lightpatch::cooker;
namespace test = lightpatch::test;

namespace {

constexpr float kPi = 3.14159265358979f;
constexpr int kTexelRays = 64;  // rays per texel in the texel workload

double cpu_now(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

Scene builtin_room() {
  Scene s;
  test::add_closed_room(s, {-4, 0, -4}, {4, 3, 4}, 0.2f, "room");
  const glm::vec3 boxes[6][2] = {
      {{-3, 0, -3}, {-1.5f, 0.8f, -2}},   {{1, 0, -3}, {2.5f, 0.9f, -1.5f}},
      {{-1, 0, -0.5f}, {1, 0.75f, 0.5f}}, {{-3.5f, 0, 1}, {-3, 2, 3}},
      {{2, 0, 2}, {2.6f, 1.2f, 2.6f}},    {{-0.3f, 0.75f, -0.2f}, {0.1f, 1.1f, 0.2f}}};
  for (int i = 0; i < 6; ++i)
    test::add_box(s, boxes[i][0], boxes[i][1], "box_" + std::to_string(i));
  s.lights.push_back(test::point_light("lamp_a", {-2, 2.6f, -2}, 8.0f, true));
  s.lights.push_back(test::point_light("lamp_b", {2, 2.6f, 2}, 8.0f));
  Light soft = test::point_light("candle", {0, 1.4f, 0}, 2.0f, true);
  soft.radius = 0.05f;
  s.lights.push_back(soft);
  s.lights.push_back(test::spot_light("spot", {3.5f, 2.8f, -3.5f}, {-1, -1, 1}, 30.0f, 0.3f, 0.6f));
  test::finish(s);
  return s;
}

// The scene's triangles in one flat Embree scene, default flags and build quality.
struct NaiveScene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  explicit NaiveScene(const Scene& s) {
    device = rtcNewDevice(nullptr);
    scene = rtcNewScene(device);
    for (const MeshInstance& m : s.meshes) {
      const size_t tris = m.indices.size() / 3;
      if (tris == 0) continue;
      RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
      auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
          g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.positions.size()));
      auto* ix = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
          g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), tris));
      for (size_t i = 0; i < m.positions.size(); ++i) {
        v[3 * i] = m.positions[i].x;
        v[3 * i + 1] = m.positions[i].y;
        v[3 * i + 2] = m.positions[i].z;
      }
      std::copy(m.indices.begin(), m.indices.end(), ix);
      rtcCommitGeometry(g);
      rtcAttachGeometry(scene, g);
      rtcReleaseGeometry(g);
    }
    rtcCommitScene(scene);
  }
  ~NaiveScene() {
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
  }
  int width() const {
    if (rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED)) return 16;
    if (rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED)) return 8;
    return 4;
  }
};

void to_rtc(const Ray& r, RTCRay& out) {
  out.org_x = r.origin.x;
  out.org_y = r.origin.y;
  out.org_z = r.origin.z;
  out.dir_x = r.dir.x;
  out.dir_y = r.dir.y;
  out.dir_z = r.dir.z;
  out.tnear = r.tmin;
  out.tfar = r.tmax;
  out.time = 0.0f;
  out.mask = 0xFFFFFFFFu;
  out.id = 0;
  out.flags = 0;
}

template <typename P>
void lane(P& p, int i, const Ray& r) {
  p.org_x[i] = r.origin.x;
  p.org_y[i] = r.origin.y;
  p.org_z[i] = r.origin.z;
  p.dir_x[i] = r.dir.x;
  p.dir_y[i] = r.dir.y;
  p.dir_z[i] = r.dir.z;
  p.tnear[i] = r.tmin;
  p.tfar[i] = r.tmax;
  p.time[i] = 0.0f;
  p.mask[i] = 0xFFFFFFFFu;
  p.id[i] = 0;
  p.flags[i] = 0;
}

// Rays through the naive scene as packets of width W; returns how many were blocked.
template <int W, typename P, typename F>
size_t packets(const NaiveScene& ns, const std::vector<Ray>& rays, F occluded) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  size_t blocked = 0;
  for (size_t first = 0; first < rays.size(); first += W) {
    alignas(64) int valid[W];
    alignas(64) P p;
    for (int i = 0; i < W; ++i) {
      const bool live = first + size_t(i) < rays.size();
      valid[i] = live ? -1 : 0;
      lane(p, i, rays[live ? first + size_t(i) : first]);
    }
    occluded(valid, ns.scene, &ctx, &p);
    for (int i = 0; i < W; ++i) blocked += valid[i] != 0 && p.tfar[i] < 0.0f ? 1 : 0;
  }
  return blocked;
}

struct Rate {
  std::string what;
  double mrays_per_cpu_s = 0.0;
  size_t rays = 0;
  double cpu_s = 0.0;
};

// Runs `fn` on this thread and times it by the thread's CPU clock.
Rate measure(const std::string& what, size_t rays, const std::function<size_t()>& fn) {
  const double c0 = cpu_now(CLOCK_THREAD_CPUTIME_ID);
  volatile size_t sink = fn();
  (void)sink;
  Rate r;
  r.what = what;
  r.rays = rays;
  r.cpu_s = cpu_now(CLOCK_THREAD_CPUTIME_ID) - c0;
  r.mrays_per_cpu_s = r.cpu_s > 0.0 ? double(rays) / r.cpu_s * 1e-6 : 0.0;
  return r;
}

glm::vec3 uniform_dir(std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float z = 1.0f - 2.0f * u(rng), phi = 2.0f * kPi * u(rng);
  const float s = std::sqrt(std::max(0.0f, 1.0f - z * z));
  return {s * std::cos(phi), s * std::sin(phi), z};
}

glm::vec3 cosine_dir(const glm::vec3& n, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float r = std::sqrt(u(rng)), phi = 2.0f * kPi * u(rng);
  const glm::vec3 a = std::fabs(n.x) > 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  const glm::vec3 t = glm::normalize(glm::cross(a, n)), b = glm::cross(n, t);
  return glm::normalize(t * (r * std::cos(phi)) + b * (r * std::sin(phi)) +
                        n * std::sqrt(std::max(0.0f, 1.0f - r * r)));
}

}  // namespace

int main(int argc, char** argv) {
  std::string scene_path;
  Quality quality = Quality::kPreview;
  size_t ray_count = 1'000'000;
  int lightmap_size = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quality" && i + 1 < argc) {
      quality = parse_quality(argv[++i]);
    } else if (a == "--rays" && i + 1 < argc) {
      ray_count = size_t(std::max(1000L, std::atol(argv[++i])));
    } else if (a == "--lightmap-size" && i + 1 < argc) {
      lightmap_size = std::max(8, std::atoi(argv[++i]));
    } else if (a == "--help" || a == "-h") {
      std::printf(
          "usage: bench_ray_rate [SCENE.gltf|.glb] [--quality draft|preview|production] "
          "[--rays N] [--lightmap-size N]\n");
      return 0;
    } else if (!a.empty() && a[0] != '-' && scene_path.empty()) {
      scene_path = a;
    } else {
      std::fprintf(stderr, "bench_ray_rate: unknown argument '%s'\n", a.c_str());
      return 2;
    }
  }
  try {
    const Scene scene = scene_path.empty() ? builtin_room() : import_gltf(scene_path);
    LayoutOptions lo;
    lo.lightmap_size = lightmap_size;
    const Layout layout = build_layout(scene, lo);
    const std::unique_ptr<Tracer> tracer = make_embree_tracer(scene);
    const TexelSet texels = build_texels(scene, layout, tracer.get());
    std::vector<size_t> valid;
    for (size_t t = 0; t < texels.valid.size(); ++t)
      if (texels.valid[t]) valid.push_back(t);
    std::printf("scene: %s, %zu triangles, %zu lights, %zu objects, %dx%d page, %zu valid texels\n",
                scene_path.empty() ? "built-in room" : scene_path.c_str(), scene.triangle_count(),
                scene.lights.size(), scene.objects.size(), layout.width, layout.height,
                valid.size());

    // The cook: bake_maps, all threads.
    BakeOptions bo;
    bo.quality = quality;
    Progress progress(true);
    Report report;
    const uint64_t r0 = tracer->rays_traced();
    const double c0 = cpu_now(CLOCK_PROCESS_CPUTIME_ID);
    const auto w0 = std::chrono::steady_clock::now();
    bake_maps(scene, layout, texels, *tracer, bo, progress, report);
    const double cook_wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    const double cook_cpu = cpu_now(CLOCK_PROCESS_CPUTIME_ID) - c0;
    const uint64_t cook_rays = tracer->rays_traced() - r0;

    // Random rays in the bounds, and texel rays.
    std::mt19937 rng(12345);
    const glm::vec3 lo3 = scene.bounds_min, hi3 = scene.bounds_max;
    const float diag = glm::length(hi3 - lo3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<Ray> random(ray_count), texel(ray_count);
    for (Ray& r : random) {
      r.origin = lo3 + (hi3 - lo3) * glm::vec3(u(rng), u(rng), u(rng));
      r.dir = uniform_dir(rng);
      r.tmin = 0.0f;
      r.tmax = diag;
    }
    const float eps = tracer->epsilon();
    for (size_t i = 0; i < ray_count; i += kTexelRays) {
      const size_t t =
          valid.empty() ? 0 : valid[size_t(u(rng) * float(valid.size())) % valid.size()];
      for (size_t k = i; k < std::min(ray_count, i + kTexelRays); ++k) {
        const glm::vec3 n = valid.empty() ? glm::vec3(0, 1, 0) : texels.normal[t];
        texel[k].origin = (valid.empty() ? lo3 : texels.position[t]) + n * eps;
        texel[k].dir = cosine_dir(n, rng);
        texel[k].tmin = eps;
        texel[k].tmax = diag;
      }
    }

    const NaiveScene naive(scene);
    const int width = naive.width();
    std::vector<Rate> rates;
    auto naive1 = [&](const std::vector<Ray>& rays) {
      return [&naive, &rays] {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        size_t blocked = 0;
        for (const Ray& r : rays) {
          RTCRay ray;
          to_rtc(r, ray);
          rtcOccluded1(naive.scene, &ctx, &ray);
          blocked += ray.tfar < 0.0f ? 1 : 0;
        }
        return blocked;
      };
    };
    auto naive_packets = [&](const std::vector<Ray>& rays) {
      return [&naive, &rays, width] {
        if (width == 16) {
          return packets<16, RTCRay16>(
              naive, rays, [](const int* v, RTCScene s, RTCIntersectContext* c, RTCRay16* p) {
                rtcOccluded16(v, s, c, p);
              });
        }
        if (width == 8) {
          return packets<8, RTCRay8>(
              naive, rays, [](const int* v, RTCScene s, RTCIntersectContext* c, RTCRay8* p) {
                rtcOccluded8(v, s, c, p);
              });
        }
        return packets<4, RTCRay4>(
            naive, rays, [](const int* v, RTCScene s, RTCIntersectContext* c, RTCRay4* p) {
              rtcOccluded4(v, s, c, p);
            });
      };
    };
    auto naive_stream = [&](const std::vector<Ray>& rays, bool coherent) {
      return [&naive, &rays, coherent] {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        ctx.flags =
            coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
        constexpr size_t kChunk = 256;
        std::vector<RTCRay> chunk(kChunk);
        size_t blocked = 0;
        for (size_t first = 0; first < rays.size(); first += kChunk) {
          const size_t m = std::min(kChunk, rays.size() - first);
          for (size_t i = 0; i < m; ++i) to_rtc(rays[first + i], chunk[i]);
          rtcOccluded1M(naive.scene, &ctx, chunk.data(), unsigned(m), sizeof(RTCRay));
          for (size_t i = 0; i < m; ++i) blocked += chunk[i].tfar < 0.0f ? 1 : 0;
        }
        return blocked;
      };
    };
    auto tracer1 = [&](const std::vector<Ray>& rays) {
      return [&tracer, &rays] {
        size_t blocked = 0;
        for (const Ray& r : rays)
          blocked += tracer->occluded_static(r.origin, r.dir, r.tmin, r.tmax);
        return blocked;
      };
    };
    auto tracer_many = [&](const std::vector<Ray>& rays) {
      return [&tracer, &rays] {
        std::vector<uint8_t> b(kTexelRays);
        size_t blocked = 0;
        for (size_t first = 0; first < rays.size(); first += kTexelRays) {
          const int m = int(std::min<size_t>(kTexelRays, rays.size() - first));
          tracer->occluded_static_many(&rays[first], m, b.data());
          for (int i = 0; i < m; ++i) blocked += b[size_t(i)];
        }
        return blocked;
      };
    };
    auto tracer_hit1 = [&](const std::vector<Ray>& rays) {
      return [&tracer, &rays] {
        size_t hits = 0;
        for (const Ray& r : rays)
          hits += tracer->intersect(r.origin, r.dir, r.tmin, r.tmax, true).hit;
        return hits;
      };
    };
    auto tracer_hit_many = [&](const std::vector<Ray>& rays) {
      return [&tracer, &rays] {
        std::vector<Hit> h(kTexelRays);
        size_t hits = 0;
        for (size_t first = 0; first < rays.size(); first += kTexelRays) {
          const int m = int(std::min<size_t>(kTexelRays, rays.size() - first));
          tracer->intersect_many(&rays[first], m, h.data(), true);
          for (int i = 0; i < m; ++i) hits += h[size_t(i)].hit;
        }
        return hits;
      };
    };
    const std::string w = std::to_string(width);
    rates.push_back(measure("naive rtcOccluded1, random rays", ray_count, naive1(random)));
    rates.push_back(
        measure("naive rtcOccluded" + w + ", random rays", ray_count, naive_packets(random)));
    rates.push_back(
        measure("naive rtcOccluded1M stream, random rays", ray_count, naive_stream(random, false)));
    rates.push_back(measure("Tracer::occluded_static, random rays", ray_count, tracer1(random)));
    rates.push_back(
        measure("Tracer::occluded_static_many, random rays", ray_count, tracer_many(random)));
    rates.push_back(measure("Tracer::intersect, random rays", ray_count, tracer_hit1(random)));
    rates.push_back(
        measure("Tracer::intersect_many, random rays", ray_count, tracer_hit_many(random)));
    rates.push_back(measure("naive rtcOccluded1, texel rays", ray_count, naive1(texel)));
    rates.push_back(
        measure("naive rtcOccluded" + w + ", texel rays", ray_count, naive_packets(texel)));
    rates.push_back(measure("naive rtcOccluded1M coherent stream, texel rays", ray_count,
                            naive_stream(texel, true)));
    rates.push_back(measure("Tracer::occluded_static, texel rays", ray_count, tracer1(texel)));
    rates.push_back(
        measure("Tracer::occluded_static_many, texel rays", ray_count, tracer_many(texel)));
    rates.push_back(measure("Tracer::intersect, texel rays", ray_count, tracer_hit1(texel)));
    rates.push_back(
        measure("Tracer::intersect_many, texel rays", ray_count, tracer_hit_many(texel)));

    // The reference path tracer, all threads.
    ReferenceOptions ro;
    ro.samples = 16;
    const uint64_t rr0 = tracer->rays_traced();
    const double rc0 = cpu_now(CLOCK_PROCESS_CPUTIME_ID);
    bake_reference(scene, texels, *tracer, {}, ro, progress, report);
    const double ref_cpu = cpu_now(CLOCK_PROCESS_CPUTIME_ID) - rc0;
    const uint64_t ref_rays = tracer->rays_traced() - rr0;

    const double naive_rate = rates[0].mrays_per_cpu_s;
    const double cook_rate = cook_cpu > 0.0 ? double(cook_rays) / cook_cpu * 1e-6 : 0.0;
    std::printf("one thread each; packet width %d (tracer batches of %d)\n", width,
                tracer->batch_width());
    std::printf("%-50s %12s %10s %9s\n", "query", "rays", "Mrays/cpu-s", "x naive");
    for (const Rate& r : rates) {
      std::printf("%-50s %12zu %10.2f %9.2f\n", r.what.c_str(), r.rays, r.mrays_per_cpu_s,
                  naive_rate > 0.0 ? r.mrays_per_cpu_s / naive_rate : 0.0);
    }
    std::printf("%-50s %12llu %10.2f %9.2f   (%s; %.2f s wall, %.2f s cpu; target >= 0.80)\n",
                "cook (bake_maps, all threads)", static_cast<unsigned long long>(cook_rays),
                cook_rate, naive_rate > 0.0 ? cook_rate / naive_rate : 0.0, quality_name(quality),
                cook_wall, cook_cpu);
    const double ref_rate = ref_cpu > 0.0 ? double(ref_rays) / ref_cpu * 1e-6 : 0.0;
    std::printf("%-50s %12llu %10.2f %9.2f   (%d samples per texel, %.2f s cpu)\n",
                "reference path tracer (all threads)", static_cast<unsigned long long>(ref_rays),
                ref_rate, naive_rate > 0.0 ? ref_rate / naive_rate : 0.0, ro.samples, ref_cpu);
  } catch (const CookError& e) {
    std::fprintf(stderr, "bench_ray_rate: %s\n", e.what());
    return 1;
  }
  return 0;
}
