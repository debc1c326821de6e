// bench_cook_ratio: bakes the same room twice, once with every light and object static and once
// with them semi-dynamic (B + every C_l + every interacting S_ol), and prints the time ratio.
// The paper's figure is slightly above 1x; the goal is 1.1x or less. Times are reported, never
// checked. Indirect light is on (preview quality: final gathering, the objects' change to the
// bounce light in every S_ol); a fourth argument "direct" turns it off. Both scenes are laid out
// and sampled as `lightpatch cook` does: a hand-made grid of texels made the gather find its hits
// by a search real cooks never run, which took half the benchmark's time.
// Usage: bench_cook_ratio [texels per 8 m] [repeats] [wall tessellation, 0 = six slabs] [direct]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <string>

#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/texel_builder.h"
#include "lightpatch/cooker/tracer.h"
#include "lightpatch/cooker/unwrap.h"
#include "test_scenes.h"

using namespace lightpatch::cooker;
namespace test = lightpatch::test;

namespace {

// A wall, floor or ceiling tessellated into k x k quads (as a modelled room's would be).
void add_grid(Scene& s, const glm::vec3& o, const glm::vec3& u, const glm::vec3& v, int k,
              const std::string& name) {
  MeshInstance m;
  m.name = name;
  const glm::vec3 n = glm::normalize(glm::cross(u, v));
  for (int j = 0; j <= k; ++j) {
    for (int i = 0; i <= k; ++i) {
      m.positions.push_back(o + u * (float(i) / float(k)) + v * (float(j) / float(k)));
      m.normals.push_back(n);
    }
  }
  for (int j = 0; j < k; ++j) {
    for (int i = 0; i < k; ++i) {
      const uint32_t a = uint32_t(j * (k + 1) + i), b = a + 1, c = a + uint32_t(k) + 2,
                     d = a + uint32_t(k) + 1;
      for (uint32_t x : {a, b, c, a, c, d}) m.indices.push_back(x);
    }
  }
  s.meshes.push_back(std::move(m));
}

// An 8 x 3 x 8 m room (tessellated shell, static beams and pillars), four lights (one soft),
// six pieces of furniture that are static in one cook and semi-dynamic in the other.
Scene room(bool semi, int tessellation) {
  Scene s;
  if (tessellation > 0) {
    add_grid(s, {-4, 0, -4}, {0, 0, 8}, {8, 0, 0}, tessellation, "floor");
    add_grid(s, {-4, 3, -4}, {8, 0, 0}, {0, 0, 8}, tessellation, "ceiling");
    add_grid(s, {-4, 0, -4}, {0, 3, 0}, {0, 0, 8}, tessellation, "wall_w");
    add_grid(s, {4, 0, -4}, {0, 0, 8}, {0, 3, 0}, tessellation, "wall_e");
    add_grid(s, {-4, 0, -4}, {8, 0, 0}, {0, 3, 0}, tessellation, "wall_n");
    add_grid(s, {-4, 0, 4}, {0, 3, 0}, {8, 0, 0}, tessellation, "wall_s");
    for (int b = 0; b < 4; ++b) {
      const float z = -3.0f + 2.0f * float(b);
      test::add_box(s, {-4, 2.7f, z}, {4, 3, z + 0.2f}, "beam_" + std::to_string(b));
      test::add_box(s, {3.5f, 0, z}, {3.8f, 2.7f, z + 0.3f}, "pillar_" + std::to_string(b));
    }
  } else {
    test::add_closed_room(s, {-4, 0, -4}, {4, 3, 4}, 0.2f, "room");
  }
  const glm::vec3 boxes[6][2] = {
      {{-3, 0, -3}, {-1.5f, 0.8f, -2}},   {{1, 0, -3}, {2.5f, 0.9f, -1.5f}},
      {{-1, 0, -0.5f}, {1, 0.75f, 0.5f}}, {{-3.5f, 0, 1}, {-3, 2, 3}},
      {{2, 0, 2}, {2.6f, 1.2f, 2.6f}},    {{-0.3f, 0.75f, -0.2f}, {0.1f, 1.1f, 0.2f}}};
  for (int i = 0; i < 6; ++i) {
    const std::string name = "furniture_" + std::to_string(i);
    if (semi)
      test::add_object_box(s, boxes[i][0], boxes[i][1], name);
    else
      test::add_box(s, boxes[i][0], boxes[i][1], name);
  }
  s.lights.push_back(test::point_light("lamp_a", {-2, 2.6f, -2}, 8.0f, semi));
  s.lights.push_back(test::point_light("lamp_b", {2, 2.6f, 2}, 8.0f, semi));
  Light soft = test::point_light("candle", {0, 1.4f, 0}, 2.0f, semi);
  soft.radius = 0.05f;
  s.lights.push_back(soft);
  s.lights.push_back(
      test::spot_light("spot", {3.5f, 2.8f, -3.5f}, {-1, -1, 1}, 30.0f, 0.3f, 0.6f, semi));
  test::finish(s);
  return s;
}

struct Run {
  std::string stages;         // stage times and indirect-light figures of the last repeat
  double seconds = 1e30;      // wall clock, best repeat
  double cpu_seconds = 1e30;  // process CPU time (all threads), best repeat
  uint64_t rays = 0;
  size_t maps = 0, pairs = 0;
};

double cpu_now() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

bool g_indirect = true;

// A scene laid out and sampled as `lightpatch cook` does (unwrapped charts on a page, every
// mesh's texels), at n / 8 texels per metre: the gather then finds its hits' texels through the
// layout, as in a real cook.
struct Cookable {
  Scene scene;
  std::unique_ptr<Tracer> tracer;
  Layout layout;
  TexelSet texels;
};

void prepare(Cookable& c, int n) {
  c.tracer = make_embree_tracer(c.scene);
  LayoutOptions lo;
  lo.texels_per_unit = float(n) / 8.0f;
  c.layout = build_layout(c.scene, lo);
  c.texels = build_texels(c.scene, c.layout, c.tracer.get());
}

void bake_once(const Cookable& c, Run& best) {
  const Scene& scene = c.scene;
  const Tracer& tracer = *c.tracer;
  const Layout& layout = c.layout;
  const TexelSet& texels = c.texels;
  BakeOptions options;
  options.quality = Quality::kPreview;
  options.indirect = g_indirect;
  Progress progress(true);
  Report report;
  const uint64_t rays0 = tracer.rays_traced();
  const double c0 = cpu_now();
  const auto t0 = std::chrono::steady_clock::now();
  const BakedMaps maps = bake_maps(scene, layout, texels, tracer, options, progress, report);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  best.cpu_seconds = std::min(best.cpu_seconds, cpu_now() - c0);
  best.seconds = std::min(best.seconds, s);
  best.rays = tracer.rays_traced() - rays0;
  best.maps = 1 + maps.contribution.size() + maps.shadows.size();
  best.pairs = maps.shadows.size();
  const nlohmann::json& root = report.root();
  std::string text;
  if (root.contains("stages")) {
    for (const auto& [k, v] : root["stages"].items())
      text += "  " + k + " " + std::to_string(v.get<double>()) + " s\n";
  }
  if (root.contains("indirect") && root["indirect"].contains("groups")) {
    for (const auto& g : root["indirect"]["groups"]) {
      text += "  indirect " + g["group"].get<std::string>() + ": " +
              g["reason"].get<std::string>() + "\n";
    }
  }
  if (root.contains("decisions")) {
    for (const auto& d : root["decisions"]) {
      const std::string what = d["what"].get<std::string>();
      if (what.rfind("indirect bounce", 0) == 0)
        text += "  " + what + ": " + d["reason"].get<std::string>() + "\n";
    }
  }
  best.stages = text;
}

}  // namespace

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::max(8, std::atoi(argv[1])) : 128;
  const int repeats = argc > 2 ? std::max(1, std::atoi(argv[2])) : 3;
  const int tessellation = argc > 3 ? std::max(0, std::atoi(argv[3])) : 32;
  g_indirect = !(argc > 4 && std::string(argv[4]) == "direct");
  Cookable stat, semi;
  stat.scene = room(false, tessellation);
  semi.scene = room(true, tessellation);
  prepare(stat, n);
  prepare(semi, n);
  const Scene& static_scene = stat.scene;
  const TexelSet& texels = stat.texels;
  Run st, sd;
  // Alternate the two so that load from other processes hits both alike.
  for (int r = 0; r < repeats; ++r) {
    bake_once(stat, st);
    bake_once(semi, sd);
  }
  size_t valid = 0;
  for (uint8_t v : texels.valid) valid += v;
  std::printf(
      "page: %d x %d (%zu valid texels; semi-dynamic %d x %d), best of %d, %zu triangles (72 of "
      "them in the furniture)\n",
      texels.width, texels.height, valid, semi.texels.width, semi.texels.height, repeats,
      static_scene.triangle_count());
  std::printf(
      "static:       %.3f s wall, %.3f s cpu, %llu rays (%.2f Mrays/s per cpu-s), %zu map\n",
      st.seconds, st.cpu_seconds, static_cast<unsigned long long>(st.rays),
      st.rays / st.cpu_seconds * 1e-6, st.maps);
  std::printf(
      "semi-dynamic: %.3f s wall, %.3f s cpu, %llu rays (%.2f Mrays/s per cpu-s), %zu maps "
      "(%zu shadow pairs)\n",
      sd.seconds, sd.cpu_seconds, static_cast<unsigned long long>(sd.rays),
      sd.rays / sd.cpu_seconds * 1e-6, sd.maps, sd.pairs);
  std::printf("static cook:\n%s", st.stages.c_str());
  std::printf("semi-dynamic cook:\n%s", sd.stages.c_str());
  std::printf("ratio semi-dynamic / static: %.3f wall, %.3f cpu (goal <= 1.1)\n",
              sd.seconds / st.seconds, sd.cpu_seconds / st.cpu_seconds);
  return 0;
}
