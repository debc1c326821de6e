// The `accuracy` verb (DESIGN.md, "Accuracy has a price tag"): sweeps the cook's quality knobs
// (presets, gather rays, indirect level, denoising, contact texels, area-light samples, texel
// density, encoding), cooks the scene with each setting, recomposes the authored state from the
// pack on the CPU reference and measures it against a reference bake of the same state (bake_state
// at several times production's settings, cached on disk). Writes a CSV (one row per setting) and a
// PNG plot of error against cook time with the Pareto front marked and the presets labelled. With
// --runtime-csv, also the run-time side: one bake packed with each encoding and recomposed on
// the CPU reference (and with --gles by the GLES runtime) against its float composition.
#include <fcntl.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "args.h"
#include "gles_backend.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/cook.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/import.h"
#include "lightpatch/cooker/io.h"
#include "lightpatch/cooker/pack_builder.h"
#include "lightpatch/cooker/progress.h"
#include "lightpatch/cooker/reference_integrator.h"
#include "lightpatch/cooker/report.h"
#include "lightpatch/cooker/texel_builder.h"
#include "lightpatch/cooker/tracer.h"
#include "lightpatch/cooker/unwrap.h"
#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/scene_state.h"
#include "limit_options.h"
#include "plot_png.h"
#include "verbs.h"

namespace lightpatch::tool {

namespace {

using namespace lightpatch::cooker;

// The reference: by default the path tracer (reference_integrator.h) at --reference-samples
// paths per texel (kQuickReferenceSamples with --quick); with --reference-integrator cook,
// production's integrator with kReferenceFactor times its gather rays and area samples
// (kQuickReferenceFactor with --quick; --reference-scale). Either way a seed of its own,
// so that its noise is independent of the sweep's.
constexpr int kQuickReferenceSamples = 64;
// The path tracer's default: progressive up to 4096 samples per texel, stopping once the noise
// is at most 0.5 % relative RMSE (the test room stops at 4096, the small inn at 1024).
constexpr int kReferenceMaxSamples = 4096;
constexpr double kReferenceNoisePercent = 0.5;
constexpr int kReferenceFactor = 4;
constexpr int kQuickReferenceFactor = 2;
constexpr uint64_t kReferenceSeedOffset = 7919;
constexpr int kDefaultLightmapSize = 128;
constexpr int kQuickLightmapSize = 32;
// Texels that matter (for the max error): reference luminance at least this fraction of the 99th
// percentile of reference luminance over valid texels.
constexpr double kMatterFraction = 0.01;

struct AccuracyOptions {
  std::string scene_path, csv_path, plot_path, runtime_csv_path;
  std::string maps_dir;  // --maps: each row's recomposed map and the reference, as PFM
  bool gles = false;
  int lightmap_size = 0;
  int reference_scale = 0;        // 0 = kReferenceFactor (kQuickReferenceFactor with --quick)
  bool path_traced = true;        // --reference-integrator reference (default) or cook
  int reference_samples = 0;      // 0 = kReferenceMaxSamples (kQuickReferenceSamples, --quick)
  double reference_noise = -1.0;  // percent; < 0 = kReferenceNoisePercent (off with --quick)
  bool quick = false;
  bool no_cache = false;
  int threads = 0;
  uint64_t seed = 1;
  bool quiet = false;
};

// One sweep point.
struct Setting {
  std::string name;  // unique, e.g. "preset=draft", "gather_rays=64"
  std::string knob;  // the series it belongs to
  BakeOptions bake;
  EncodingPolicy encoding = EncodingPolicy::kAuto;
  int lightmap_size = 0;  // the page; 0 = the reference's
  bool label = false;     // a preset: labelled in the plot
};

struct Metrics {
  double rel_rmse = 0.0, max_rel_error = 0.0, psnr_db = 0.0;
  int max_x = -1, max_y = -1;  // the texel of max_rel_error (reference layout), -1 if none
  // The same maximum with each channel's difference less kNoiseSigmas of the reference's standard
  // error there (never below 0): what the reference's own noise cannot explain. Equals
  // max_rel_error without a standard error (the cook as reference, the runtime rows).
  double max_rel_error_beyond_noise = 0.0;
  // rel_rmse^2 = (the row's own error)^2 + (the reference's noise)^2 for independent noise: the
  // row's own error, and whether it is below the noise (then the row cannot be told from rows
  // of smaller error).
  double rel_rmse_excess = 0.0;
  bool within_noise = false;
  // The sign of the error, which a relative RMSE hides: the row's light over the reference's,
  // summed over valid texels and channels, less 1; and the median over the texels that matter of
  // the ratio of their channel sums (1 when the typical texel is right).
  double bias = 0.0, median_ratio = 1.0;
};

struct Row {
  Setting setting;
  double cook_s = 0.0;
  uint64_t rays = 0;
  uint64_t pack_bytes = 0;
  int width = 0, height = 0;
  Metrics m;
  bool pareto = false;
};

// A scene at one layout, ready to bake.
struct Prepared {
  Layout layout;
  TexelSet texels;
};

Prepared prepare_layout(const Scene& scene, const Tracer& tracer, int lightmap_size, int align) {
  Prepared p;
  LayoutOptions lo;
  lo.lightmap_size = lightmap_size;
  lo.align = align;
  p.layout = build_layout(scene, lo);
  p.texels = build_texels(scene, p.layout, &tracer);
  return p;
}

double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// FNV-1a, 64 bits: the reference cache key.
struct Hasher {
  uint64_t h = 1469598103934665603ull;
  void bytes(const void* data, size_t n) {
    const uint8_t* p = static_cast<const uint8_t*>(data);
    for (size_t i = 0; i < n; ++i) {
      h ^= p[i];
      h *= 1099511628211ull;
    }
  }
  template <typename T>
  void value(const T& v) {
    bytes(&v, sizeof(v));
  }
  void text(const std::string& s) {
    value(s.size());
    bytes(s.data(), s.size());
  }
};

float luminance(const float* rgb) {
  return 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2];
}

// What the comparisons need from the reference, computed once.
struct ReferenceStats {
  std::vector<uint32_t> valid;   // valid texel indices
  std::vector<uint8_t> matters;  // per valid texel
  double peak = 0.0;             // PSNR peak: 99th percentile of max-channel irradiance
  double sum_sq = 0.0;           // sum of squared channel values over valid texels
};

double percentile99(std::vector<float> v) {
  if (v.empty()) return 0.0;
  const size_t k = std::min(v.size() - 1, size_t(std::floor(0.99 * double(v.size() - 1))));
  std::nth_element(v.begin(), v.begin() + long(k), v.end());
  return v[k];
}

// The texels the sweep judges: valid, of meshes that cast shadows. A light's own flame or bulb
// (which the light sits in) is left out: what it receives from inside its light is no receiver's
// light map.
bool judged(const TexelSet& texels, const Scene& scene, size_t i) {
  if (!texels.valid[i]) return false;
  const int mesh = texels.mesh.empty() ? -1 : texels.mesh[i];
  return mesh < 0 || scene.meshes[size_t(mesh)].cast_shadows;
}

ReferenceStats reference_stats(const FloatImage& ref, const TexelSet& texels, const Scene& scene) {
  ReferenceStats s;
  std::vector<float> lum, peak;
  for (size_t i = 0; i < texels.valid.size(); ++i) {
    if (!judged(texels, scene, i)) continue;
    const float* r = &ref.data[i * 3];
    s.valid.push_back(uint32_t(i));
    lum.push_back(luminance(r));
    peak.push_back(std::max({r[0], r[1], r[2]}));
    for (int c = 0; c < 3; ++c) s.sum_sq += double(r[c]) * r[c];
  }
  const double cut = kMatterFraction * percentile99(lum);
  for (float l : lum) s.matters.push_back(l >= cut && l > 0.0f ? 1 : 0);
  s.peak = percentile99(peak);
  return s;
}

// Standard errors a texel's difference from the path tracer must exceed to count beyond its noise
// (one texel in about 700 of honest noise would pass 3 in one channel).
constexpr double kNoiseSigmas = 3.0;

// `map`: RGB at the reference's layout; `se`: the reference's standard error there, or null.
Metrics compare(const std::vector<float>& map, const FloatImage& ref, const ReferenceStats& s,
                const FloatImage* se = nullptr) {
  Metrics m;
  double sq = 0.0, sum_x = 0.0, sum_r = 0.0;
  std::vector<double> ratios;
  for (size_t k = 0; k < s.valid.size(); ++k) {
    const size_t i = s.valid[k];
    const float* r = &ref.data[i * 3];
    const float* x = &map[i * 3];
    const double tx = double(x[0]) + x[1] + x[2], tr = double(r[0]) + r[1] + r[2];
    sum_x += tx;
    sum_r += tr;
    if (s.matters[k] && tr > 0.0) ratios.push_back(tx / tr);
    double worst = 0.0, beyond = 0.0;
    for (int c = 0; c < 3; ++c) {
      const double d = double(x[c]) - double(r[c]);
      sq += d * d;
      worst = std::max(worst, std::abs(d));
      const double noise = se ? kNoiseSigmas * double(se->data[i * 3 + size_t(c)]) : 0.0;
      beyond = std::max(beyond, std::abs(d) - noise);
    }
    if (s.matters[k]) {
      const double denom = std::max({r[0], r[1], r[2]});
      if (worst / denom > m.max_rel_error) {
        m.max_rel_error = worst / denom;
        m.max_x = int(i % size_t(ref.width));
        m.max_y = int(i / size_t(ref.width));
      }
      m.max_rel_error_beyond_noise = std::max(m.max_rel_error_beyond_noise, beyond / denom);
    }
  }
  m.rel_rmse = s.sum_sq > 0.0 ? std::sqrt(sq / s.sum_sq) : 0.0;
  m.bias = sum_r > 0.0 ? sum_x / sum_r - 1.0 : 0.0;
  if (!ratios.empty()) {
    const size_t mid = ratios.size() / 2;
    std::nth_element(ratios.begin(), ratios.begin() + long(mid), ratios.end());
    m.median_ratio = ratios[mid];
  }
  const double n = 3.0 * double(std::max<size_t>(1, s.valid.size()));
  const double mse = sq / n;
  m.psnr_db = mse > 0.0 ? 10.0 * std::log10(s.peak * s.peak / mse) : HUGE_VAL;
  return m;
}

// The authored state recomposed from pack bytes on the CPU reference.
std::vector<float> recompose_authored(const std::vector<uint8_t>& pack) {
  PackView view;
  Error error;
  // The CPU reference takes float maps: only the format is checked, not the GLES runtime's limits.
  if (PackView::open(pack.data(), pack.size(), RecomposeLimits::format_only(), &view, &error) !=
      Status::kOk) {
    throw CookError(std::string("accuracy: the cooked pack does not load: ") + error.message);
  }
  SceneState state;
  CpuRecomposer recomposer;
  if (state.init(view, &error) != Status::kOk || recomposer.init(view, &error) != Status::kOk) {
    throw CookError(std::string("accuracy: recompose: ") + error.message);
  }
  if (recomposer.rebuild(state) != Status::kOk) throw CookError("accuracy: recompose failed");
  const size_t n = size_t(recomposer.width()) * recomposer.height() * 3;
  return std::vector<float>(recomposer.rgb(), recomposer.rgb() + n);
}

// Resamples a map of another layout of the same scene to the reference layout: each valid
// reference texel takes the value of the nearest valid texel (by world position) of the same mesh
// whose normal is within 60 degrees. Nearest, not bilinear: this overstates a coarse map's error a
// little next to what a renderer's filtering shows.
std::vector<float> resample_to(const std::vector<float>& map, const TexelSet& from,
                               const TexelSet& to, float cell) {
  struct Key {
    int64_t x, y, z;
    bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
  };
  struct KeyHash {
    size_t operator()(const Key& k) const {
      return size_t(k.x * 73856093 ^ k.y * 19349663 ^ k.z * 83492791);
    }
  };
  auto key_of = [cell](const glm::vec3& p) {
    return Key{int64_t(std::floor(p.x / cell)), int64_t(std::floor(p.y / cell)),
               int64_t(std::floor(p.z / cell))};
  };
  std::unordered_map<Key, std::vector<uint32_t>, KeyHash> grid;
  for (size_t i = 0; i < from.valid.size(); ++i) {
    if (from.valid[i]) grid[key_of(from.position[i])].push_back(uint32_t(i));
  }
  std::vector<float> out(to.valid.size() * 3, 0.0f);
  for (size_t i = 0; i < to.valid.size(); ++i) {
    if (!to.valid[i]) continue;
    const glm::vec3 p = to.position[i];
    const Key k = key_of(p);
    int64_t best = -1;
    float best_d = HUGE_VALF;
    for (int reach = 1; reach <= 8 && best < 0; reach *= 2) {
      for (int64_t dz = -reach; dz <= reach; ++dz) {
        for (int64_t dy = -reach; dy <= reach; ++dy) {
          for (int64_t dx = -reach; dx <= reach; ++dx) {
            const auto it = grid.find(Key{k.x + dx, k.y + dy, k.z + dz});
            if (it == grid.end()) continue;
            for (uint32_t j : it->second) {
              if (from.mesh[j] != to.mesh[i]) continue;
              if (glm::dot(from.normal[j], to.normal[i]) < 0.5f) continue;
              const glm::vec3 d = from.position[j] - p;
              const float d2 = glm::dot(d, d);
              if (d2 < best_d) {
                best_d = d2;
                best = j;
              }
            }
          }
        }
      }
    }
    if (best < 0) continue;  // no counterpart: stays 0 and counts as error
    for (int c = 0; c < 3; ++c) out[i * 3 + size_t(c)] = map[size_t(best) * 3 + size_t(c)];
  }
  return out;
}

std::vector<Setting> make_sweep(const AccuracyOptions& o, bool has_area_lights, int base_size) {
  std::vector<Setting> s;
  BakeOptions base;
  base.seed = o.seed;
  base.threads = o.threads;
  auto preset = [&](Quality q) {
    Setting x;
    x.name = std::string("preset=") + quality_name(q);
    x.knob = "preset";
    x.bake = base;
    x.bake.quality = q;
    x.label = true;
    return x;
  };
  // One knob turned from preset q, the others at q's values; unlabelled on the plot.
  auto turned = [&](Quality q, const std::string& name, const char* series) {
    Setting x = preset(q);
    x.name = name;
    x.knob = series;
    x.label = false;
    return x;
  };
  auto encoding = [&](Quality q, EncodingPolicy e) {
    Setting x =
        turned(q,
               std::string("encoding=") + (e == EncodingPolicy::kLinear ? "linear" : "square") +
                   " (" + quality_name(q) + ")",
               "encoding");
    x.encoding = e;
    return x;
  };
  if (o.quick) {
    s.push_back(preset(Quality::kDraft));
    s.push_back(preset(Quality::kProduction));
    s.push_back(encoding(Quality::kDraft, EncodingPolicy::kLinear));
    s.push_back(encoding(Quality::kDraft, EncodingPolicy::kSquare));
    return s;
  }
  for (Quality q : {Quality::kDraft, Quality::kPreview, Quality::kProduction}) {
    s.push_back(preset(q));
  }
  // Each knob swept around the preview preset, the others at preview's values.
  const Quality p = Quality::kPreview;
  for (int n : {32, 64, 128, 512, 1024}) {
    Setting x = turned(p, "gather_rays=" + std::to_string(n), "gather rays");
    x.bake.gather_rays = n;
    s.push_back(x);
  }
  for (int n : {1, 4, 8}) {
    Setting x = turned(p, "indirect_scale=" + std::to_string(n), "indirect scale");
    x.bake.indirect_scale = n;
    s.push_back(x);
  }
  for (int n : {0, 1, 3}) {
    Setting x = turned(p, "denoise=" + std::to_string(n), "denoise");
    x.bake.denoise = n;
    s.push_back(x);
  }
  {
    Setting x = turned(p, "contact_texels=on", "contact texels");
    x.bake.contact_texels = true;
    s.push_back(x);
  }
  if (has_area_lights) {
    for (int n : {1, 4, 32, 64}) {
      Setting x = turned(p, "area_samples=" + std::to_string(n), "area samples");
      x.bake.area_samples = n;
      s.push_back(x);
    }
  }
  for (int size : {base_size / 4, base_size / 2}) {
    if (size < 8) continue;
    Setting x = turned(p, "lightmap_size=" + std::to_string(size), "texel density");
    x.lightmap_size = size;
    s.push_back(x);
  }
  for (EncodingPolicy e : {EncodingPolicy::kLinear, EncodingPolicy::kSquare}) {
    s.push_back(encoding(p, e));
  }
  return s;
}

const char* encoding_name(EncodingPolicy e) {
  switch (e) {
    case EncodingPolicy::kAuto:
      return "auto";
    case EncodingPolicy::kLinear:
      return "linear";
    case EncodingPolicy::kSquare:
      return "square";
  }
  return "auto";
}

bool same_bake(const Setting& a, const Setting& b) {
  return a.lightmap_size == b.lightmap_size && a.bake.quality == b.bake.quality &&
         gather_preset(a.bake).rays == gather_preset(b.bake).rays &&
         gather_preset(a.bake).level == gather_preset(b.bake).level &&
         gather_preset(a.bake).denoise == gather_preset(b.bake).denoise &&
         a.bake.contact_texels == b.bake.contact_texels &&
         a.bake.area_samples == b.bake.area_samples && a.bake.seed == b.bake.seed &&
         a.bake.indirect == b.bake.indirect;
}

// Errors below the reference's noise (`floor`, as a rel_rmse) count as equal: a row does not win
// by an error the reference cannot resolve.
void mark_pareto(std::vector<Row>& rows, double floor) {
  auto err = [floor](const Row& r) { return std::max(r.m.rel_rmse, floor); };
  for (Row& r : rows) {
    r.pareto = true;
    for (const Row& o : rows) {
      if (&o == &r) continue;
      const bool no_worse = o.cook_s <= r.cook_s && err(o) <= err(r);
      const bool better = o.cook_s < r.cook_s || err(o) < err(r);
      if (no_worse && better) {
        r.pareto = false;
        break;
      }
    }
  }
}

std::string number(double v, const char* format = "%.6g") {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, v);
  return buf;
}

std::string csv_text(const std::vector<Row>& rows, const std::vector<std::string>& notes) {
  std::string s;
  for (const std::string& n : notes) s += "# " + n + "\n";
  s += "setting,knob,quality,gather_rays,indirect_scale,denoise,area_samples,lightmap_size,"
       "encoding,cook_s,rays,pack_bytes,rel_rmse,max_rel_error,psnr_db,pareto,rel_rmse_excess,"
       "within_noise,max_rel_error_beyond_noise,max_error_x,max_error_y,bias,median_ratio\n";
  for (const Row& r : rows) {
    const BakeOptions& b = r.setting.bake;
    const GatherPreset gp = gather_preset(b);
    const int samples = b.area_samples > 0               ? b.area_samples
                        : b.quality == Quality::kDraft   ? 4
                        : b.quality == Quality::kPreview ? 16
                                                         : 64;
    s += "\"" + r.setting.name + "\"," + r.setting.knob + "," + quality_name(b.quality) + "," +
         std::to_string(gp.rays) + "," + std::to_string(gp.level) + "," +
         std::to_string(gp.denoise) + "," + std::to_string(samples) + "," +
         std::to_string(r.width) + "," + encoding_name(r.setting.encoding) + "," +
         number(r.cook_s, "%.4f") + "," + std::to_string(r.rays) + "," +
         std::to_string(r.pack_bytes) + "," + number(r.m.rel_rmse) + "," +
         number(r.m.max_rel_error) + "," + number(r.m.psnr_db, "%.3f") + "," +
         (r.pareto ? "1" : "0") + "," + number(r.m.rel_rmse_excess) + "," +
         (r.m.within_noise ? "1" : "0") + "," + number(r.m.max_rel_error_beyond_noise) + "," +
         std::to_string(r.m.max_x) + "," + std::to_string(r.m.max_y) + "," + number(r.m.bias) +
         "," + number(r.m.median_ratio) + "\n";
  }
  return s;
}

std::string folder_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
}

void probe_output_folder(const std::string& path) {
  const std::string dir = folder_of(path);
  std::string probe = dir + "/.lightpatch-probe.XXXXXX";
  const int fd = ::mkstemp(probe.data());
  if (fd < 0) throw CookError("cannot write into '" + dir + "' (for '" + path + "')");
  ::close(fd);
  ::unlink(probe.c_str());
}

std::string hex64(uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

// The authored state composed in float from the cook's unquantized maps, as the runtime's
// equation does (DESIGN.md, The method in one screen): every light on at its authored colour and
// intensity, every object visible. The runtime rows' reference: what a pack would give with no
// 8-bit encoding and an exact target.
std::vector<float> compose_authored_float(const Scene& scene, const BakedMaps& maps, int w, int h) {
  const size_t n = size_t(w) * size_t(h);
  std::vector<float> out(n * 3, 0.0f);
  auto add = [&](const FloatImage& m, const glm::vec3& f) {
    for (size_t i = 0; i < n; ++i) {
      for (int c = 0; c < 3; ++c) {
        const float v = m.channels == 1 ? m.data[i] : m.data[i * 3 + size_t(c)];
        out[i * 3 + size_t(c)] += f[c] * v;
      }
    }
  };
  add(maps.base, glm::vec3(1.0f));
  for (const StaticShadowMap& s : maps.static_shadows) add(s.map, glm::vec3(-1.0f));
  auto factor = [&](int light) {
    const Light& l = scene.lights[size_t(maps.lights[size_t(light)])];
    return l.color * l.intensity;
  };
  for (size_t l = 0; l < maps.contribution.size(); ++l) add(maps.contribution[l], factor(int(l)));
  for (const ShadowMap& s : maps.shadows) add(s.map, -factor(s.light));
  for (const PairCorrectionMap& p : maps.pair_corrections) add(p.map, factor(p.light));
  return out;
}

// One runtime row: a pack's encoding and a light-map target, against the float composition.
struct RuntimeRow {
  std::string encoding, target;
  double recompose_ms = -1.0;  // < 0: not measured
  uint64_t atlas_bytes = 0, target_bytes = 0;
  Metrics m;
};

uint64_t atlas_bytes_of(const std::vector<uint8_t>& pack) {
  PackView view;
  Error error;
  if (PackView::open(pack.data(), pack.size(), RecomposeLimits::format_only(), &view, &error) !=
      Status::kOk) {
    throw CookError(std::string("accuracy: the cooked pack does not load: ") + error.message);
  }
  uint64_t bytes = 0;
  for (uint32_t i = 0; i < view.atlas_count(); ++i) {
    bytes += uint64_t(view.atlas(i).width) * view.atlas(i).height * 4;
  }
  return bytes;
}

// Median wall time of `reps` full rebuilds of the authored state on the CPU reference (ms).
double cpu_rebuild_ms(const std::vector<uint8_t>& pack, int reps) {
  PackView view;
  Error error;
  SceneState state;
  CpuRecomposer recomposer;
  if (PackView::open(pack.data(), pack.size(), RecomposeLimits::format_only(), &view, &error) !=
          Status::kOk ||
      state.init(view, &error) != Status::kOk || recomposer.init(view, &error) != Status::kOk) {
    throw CookError(std::string("accuracy: recompose: ") + error.message);
  }
  std::vector<double> ms;
  for (int r = 0; r < reps; ++r) {
    const auto t = std::chrono::steady_clock::now();
    if (recomposer.rebuild(state) != Status::kOk) throw CookError("accuracy: recompose failed");
    ms.push_back(1000.0 * since(t));
  }
  std::nth_element(ms.begin(), ms.begin() + long(ms.size() / 2), ms.end());
  return ms[ms.size() / 2];
}

// --maps: DIR/NAME.pfm, NAME a row's setting ("preset=preview" -> "preset_preview") or
// "reference"; characters other than letters, digits, '.', '-' and '_' become '_'.
std::string map_path(const std::string& dir, const std::string& name) {
  std::string file;
  for (char c : name) {
    const bool keep =
        std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_';
    file += keep ? c : '_';
  }
  return (std::filesystem::path(dir) / (file + ".pfm")).string();
}

std::string runtime_csv_text(const std::vector<RuntimeRow>& rows,
                             const std::vector<std::string>& notes) {
  std::string s;
  for (const std::string& n : notes) s += "# " + n + "\n";
  s += "encoding,target,recompose_ms,atlas_bytes,target_bytes,rel_rmse,max_rel_error,psnr_db\n";
  for (const RuntimeRow& r : rows) {
    s += r.encoding + "," + r.target + "," +
         (r.recompose_ms >= 0.0 ? number(r.recompose_ms, "%.4f") : std::string("")) + "," +
         std::to_string(r.atlas_bytes) + "," + std::to_string(r.target_bytes) + "," +
         number(r.m.rel_rmse) + "," + number(r.m.max_rel_error) + "," +
         number(r.m.psnr_db, "%.3f") + "\n";
  }
  return s;
}

}  // namespace

int verb_accuracy(Args& args) {
  AccuracyOptions o;
  args.option("--csv", &o.csv_path);
  args.option("--plot", &o.plot_path);
  args.option("--runtime-csv", &o.runtime_csv_path);
  args.option("--maps", &o.maps_dir);
  o.gles = args.flag("--gles");
  o.quick = args.flag("--quick");
  o.no_cache = args.flag("--no-cache");
  o.lightmap_size = args.int_option("--lightmap-size", 0, 8, 4096);
  o.reference_scale = args.int_option("--reference-scale", 0, 1, 16);
  std::string integrator = "reference";
  if (!args.option("--reference-integrator", &integrator)) integrator = "reference";
  o.reference_samples = args.int_option("--reference-samples", 0, 2, 1 << 20);
  o.reference_noise = args.float_option("--reference-noise", -1.0f, 0.0f, 100.0f);
  o.threads = args.int_option("--threads", 0, 1, 1024);
  o.seed = static_cast<uint64_t>(args.int_option("--seed", 1, 0, 2'000'000'000));
  o.quiet = args.flag("--quiet", "-q");
  const ImportLimits import_limits = parse_import_limits(args);
  o.scene_path = args.positional("SCENE");
  args.finish();
  if (o.csv_path.empty()) throw ArgsError("missing --csv OUT.csv");
  if (o.plot_path.empty()) throw ArgsError("missing --plot OUT.png");
  if (o.csv_path == o.plot_path) throw ArgsError("--csv and --plot name the same file");
  if (!o.runtime_csv_path.empty() &&
      (o.runtime_csv_path == o.csv_path || o.runtime_csv_path == o.plot_path)) {
    throw ArgsError("--runtime-csv names the same file as --csv or --plot");
  }
  if (o.gles && o.runtime_csv_path.empty()) throw ArgsError("--gles needs --runtime-csv");
  if (integrator != "reference" && integrator != "cook") {
    throw ArgsError("--reference-integrator must be reference or cook, got '" + integrator + "'");
  }
  o.path_traced = integrator == "reference";
  if (o.path_traced && o.reference_scale > 0) {
    throw ArgsError("--reference-scale is for --reference-integrator cook");
  }
  if (!o.path_traced && (o.reference_samples > 0 || o.reference_noise >= 0.0)) {
    throw ArgsError(
        "--reference-samples and --reference-noise are for --reference-integrator reference");
  }
  if (o.reference_samples == 0) {
    o.reference_samples = o.quick ? kQuickReferenceSamples : kReferenceMaxSamples;
  }
  if (o.reference_noise < 0.0) o.reference_noise = o.quick ? 0.0 : kReferenceNoisePercent;
  if (o.lightmap_size == 0) o.lightmap_size = o.quick ? kQuickLightmapSize : kDefaultLightmapSize;
  check_command_files({o.scene_path}, {o.csv_path, o.plot_path, o.runtime_csv_path});
  probe_output_folder(o.csv_path);
  probe_output_folder(o.plot_path);
  if (!o.runtime_csv_path.empty()) probe_output_folder(o.runtime_csv_path);
  if (!o.maps_dir.empty()) {
    std::error_code ec;
    if (!std::filesystem::is_directory(o.maps_dir, ec)) {
      throw ArgsError("--maps " + o.maps_dir + ": not a folder (create it first)");
    }
    probe_output_folder(map_path(o.maps_dir, "reference"));
  }

  const auto t_all = std::chrono::steady_clock::now();
  Progress progress(o.quiet);
  Progress silent(true);
  Report scratch;

  progress.begin("import", 1);
  const Scene scene = import_gltf(o.scene_path, import_limits);
  progress.end();
  progress.begin("trace setup", 1);
  const std::unique_ptr<Tracer> tracer = make_embree_tracer(scene);
  progress.end();
  progress.begin("layout and texels", 1);
  // The reference's layout is aligned as the preview preset's, which most rows use.
  BakeOptions preview;
  const int ref_align = layout_align(preview);
  const Prepared ref_layout = prepare_layout(scene, *tracer, o.lightmap_size, ref_align);
  progress.end();
  for (const std::string& note : ref_layout.layout.notes) progress.message("note: " + note);

  // The reference: cached next to the CSV, keyed by the scene file, the imported scene's texels
  // and lights, the layout and the reference's options.
  BakeOptions ref_options;
  const int factor = o.reference_scale > 0 ? o.reference_scale
                     : o.quick             ? kQuickReferenceFactor
                                           : kReferenceFactor;
  {
    BakeOptions prod;
    prod.quality = Quality::kProduction;
    ref_options.quality = Quality::kProduction;
    ref_options.gather_rays = gather_preset(prod).rays * factor;
    ref_options.area_samples = 64 * factor;
    ref_options.seed = o.seed + kReferenceSeedOffset;
    ref_options.threads = o.threads;
  }
  ReferenceOptions pt_options;
  pt_options.samples = o.reference_samples;
  pt_options.target_noise = 0.01 * o.reference_noise;
  pt_options.seed = o.seed + kReferenceSeedOffset;
  pt_options.threads = o.threads;
  // Only the judged texels are traced, so the noise target stops on the noise the rows are
  // judged against (the bright flames' texels had stopped the small inn's at 1.2 % for 0.5 %).
  pt_options.region.resize(ref_layout.texels.valid.size());
  for (size_t i = 0; i < pt_options.region.size(); ++i)
    pt_options.region[i] = judged(ref_layout.texels, scene, i);
  Hasher hasher;
  // v3: a texel's value is its mean over its surface patch (texel_footprint.h); v4: the judged
  // texels only; v5: the patch less the cells behind static geometry.
  hasher.text(o.path_traced ? "lightpatch accuracy reference v5: path tracing"
                            : "lightpatch accuracy reference v1");
  {
    const std::vector<uint8_t> file = read_file(o.scene_path);
    hasher.bytes(file.data(), file.size());
    const TexelSet& t = ref_layout.texels;
    hasher.value(t.width);
    hasher.value(t.height);
    hasher.bytes(t.position.data(), t.position.size() * sizeof(glm::vec3));
    hasher.bytes(t.normal.data(), t.normal.size() * sizeof(glm::vec3));
    hasher.bytes(t.albedo.data(), t.albedo.size() * sizeof(glm::vec3));
    hasher.bytes(t.valid.data(), t.valid.size());
    for (const Light& l : scene.lights) {
      hasher.text(l.name);
      hasher.value(l.type);
      hasher.value(l.position);
      hasher.value(l.direction);
      hasher.value(l.color);
      hasher.value(l.intensity);
      hasher.value(l.range);
      hasher.value(l.inner_cone);
      hasher.value(l.outer_cone);
      hasher.value(l.radius);
      hasher.value(l.semi_dynamic);
    }
    if (o.path_traced) {
      // The definition of a texel's light (its patch, texel_footprint.h; paths that start inside
      // solid geometry dropped): a change to it is a new reference.
      hasher.text("reference 2: inside paths dropped, a patch with no open cell its point");
      hasher.value(pt_options.samples);
      hasher.value(pt_options.target_noise);
      hasher.value(pt_options.seed);
    } else {
      hasher.value(ref_options.quality);
      hasher.value(ref_options.area_samples);
      hasher.value(ref_options.gather_rays);
      hasher.value(ref_options.integrator);
      hasher.value(ref_options.seed);
    }
  }
  const std::string cache_stem =
      folder_of(o.csv_path) + "/lightpatch-accuracy-reference-" + hex64(hasher.h);
  const std::string cache_path = cache_stem + ".pfm";
  // The path tracer's also: its standard-error map and what it traced (samples, rays, seconds).
  const std::string cache_error_path = cache_stem + ".stderr.pfm";
  const std::string cache_info_path = cache_stem + ".json";
  FloatImage reference, reference_error;
  nlohmann::json ref_info = nlohmann::json::object();
  bool cached = false;
  if (!o.no_cache && std::filesystem::exists(cache_path) &&
      (!o.path_traced ||
       (std::filesystem::exists(cache_error_path) && std::filesystem::exists(cache_info_path)))) {
    try {
      reference = read_pfm(cache_path);
      const auto fits = [&](const FloatImage& m) {
        return m.width == ref_layout.layout.width && m.height == ref_layout.layout.height &&
               m.channels == 3;
      };
      cached = fits(reference);
      if (o.path_traced) {
        reference_error = read_pfm(cache_error_path);
        const std::vector<uint8_t> text = read_file(cache_info_path);
        ref_info = nlohmann::json::parse(text.begin(), text.end(), nullptr, false);
        cached = cached && fits(reference_error) && ref_info.is_object() &&
                 ref_info.contains("samples") && ref_info["samples"].is_number_integer();
      }
    } catch (const CookError& e) {
      progress.message(std::string("note: reference cache unreadable, baking again: ") + e.what());
      cached = false;
    }
  }
  const std::string ref_what =
      o.path_traced
          ? "path tracing, up to " + std::to_string(pt_options.samples) + " samples per texel" +
                (pt_options.target_noise > 0.0
                     ? ", stopping at " + number(100.0 * pt_options.target_noise, "%.3g") +
                           " % noise"
                     : std::string())
          : "production x" + std::to_string(factor) + ": " +
                std::to_string(ref_options.gather_rays) + " gather rays, " +
                std::to_string(ref_options.area_samples) + " area samples";
  double ref_seconds = 0.0;
  if (cached) {
    progress.message("reference: using the cache " + cache_path);
  } else {
    progress.message("reference: baking (" + ref_what + ")");
    const auto t = std::chrono::steady_clock::now();
    if (o.path_traced) {
      ReferenceBake rb = bake_reference(scene, ref_layout.texels, *tracer, StateSpec{}, pt_options,
                                        progress, scratch);
      reference = std::move(rb.map);
      reference_error = std::move(rb.std_error);
      finalize_map(reference_error, scene, ref_layout.layout, ref_layout.texels);
      ref_info = {{"samples", rb.samples},
                  {"rays", rb.rays},
                  {"seconds", rb.seconds},
                  {"inside_path_fraction", rb.inside_path_fraction},
                  {"inside_texels", rb.inside_texels}};
    } else {
      reference = bake_state(scene, ref_layout.layout, ref_layout.texels, *tracer, StateSpec{},
                             ref_options, progress, scratch);
    }
    finalize_map(reference, scene, ref_layout.layout, ref_layout.texels);
    ref_seconds = since(t);
    write_pfm(cache_path, reference);
    if (o.path_traced) {
      write_pfm(cache_error_path, reference_error);
      const std::string text = ref_info.dump(1) + "\n";
      write_file_atomic(cache_info_path, text.data(), text.size());
    }
    progress.message("reference: baked in " + number(ref_seconds, "%.2f") + " s, cached in " +
                     cache_path);
  }
  for (float v : reference.data) {
    if (!std::isfinite(v)) throw CookError("accuracy: the reference map has a non-finite texel");
  }
  if (!o.maps_dir.empty()) {
    write_pfm(map_path(o.maps_dir, "reference"), reference);
    if (o.path_traced) write_pfm(map_path(o.maps_dir, "reference.stderr"), reference_error);
  }
  const ReferenceStats stats = reference_stats(reference, ref_layout.texels, scene);
  if (stats.valid.empty()) throw CookError("accuracy: the scene has no light-map texels");
  if (!(stats.peak > 0.0)) throw CookError("accuracy: the scene is unlit (the reference is black)");
  // The path-traced reference's own noise: as a relative RMSE (what it alone adds to every row's
  // rel_rmse) and as the mean relative standard error over the texels that matter.
  double noise_rmse = 0.0, noise_mean_rel = 0.0;
  if (o.path_traced) {
    double se2 = 0.0, rel = 0.0;
    size_t counted = 0;
    for (size_t k = 0; k < stats.valid.size(); ++k) {
      const float* e = &reference_error.data[size_t(stats.valid[k]) * 3];
      const float* r = &reference.data[size_t(stats.valid[k]) * 3];
      const double e2 = double(e[0]) * e[0] + double(e[1]) * e[1] + double(e[2]) * e[2];
      se2 += e2;
      const double r2 = double(r[0]) * r[0] + double(r[1]) * r[1] + double(r[2]) * r[2];
      if (stats.matters[k] && r2 > 0.0) {
        rel += std::sqrt(e2 / r2);
        ++counted;
      }
    }
    noise_rmse = stats.sum_sq > 0.0 ? std::sqrt(se2 / stats.sum_sq) : 0.0;
    noise_mean_rel = counted > 0 ? rel / double(counted) : 0.0;
    progress.message("reference noise: relative RMSE " + number(100.0 * noise_rmse, "%.3f") +
                     " %, mean relative standard error " + number(100.0 * noise_mean_rel, "%.3f") +
                     " % over the texels that matter");
  }

  bool has_area = false;
  for (const Light& l : scene.lights) {
    has_area = has_area || (l.radius > 0.0f && l.type != LightType::kDirectional);
  }
  for (const Material& m : scene.materials) {
    has_area = has_area || m.emissive != glm::vec3(0.0f);
  }
  const std::vector<Setting> sweep = make_sweep(o, has_area, o.lightmap_size);

  std::vector<Row> rows;
  std::vector<std::string> skipped;  // settings the scene cannot take (a page too small)
  struct Baked {
    Setting setting;
    BakedMaps maps;
    double seconds = 0.0;
    uint64_t rays = 0;
  };
  std::vector<Baked> baked;  // bakes reused by settings that differ only in encoding
  progress.begin("sweep", sweep.size());
  for (const Setting& setting : sweep) {
    Row row;
    row.setting = setting;
    const Prepared* prepared = &ref_layout;
    Prepared other;
    const int size = setting.lightmap_size > 0 ? setting.lightmap_size : o.lightmap_size;
    const int align = layout_align(setting.bake);
    if (size != o.lightmap_size || align != ref_align) {
      try {
        other = prepare_layout(scene, *tracer, size, align);
      } catch (const CookError& e) {
        skipped.push_back(setting.name + " skipped: " + e.what());
        progress.message("note: " + skipped.back());
        progress.advance();
        continue;
      }
      prepared = &other;
    }
    const Baked* reuse = nullptr;
    for (const Baked& b : baked) {
      if (same_bake(b.setting, setting)) reuse = &b;
    }
    Baked fresh;
    if (!reuse) {
      const uint64_t rays0 = tracer->rays_traced();
      const auto t = std::chrono::steady_clock::now();
      Report report;
      fresh.maps = bake_maps(scene, prepared->layout, prepared->texels, *tracer, setting.bake,
                             silent, report);
      finalize_maps(fresh.maps, scene, prepared->layout, prepared->texels);
      fresh.seconds = since(t);
      fresh.rays = tracer->rays_traced() - rays0;
      fresh.setting = setting;
      reuse = &fresh;
    }
    const auto t = std::chrono::steady_clock::now();
    Report report;
    // The pack `cook` makes of this setting (its preset's tolerances, the panes' level), in the
    // row's encoding.
    PackOptions po = pack_options(setting.bake);
    po.encoding = setting.encoding;
    const std::vector<uint8_t> pack = build_pack(scene, prepared->layout, reuse->maps, po, report);
    row.cook_s = reuse->seconds + since(t);
    row.rays = reuse->rays;
    row.pack_bytes = pack.size();
    row.width = prepared->layout.width;
    row.height = prepared->layout.height;
    std::vector<float> map = recompose_authored(pack);
    if (prepared != &ref_layout) {
      const float cell = 2.0f / std::max(1e-6f, prepared->layout.texels_per_unit);
      map = resample_to(map, prepared->texels, ref_layout.texels, cell);
    }
    for (float v : map) {
      if (!std::isfinite(v)) throw CookError("accuracy: " + setting.name + ": non-finite texel");
    }
    row.m = compare(map, reference, stats, o.path_traced ? &reference_error : nullptr);
    if (!o.maps_dir.empty()) {
      FloatImage image(ref_layout.layout.width, ref_layout.layout.height, 3);
      image.data = map;
      write_pfm(map_path(o.maps_dir, setting.name), image);
    }
    rows.push_back(row);
    if (reuse == &fresh && setting.lightmap_size == 0) baked.push_back(std::move(fresh));
    progress.advance();
  }
  progress.end();
  for (Row& r : rows) {
    r.m.rel_rmse_excess =
        std::sqrt(std::max(0.0, r.m.rel_rmse * r.m.rel_rmse - noise_rmse * noise_rmse));
    r.m.within_noise = noise_rmse > 0.0 && r.m.rel_rmse_excess <= noise_rmse;
  }
  mark_pareto(rows, std::sqrt(2.0) * noise_rmse);

  // The runtime: the encoding rows' bake packed with each encoding, recomposed on the CPU
  // reference (float32 target) and, with --gles, by the GLES runtime (RGBA16F target), against
  // the float composition of the same bake's unquantized maps.
  std::vector<RuntimeRow> runtime_rows;
  std::vector<std::string> runtime_notes;
  if (!o.runtime_csv_path.empty()) {
    const Baked* source = nullptr;
    for (const Setting& st : sweep) {
      if (st.knob != "encoding") continue;
      for (const Baked& b : baked) {
        if (same_bake(b.setting, st)) source = &b;
      }
    }
    if (!source) throw CookError("accuracy: no bake for the runtime rows");
    const int w = ref_layout.layout.width, h = ref_layout.layout.height;
    FloatImage float_ref(w, h, 3);
    float_ref.data = compose_authored_float(scene, source->maps, w, h);
    const ReferenceStats fstats = reference_stats(float_ref, ref_layout.texels, scene);
    progress.begin("runtime", 3);
    for (EncodingPolicy e :
         {EncodingPolicy::kAuto, EncodingPolicy::kLinear, EncodingPolicy::kSquare}) {
      Report report;
      PackOptions po = pack_options(source->setting.bake);
      po.encoding = e;
      const std::vector<uint8_t> pack =
          build_pack(scene, ref_layout.layout, source->maps, po, report);
      RuntimeRow cpu;
      cpu.encoding = encoding_name(e);
      cpu.target = "cpu-float32";
      cpu.atlas_bytes = atlas_bytes_of(pack);
      cpu.target_bytes = uint64_t(w) * uint64_t(h) * 3 * 4;
      cpu.m = compare(recompose_authored(pack), float_ref, fstats);
      cpu.recompose_ms = cpu_rebuild_ms(pack, 5);
      runtime_rows.push_back(cpu);
      if (o.gles) {
        PackView view;
        Error error;
        if (PackView::open(pack.data(), pack.size(), &view, &error) != Status::kOk) {
          throw CookError(std::string("accuracy: the cooked pack does not load: ") + error.message);
        }
        std::vector<float> rgb;
        recompose_gles(view, {}, &rgb);
        if (rgb.size() != float_ref.data.size()) {
          throw CookError("accuracy: the GLES backend returned a map of the wrong size");
        }
        RuntimeRow gpu = cpu;
        gpu.target = "gles-rgba16f";
        gpu.recompose_ms = -1.0;
        gpu.target_bytes = uint64_t(w) * uint64_t(h) * 8 * 2;
        gpu.m = compare(rgb, float_ref, fstats);
        runtime_rows.push_back(gpu);
      }
      progress.advance();
    }
    progress.end();
    runtime_notes = {
        "lightpatch accuracy " + o.scene_path + ": the runtime",
        "bake: " + source->setting.name + " at " + std::to_string(w) + "x" + std::to_string(h) +
            "; reference: the authored state composed in float from the same bake's "
            "unquantized maps (B - static shadows + sum f_l (C_l - S_ol + pair corrections))",
        "errors as in the main CSV (valid texels; texels that matter: 1% of the 99th percentile "
        "of the float composition's luminance)",
        "recompose_ms: median of 5 full rebuilds of the authored state on the CPU reference; "
        "the GLES time is not measured here (lightpatch bench PACK measures it)",
        "atlas_bytes: the pack's RGBA8 atlases; target_bytes: cpu-float32 = the RGB float map, "
        "gles-rgba16f = the light map and the intermediate texture, RGBA16F each",
    };
  }

  std::vector<std::string> notes = {
      "lightpatch accuracy " + o.scene_path + (o.quick ? " (--quick)" : ""),
      o.path_traced
          ? "reference: bake-state --integrator reference of the authored state (path tracing, " +
                ref_info.value("samples", nlohmann::json(0)).dump() + " samples per texel (" +
                ref_what.substr(std::string("path tracing, ").size()) + ")" + "; " +
                ref_info.value("rays", nlohmann::json(0)).dump() + " rays in " +
                number(ref_info.value("seconds", 0.0), "%.1f") + " s, seed " +
                std::to_string(pt_options.seed) + "), " + std::to_string(reference.width) + "x" +
                std::to_string(reference.height) + (cached ? ", from the cache" : "") +
                "; paths whose first ray met the back of a static surface started inside solid "
                "geometry and are not samples (a texel is the mean of its others): " +
                number(100.0 * ref_info.value("inside_path_fraction", 0.0), "%.3f") +
                " % of the paths; " + ref_info.value("inside_texels", nlohmann::json(0)).dump() +
                " valid texels had none (never seen: 0)"
          : "reference: bake_state of the authored state, production x" + std::to_string(factor) +
                " (" + std::to_string(ref_options.gather_rays) + " gather rays, " +
                std::to_string(ref_options.area_samples) + " area samples, seed " +
                std::to_string(ref_options.seed) + "), " + std::to_string(reference.width) + "x" +
                std::to_string(reference.height) + (cached ? ", from the cache" : ""),
      o.path_traced
          ? "reference noise: relative RMSE " + number(100.0 * noise_rmse, "%.3f") +
                " % (sqrt(sum se^2 / sum r^2) over valid texels, se its per-texel standard "
                "error), mean relative standard error " +
                number(100.0 * noise_mean_rel, "%.3f") +
                " % over texels that matter; rel_rmse_excess = sqrt(rel_rmse^2 - noise^2) is a "
                "row's own error; within_noise = 1 where that is below the noise (such rows "
                "are not told apart: errors below sqrt(2) x noise are equal for the Pareto "
                "front)"
          : "reference noise: not estimated (--reference-integrator cook); rel_rmse_excess = "
            "rel_rmse, within_noise = 0",
      "each row: bake_maps + finalize + build_pack (cook_s, rays), then the authored state "
      "recomposed from the pack on the CPU reference and compared with the reference over valid "
      "texels",
      "rel_rmse = sqrt(sum (x-r)^2 / sum r^2) over RGB of valid texels (here and below: "
      "texels of meshes that cast no shadows, a light's own flame or bulb, left out)",
      "max_rel_error = max over texels that matter of max_c |x_c-r_c| / max_c r_c; texels that "
      "matter: reference luminance >= 1% of its 99th percentile; max_error_x, max_error_y: that "
      "texel in the reference's page (column, row from the top)",
      "max_rel_error_beyond_noise: the same with each |x_c-r_c| less 3 standard errors of the "
      "reference there (not below 0): what the reference's noise cannot explain (= max_rel_error "
      "without a path-traced reference)",
      "psnr_db = 10 log10(peak^2 / MSE), peak = 99th percentile of the reference's max channel",
      "bias = sum x / sum r - 1 over RGB of valid texels (the sign rel_rmse hides: < 0, the row is "
      "darker); median_ratio = the median over texels that matter of (x_r+x_g+x_b) / "
      "(r_r+r_g+r_b) (1: the typical texel is right)",
      "knob rows vary one knob from the preview preset; rows that differ only in encoding reuse "
      "the bake (cook_s = its bake time + their own pack time)",
      "texel density rows: a coarser page, resampled to the reference's texels by nearest valid "
      "texel of the same mesh (world position, normal within 60 deg); a renderer's bilinear "
      "filter would show a little less error",
      "import, layout and tracer setup (shared by all rows) are not in cook_s",
  };
  notes.insert(notes.end(), skipped.begin(), skipped.end());
  const std::string csv = csv_text(rows, notes);

  PlotSpec plot;
  plot.title = "lightpatch accuracy: " + std::filesystem::path(o.scene_path).filename().string() +
               " (" + std::to_string(o.lightmap_size) + "x" + std::to_string(o.lightmap_size) +
               " light map)";
  plot.x_label = "cook time (s)";
  plot.y_label = "relative RMSE vs reference (%)";
  for (const Row& r : rows) {
    auto it = std::find(plot.series.begin(), plot.series.end(), r.setting.knob);
    if (it == plot.series.end()) it = plot.series.insert(plot.series.end(), r.setting.knob);
    PlotPoint p;
    p.x = r.cook_s;
    p.y = 100.0 * r.m.rel_rmse;
    p.series = int(it - plot.series.begin());
    p.front = r.pareto;
    if (r.setting.label) p.label = quality_name(r.setting.bake.quality);
    plot.points.push_back(p);
  }
  const std::vector<uint8_t> png = render_plot_png(plot);
  write_file_atomic(o.csv_path, csv.data(), csv.size());
  write_file_atomic(o.plot_path, png.data(), png.size());
  if (!o.runtime_csv_path.empty()) {
    const std::string text = runtime_csv_text(runtime_rows, runtime_notes);
    write_file_atomic(o.runtime_csv_path, text.data(), text.size());
  }

  if (!o.quiet) {
    std::printf("%-34s %9s %12s %10s %9s %9s %8s %8s %s\n", "setting", "cook_s", "rays",
                "pack_bytes", "rel_rmse", "max_rel", "bias", "psnr_db", "pareto");
    for (const Row& r : rows) {
      std::printf("%-34s %9.3f %12llu %10llu %8.3f%% %8.2f%% %+7.2f%% %8.2f %s%s\n",
                  r.setting.name.c_str(), r.cook_s, static_cast<unsigned long long>(r.rays),
                  static_cast<unsigned long long>(r.pack_bytes), 100.0 * r.m.rel_rmse,
                  100.0 * r.m.max_rel_error, 100.0 * r.m.bias, r.m.psnr_db, r.pareto ? "*" : "",
                  r.m.within_noise ? " (within the reference's noise)" : "");
    }
    if (!runtime_rows.empty()) {
      std::printf("\n%-8s %-14s %12s %12s %12s %9s %9s %8s\n", "encoding", "target", "recompose_ms",
                  "atlas_bytes", "target_bytes", "rel_rmse", "max_rel", "psnr_db");
      for (const RuntimeRow& r : runtime_rows) {
        std::printf("%-8s %-14s %12s %12llu %12llu %8.4f%% %8.3f%% %8.2f\n", r.encoding.c_str(),
                    r.target.c_str(),
                    r.recompose_ms >= 0.0 ? number(r.recompose_ms, "%.3f").c_str() : "-",
                    static_cast<unsigned long long>(r.atlas_bytes),
                    static_cast<unsigned long long>(r.target_bytes), 100.0 * r.m.rel_rmse,
                    100.0 * r.m.max_rel_error, r.m.psnr_db);
      }
    }
  }
  progress.message("wrote " + o.csv_path + " and " + o.plot_path + " (" +
                   std::to_string(rows.size()) + " settings) in " + number(since(t_all), "%.1f") +
                   " s");
  return 0;
}

}  // namespace lightpatch::tool
