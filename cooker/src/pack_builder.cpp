#include "lightpatch/cooker/pack_builder.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <set>
#include <tuple>
#include <utility>

#include "atlas_packer.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/probes.h"
#include "lightpatch/group_rules.h"
#include "lightpatch/moving_lights.h"
#include "lightpatch/pack_format.h"
#include "lightpatch/pack_view.h"
#include "map_split.h"
#include "pack_writer.h"
#include "panes/pane_cluster.h"
#include "patch_extract.h"
#include "quantize.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

using namespace pack;
static_assert(std::endian::native == std::endian::little,
              "the pack writer assumes a little-endian host");

namespace {

struct MapJob {
  const FloatImage* map = nullptr;
  const FloatImage* indirect = nullptr;  // its bounce part's block image, or null
  const FloatImage* direct = nullptr;    // its direct part (ShadowMap::direct), or null
  // A pane's map and block image in tiles (PaneMap), made dense while its job is cut, in place
  // of `map` and `indirect`.
  const TiledImage* tiled_map = nullptr;
  const TiledImage* tiled_indirect = nullptr;
  bool has_indirect() const {
    return (indirect && !indirect->data.empty()) || (tiled_indirect && !tiled_indirect->empty());
  }
  // Its threshold is half a step of its group's own peak, finer than the authored exposure's (a
  // light far dimmer than the others, which recomposes alone to 8 bits): its bounce light keeps
  // the level tolerance (PackOptions::bounce_tolerance is about the authored image).
  bool own_peak = false;
  SourcePatch prototype;
  float threshold = 0.0f;
  std::string what;
  // Stored on the indirect map alone where the pack has one (a moving lights' pane: its bounce
  // light at the indirect level, pack_format.h), with no light-map part.
  bool indirect_only = false;
};

// A map's bounce part (PackOptions::bounce_tolerance) is significant from this fraction of the
// map's threshold. At 1 each part dropped the dim tail that the whole map carries beside the
// other part's light: every map of the small inn in parts (bounce tolerance 4, uncapped), its fire
// alone against `bake-state`, signed bias -1.94 % (-1.23 % whole); at 0.5, -0.68 %; at 0.25,
// -0.25 % for 4 % more bytes.
constexpr float kBounceThresholdFraction = 0.5f;

// A map's bounce tolerance at a texel is also capped at this share of the map's own light there
// (in output steps, never below the level tolerance). Capped only at what all maps show, each of
// several lights could lose up to the whole tolerance at one texel, and their errors add up: the
// small inn (preview) had 120 texels that matter with under half their light against
// `bake-state` and 1,054 off by over 25 % (two or three lights each losing up to 3 steps of a
// texel that shows 6-12); at 0.5, 0 and 160 for 7 % more atlas bytes; at 0.25, 0 and 29 for 11 %
// (README, "8-bit codes that keep every texel, and each map's share of the bounce tolerance").
constexpr float kBounceShare = 0.5f;

// What a light-map patch costs where the pack builder weighs cuts and parts: its atlas bytes, its
// record and kPatchDrawBytes for the quad it draws.
uint64_t patch_bytes(const SourcePatch& p) {
  return uint64_t(p.stored_w()) * uint64_t(p.stored_h()) * uint64_t(p.channels) +
         sizeof(pack::PatchRecord) + kPatchDrawBytes;
}

// The destination texels a patch draws (budgets count these).
uint64_t dest_texels(const SourcePatch& p) {
  return uint64_t(p.dest.w) * uint64_t(p.dest.h);
}

// The atlas channel-texels patches take.
uint64_t channel_texels(const std::vector<SourcePatch>& v) {
  uint64_t n = 0;
  for (const SourcePatch& p : v)
    n += uint64_t(p.stored_w()) * uint64_t(p.stored_h()) * uint64_t(p.channels);
  return n;
}

float max3(const glm::vec3& v) {
  return std::max({v.x, v.y, v.z});
}

// A map's significance threshold: half an 8-bit step at the authored exposure (`at_authored`), or
// half a step of the map's own peak where that is finer, so that a light far dimmer than the
// others, or static light far dimmer than the semi-dynamic lights, still recomposes alone to 8
// bits when the bright ones are off (the baker's rule, bake.cpp).
float significance_of_peak(float peak, float at_authored) {
  return peak > 0.0f ? std::min(at_authored, 0.5f * peak / 255.0f) : at_authored;
}

float significance(const FloatImage& map, float at_authored) {
  float peak = 0.0f;
  for (float v : map.data) {
    if (std::isfinite(v)) peak = std::max(peak, v);
  }
  return significance_of_peak(peak, at_authored);
}

// A patch as stored: source patch `source` whole (destination -1), or its channel `destination`
// alone as a 1-channel patch that draws into that map channel only.
struct StoredPatch {
  size_t source = 0;
  int destination = -1;
};

std::vector<StoredPatch> whole_patches(const std::vector<SourcePatch>& patches) {
  std::vector<StoredPatch> out(patches.size());
  for (size_t i = 0; i < patches.size(); ++i) out[i].source = i;
  return out;
}

// A 3-channel patch takes channels 0-2 of its atlas texels; only 1-channel patches can use
// channel 3, so a pack of mostly tinted patches leaves up to a quarter of its atlases empty (the
// inns at preview, bounce light tinted by the albedos: 10 % and 16 % of the atlas bytes with the
// base patches alone split). Tinted patches are stored as three 1-channel patches (one map
// channel each), largest first, while the 1-channel channel-texels still fit the alpha plane
// under the 3-channel patches left:
//  1. those of the groups without a light (B and the static shadows: drawn on a full rebuild, and
//     the static shadows on their object's toggle, never on a light change);
//  2. with `contributions_too`, then those of the light contributions C_l (drawn on a rebuild and
//     on their light's change, never on an object's toggle), always from the light whose change
//     draws the fewest texels so far, and never so that a light's change draws more texels than
//     the costliest light change of the unsplit patches: the slowest change keeps its latency
//     (one light: nothing split).
// Each split texel costs two more texels drawn when its group is drawn; the decoded values are
// the same bytes, so the recomposition is too.
std::vector<StoredPatch> split_for_alpha(const std::vector<SourcePatch>& patches,
                                         bool contributions_too) {
  // Texels drawn (destination) and atlas texels (fewer for a magnified patch).
  auto texels = [&](size_t i) { return int64_t(patches[i].dest.w) * patches[i].dest.h; };
  auto stored = [&](size_t i) { return int64_t(patches[i].stored_w()) * patches[i].stored_h(); };
  auto largest_first = [&](std::vector<size_t>& v) {
    std::stable_sort(v.begin(), v.end(), [&](size_t a, size_t b) { return stored(a) > stored(b); });
  };
  int64_t rgb = 0, grey = 0;  // atlas texels of 3-channel patches, channel-texels of 1-channel
  std::vector<size_t> unlit;  // tinted patches of groups without a light
  std::map<int, std::vector<size_t>> contributions;  // tinted C_l patches by light
  std::map<int, int64_t> change;                     // texels each light's change draws
  for (size_t i = 0; i < patches.size(); ++i) {
    const SourcePatch& p = patches[i];
    // 2-channel patches pair up (channels 0-1 and 2-3 of one place): they leave the alpha plane
    // under 3-channel patches to the 1-channel ones.
    if (p.channels != 2) (p.channels == 3 ? rgb : grey) += stored(i);
    if (group_has_light(p.kind)) change[p.light] += texels(i);
    if (p.channels != 3) continue;
    if (!group_has_light(p.kind))
      unlit.push_back(i);
    else if (p.kind == kGroupContribution && contributions_too)
      contributions[p.light].push_back(i);
  }
  std::vector<uint8_t> split(patches.size(), 0);
  auto try_split = [&](size_t i) {
    const int64_t t = stored(i);
    if (grey + 3 * t > rgb - t) return false;  // a smaller one may still fit
    grey += 3 * t;
    rgb -= t;
    split[i] = 1;
    return true;
  };
  largest_first(unlit);
  for (size_t i : unlit) try_split(i);
  int64_t costliest = 0;
  for (const auto& [light, texels_drawn] : change) costliest = std::max(costliest, texels_drawn);
  // (texels the light's change draws, light): the cheapest light offers its next patch.
  std::set<std::pair<int64_t, int>> queue;
  std::map<int, size_t> next;
  for (auto& [light, v] : contributions) {
    largest_first(v);
    queue.insert({change[light], light});
  }
  while (!queue.empty()) {
    auto [cost, light] = *queue.begin();
    queue.erase(queue.begin());
    const std::vector<size_t>& v = contributions[light];
    size_t& k = next[light];
    const size_t i = v[k++];
    if (cost + 2 * texels(i) <= costliest && try_split(i)) cost += 2 * texels(i);
    if (k < v.size()) queue.insert({cost, light});
  }
  std::vector<StoredPatch> out;
  for (size_t i = 0; i < patches.size(); ++i) {
    if (!split[i]) {
      out.push_back({i, -1});
      continue;
    }
    for (int c = 0; c < 3; ++c) out.push_back({i, c});
  }
  return out;
}

// What the atlas packer places for the stored patches (a channel apart takes one channel).
std::vector<PackItem> pack_items(const std::vector<SourcePatch>& patches,
                                 const std::vector<StoredPatch>& stored) {
  std::vector<PackItem> items(stored.size());
  for (size_t i = 0; i < stored.size(); ++i) {
    const SourcePatch& p = patches[stored[i].source];
    items[i] = PackItem{p.stored_w(), p.stored_h(), stored[i].destination >= 0 ? 1 : p.channels};
  }
  return items;
}

int64_t atlas_texels(const AtlasLayout& layout) {
  int64_t t = 0;
  for (const AtlasSize& a : layout.atlases) t += int64_t(a.width) * a.height;
  return t;
}

nlohmann::json error_json(const EncodingError& e) {
  nlohmann::json j;
  j["relative_rmse"] = e.sum_sq_value > 0.0 ? std::sqrt(e.sum_sq_error / e.sum_sq_value) : 0.0;
  j["max_error"] = e.max_error;
  j["samples"] = e.samples;
  return j;
}

void check_map(int width, int height, int channels, const Layout& layout, int channels_a,
               int channels_b, const std::string& what) {
  if (width != layout.width || height != layout.height ||
      (channels != channels_a && channels != channels_b)) {
    throw CookError(what + ": " + std::to_string(width) + "x" + std::to_string(height) + "x" +
                    std::to_string(channels) + " does not match the " +
                    std::to_string(layout.width) + "x" + std::to_string(layout.height) +
                    " light map");
  }
}
void check_map(const FloatImage& m, const Layout& layout, int channels_a, int channels_b,
               const std::string& what) {
  check_map(m.width, m.height, m.channels, layout, channels_a, channels_b, what);
  if (m.data.size() != size_t(m.width) * m.height * m.channels)
    throw CookError(what + ": its data does not match its size");
}

// The probe bake as pack records (pack_format.h, "Light probes"): names into the strings, sets
// sorted by owner with kNone16 for "none", their entries concatenated in that order.
// An entry whose irradiance stays below `threshold` (the significance of its set's maps) in every
// direction: |Y_k| <= 0.631 for every basis function, so this bounds it.
bool negligible(const ProbeEntry& e, float threshold) {
  float bound[3] = {0, 0, 0};
  for (uint32_t k = 0; k < kProbeShCount; ++k)
    for (int ch = 0; ch < 3; ++ch) bound[ch] += 0.631f * std::abs(e.sh[k * 3 + ch]);
  return std::max({bound[0], bound[1], bound[2]}) < threshold;
}

// `light_threshold` holds the semi-dynamic lights' significance, `pane_threshold` the panes'
// (pack lights first_pane + k); the moving lights between them have no sets.
void add_probes(const ProbeBake& bake, size_t light_count, size_t object_count,
                const std::vector<float>& light_threshold, size_t first_pane,
                const std::vector<float>& pane_threshold, float base_threshold, PackContents& c) {
  if (bake.probes.empty()) return;
  if (bake.probes.size() > kMaxProbes) {
    throw CookError(std::to_string(bake.probes.size()) + " light probes, over the format's " +
                    std::to_string(kMaxProbes));
  }
  for (const ProbeBake::Probe& p : bake.probes) {
    ProbeRecord r{};
    for (int a = 0; a < 3; ++a) r.position[a] = p.position[a];
    for (int k = 0; k < 6; ++k) r.reach[k] = p.reach[k];
    if (!p.name.empty()) c.add_name(p.name, &r.name_offset, &r.name_length);
    c.probes.push_back(r);
  }
  if (bake.has_grid) {
    uint64_t points = 1;
    for (int a = 0; a < 3; ++a) {
      if (bake.grid_size[a] < 1) throw CookError("probe grid: an empty axis");
      points *= uint64_t(bake.grid_size[a]);
      if (points > kMaxProbeGridPoints) throw CookError("probe grid: too many points");
    }
    if (bake.grid_index.size() != points) throw CookError("probe grid: index count");
    c.has_probe_grid = true;
    for (int a = 0; a < 3; ++a) {
      c.probe_grid.origin[a] = bake.grid_origin[a];
      c.probe_grid.size[a] = uint32_t(bake.grid_size[a]);
    }
    c.probe_grid.spacing = bake.grid_spacing;
    c.probe_grid_indices = bake.grid_index;
  }
  auto owner = [&](int v, size_t count, const char* what) -> uint16_t {
    if (v < 0) return kNone16;
    if (size_t(v) >= count) throw CookError(std::string("probe set: ") + what + " out of range");
    return uint16_t(v);
  };
  std::vector<std::pair<ProbeSetRecord, const ProbeBake::Set*>> sets;
  for (const ProbeBake::Set& s : bake.sets) {
    if (s.entries.empty()) continue;
    ProbeSetRecord r{};
    r.kind = s.kind;
    r.light = owner(s.light, light_count, "light");
    r.object_a = owner(s.object, object_count, "object");
    r.object_b = kNone16;
    const bool pane = s.light >= 0 && size_t(s.light) >= first_pane;
    if (s.light >= 0 && size_t(s.light) >= light_threshold.size() &&
        (!pane || s.kind != kGroupContribution || s.object >= 0)) {
      throw CookError("probe set of light " + std::to_string(s.light) +
                      ": a moving light has no probe sets, a pane only its contribution");
    }
    sets.emplace_back(r, &s);
  }
  auto key = [](const ProbeSetRecord& r) {
    return std::tie(r.kind, r.light, r.object_a, r.object_b);
  };
  std::sort(sets.begin(), sets.end(),
            [&](const auto& a, const auto& b) { return key(a.first) < key(b.first); });
  for (size_t i = 0; i < sets.size(); ++i) {
    ProbeSetRecord r = sets[i].first;
    if (i > 0 && key(sets[i - 1].first) == key(r)) throw CookError("two probe sets of one owner");
    r.first_entry = uint32_t(c.probe_entries.size());
    // The patches' rule: what stays below the set's significance is not stored.
    const float threshold = r.light == kNone16 ? base_threshold
                            : r.light < light_threshold.size()
                                ? light_threshold[r.light]
                                : pane_threshold[r.light - first_pane];
    for (const ProbeEntry& e : sets[i].second->entries)
      if (!negligible(e, threshold)) c.probe_entries.push_back(e);
    if (c.probe_entries.size() > 0xFFFFFFFFu) throw CookError("too many probe entries");
    r.entry_count = uint32_t(c.probe_entries.size() - r.first_entry);
    if (r.entry_count > 0) c.probe_sets.push_back(r);
  }
}

// What the probes cost in the pack (the four sections' bytes, without their alignment padding).
nlohmann::json probe_report(const PackContents& c) {
  const uint64_t grid_bytes =
      c.has_probe_grid ? sizeof(ProbeGridRecord) + c.probe_grid_indices.size() * 4 : 0;
  const uint64_t bytes = c.probes.size() * sizeof(ProbeRecord) + grid_bytes +
                         c.probe_sets.size() * sizeof(ProbeSetRecord) +
                         c.probe_entries.size() * sizeof(ProbeEntry);
  uint64_t named = 0, grid_points_with_probe = 0;
  for (const ProbeRecord& p : c.probes) named += p.name_length > 0 ? 1 : 0;
  for (uint32_t i : c.probe_grid_indices) grid_points_with_probe += i != kNone32 ? 1 : 0;
  nlohmann::json j;
  j["count"] = c.probes.size();
  j["named"] = named;
  j["grid"] =
      c.has_probe_grid
          ? nlohmann::json{{"size",
                            {c.probe_grid.size[0], c.probe_grid.size[1], c.probe_grid.size[2]}},
                           {"spacing", c.probe_grid.spacing},
                           {"points_with_probe", grid_points_with_probe}}
          : nlohmann::json(nullptr);
  j["sets"] = c.probe_sets.size();
  j["entries"] = c.probe_entries.size();
  j["bytes"] = bytes;
  return j;
}

// The light map's surfaces for choosing between a map's two cuts place by place: each chart's
// rectangle (a region's rectangle where it lists none) a unit, and per texel the unit it lies in
// (-1: none). Units whose rectangles overlap are joined from the start.
struct ChartUnits {
  int width = 0, height = 0;
  std::vector<int> unit_of;  // per light-map texel
  std::vector<int> parent;   // union-find over the units
};

int find_unit(std::vector<int>& parent, int u) {
  while (parent[size_t(u)] != u) {
    parent[size_t(u)] = parent[size_t(parent[size_t(u)])];
    u = parent[size_t(u)];
  }
  return u;
}

void join_units(std::vector<int>& parent, int a, int b) {
  a = find_unit(parent, a);
  b = find_unit(parent, b);
  if (a != b) parent[size_t(std::max(a, b))] = std::min(a, b);
}

ChartUnits chart_units(const Layout& layout) {
  ChartUnits u;
  u.width = layout.width;
  u.height = layout.height;
  u.unit_of.assign(size_t(u.width) * size_t(u.height), -1);
  for (const Region& region : layout.regions) {
    std::vector<Rect> rects = region.charts;
    if (rects.empty()) rects.push_back(region.rect);
    for (const Rect& r : rects) {
      const int id = int(u.parent.size());
      u.parent.push_back(id);
      for (int y = std::max(0, r.y); y < std::min(u.height, r.y + r.h); ++y) {
        for (int x = std::max(0, r.x); x < std::min(u.width, r.x + r.w); ++x) {
          int& at = u.unit_of[size_t(y) * size_t(u.width) + size_t(x)];
          if (at >= 0) join_units(u.parent, at, id);
          at = id;
        }
      }
    }
  }
  return u;
}

// Joins the units a patch's rectangle touches; returns one of them (`none` if it touches none).
int join_patch_units(const ChartUnits& u, std::vector<int>& parent, const Rect& d, int none) {
  int first = -1;
  for (int y = std::max(0, d.y); y < std::min(u.height, d.y + d.h); ++y) {
    for (int x = std::max(0, d.x); x < std::min(u.width, d.x + d.w); ++x) {
      const int at = u.unit_of[size_t(y) * size_t(u.width) + size_t(x)];
      if (at < 0) continue;
      if (first < 0)
        first = at;
      else if (at != first)
        join_units(parent, first, at);
    }
  }
  return first < 0 ? none : first;
}

// A set of charts' two ways to store a map there (ChartUnits): whole, or as its direct and bounce
// parts; bytes as patch_bytes() counts them, destination texels drawn.
struct ChartSetChoice {
  uint64_t whole_bytes = 0, parts_bytes = 0, whole_texels = 0, parts_texels = 0;
  bool used = false, in_parts = false;
  double whole_cost() const { return double(whole_bytes) + kDrawTexelBytes * double(whole_texels); }
  double parts_cost() const { return double(parts_bytes) + kDrawTexelBytes * double(parts_texels); }
};

}  // namespace

std::vector<uint8_t> build_pack(const Scene& scene, const Layout& layout, const BakedMaps& maps,
                                const PackOptions& options, Report& report,
                                const ProbeBake* probes) {
  if (layout.width <= 0 || layout.height <= 0 || layout.width > int(kMaxLightmapSize) ||
      layout.height > int(kMaxLightmapSize)) {
    throw CookError("light-map size " + std::to_string(layout.width) + "x" +
                    std::to_string(layout.height) + " out of range");
  }
  if (options.max_atlas_size < kMinAtlasSize || options.max_atlas_size > int(kMaxAtlasSize) ||
      options.max_atlas_size % int(kAtlasAlign) != 0) {
    throw CookError("maximum atlas size " + std::to_string(options.max_atlas_size) +
                    " must be a multiple of " + std::to_string(kAtlasAlign) + " in " +
                    std::to_string(kMinAtlasSize) + ".." + std::to_string(kMaxAtlasSize));
  }
  if (!std::isfinite(maps.output_step) || maps.output_step < 0.0f) {
    throw CookError("output step must be finite and >= 0");
  }
  if (maps.lights.size() != maps.contribution.size()) {
    throw CookError("baked maps: " + std::to_string(maps.lights.size()) + " lights but " +
                    std::to_string(maps.contribution.size()) + " contribution maps");
  }
  const size_t pack_lights = maps.lights.size() + maps.moving_lights.size() + maps.panes.size();
  if (pack_lights >= kNone16 || scene.objects.size() >= kNone16) {
    throw CookError("too many semi-dynamic lights, moving lights and panes (" +
                    std::to_string(pack_lights) + ") or objects for the pack format (max 65534)");
  }
  if (maps.panes.size() > kMaxPanes) {
    throw CookError(std::to_string(maps.panes.size()) + " panes, over the pack's limit of " +
                    std::to_string(kMaxPanes));
  }
  for (int li : maps.moving_lights) {
    if (li < 0 || size_t(li) >= scene.lights.size() || !scene.lights[size_t(li)].moving ||
        scene.lights[size_t(li)].type == LightType::kDirectional) {
      throw CookError("baked maps: moving light " + std::to_string(li) +
                      " is not a moving point or spot light of the scene");
    }
  }
  if (!maps.panes.empty() && maps.moving_lights.empty())
    throw CookError("baked maps: panes without a moving light");
  check_map(maps.base, layout, 3, 3, "base map");

  // Authored factor of each light, as the baker's significance rule has it (maps.h).
  float s_max = 0.0f;
  for (const Light& l : scene.lights) s_max = std::max(s_max, max3(l.color) * l.intensity);
  std::vector<float> authored(maps.lights.size());
  for (size_t i = 0; i < maps.lights.size(); ++i) {
    const int li = maps.lights[i];
    if (li < 0 || size_t(li) >= scene.lights.size()) {
      throw CookError("baked maps: light " + std::to_string(i) + " refers to scene light " +
                      std::to_string(li) + " which does not exist");
    }
    const Light& l = scene.lights[size_t(li)];
    float a = std::max(max3(l.color) * l.intensity, 1e-2f * s_max);
    if (!(a > 0.0f) || !std::isfinite(a)) a = 1.0f;
    authored[i] = a;
    check_map(maps.contribution[i], layout, 1, 3, "contribution map of light '" + l.name + "'");
  }

  const float half_step = 0.5f * maps.output_step;
  // Significance of each light's maps (intensity 1, at its authored factor) and of the base map
  // with the static shadows (absolute): bake.cpp's rule, see significance().
  std::vector<float> light_threshold(maps.lights.size());
  for (size_t i = 0; i < maps.lights.size(); ++i)
    light_threshold[i] = significance(maps.contribution[i], half_step / authored[i]);
  const float base_threshold = significance(maps.base, half_step);
  // Bounce light's tolerance at each texel, as a factor on the level tolerance
  // (PackOptions::bounce_tolerance): at most the light the authored image shows there, in output
  // steps (the base map and every light's contribution at its authored factor, each texel's
  // brightest channel), at least the level tolerance. Only where some map has a direct part.
  bool any_direct = !maps.base_direct.data.empty();
  for (const FloatImage& d : maps.contribution_direct) any_direct |= !d.data.empty();
  for (const ShadowMap& m : maps.shadows) any_direct |= !m.direct.data.empty();
  for (const PairCorrectionMap& m : maps.pair_corrections) any_direct |= !m.direct.data.empty();
  for (const StaticShadowMap& m : maps.static_shadows) any_direct |= !m.direct.data.empty();
  FloatImage bounce_scale;
  if (any_direct) {
    FloatImage shown(maps.base.width, maps.base.height, 1);
    auto add = [&](const FloatImage& m, float a) {
      if (m.width != shown.width || m.height != shown.height || !(maps.output_step > 0.0f)) return;
      const size_t ch = size_t(m.channels);
      for (size_t t = 0; t < shown.data.size(); ++t) {
        float v = 0.0f;
        for (size_t c = 0; c < ch; ++c) v = std::max(v, m.data[t * ch + c]);
        shown.data[t] += a * v / maps.output_step;
      }
    };
    add(maps.base, 1.0f);
    for (size_t i = 0; i < maps.lights.size(); ++i) add(maps.contribution[i], authored[i]);
    for (float& v : shown.data)
      v = std::clamp(v, options.level_tolerance, options.bounce_tolerance) /
          options.level_tolerance;
    bounce_scale = std::move(shown);
  }
  std::vector<uint8_t> light_own_peak(maps.lights.size());
  for (size_t i = 0; i < maps.lights.size(); ++i)
    light_own_peak[i] = light_threshold[i] < half_step / authored[i] ? 1 : 0;
  const bool base_own_peak = base_threshold < half_step;
  // Patches are cut into tiles so that a light reaching a few corners of a large region pays for
  // those corners only; a tile also never exceeds an atlas.
  const int max_dim = std::min(options.max_atlas_size, std::max(options.tile_size, 4));
  std::vector<MapJob> jobs;
  {
    MapJob j;
    j.map = &maps.base;
    j.indirect = &maps.base_indirect;
    j.direct = &maps.base_direct;
    j.own_peak = base_own_peak;
    j.prototype.kind = kGroupBase;
    j.threshold = base_threshold;
    j.what = "base map";
    jobs.push_back(j);
  }
  for (size_t i = 0; i < maps.lights.size(); ++i) {
    MapJob j;
    j.map = &maps.contribution[i];
    if (i < maps.contribution_indirect.size()) j.indirect = &maps.contribution_indirect[i];
    if (i < maps.contribution_direct.size()) j.direct = &maps.contribution_direct[i];
    j.own_peak = light_own_peak[i] != 0;
    j.prototype.kind = kGroupContribution;
    j.prototype.light = int(i);
    j.prototype.weight = authored[i];
    j.threshold = light_threshold[i];
    j.what = "contribution map of light '" + scene.lights[size_t(maps.lights[i])].name + "'";
    jobs.push_back(j);
  }
  // The panes, after the lights and the moving lights in the light table.
  const float pane_threshold_at = pane_significance(scene, half_step);
  const float strongest_moving = strongest_moving_light(scene);
  const size_t first_pane = maps.lights.size() + maps.moving_lights.size();
  std::vector<float> pane_threshold(maps.panes.size());
  for (size_t k = 0; k < maps.panes.size(); ++k) {
    const PaneMap& pm = maps.panes[k];
    const bool blocks_only = pm.map.empty();  // PaneMap: its block image holds it
    pane_threshold[k] =
        significance_of_peak(blocks_only ? pm.peak : pm.map.peak(), pane_threshold_at);
    MapJob j;
    j.tiled_map = blocks_only ? nullptr : &pm.map;
    j.tiled_indirect = &pm.indirect;
    j.indirect_only = true;
    j.prototype.kind = kGroupContribution;
    j.prototype.light = int(first_pane + k);
    j.prototype.weight = strongest_moving;
    j.threshold = pane_threshold[k];
    j.what = "pane " + std::to_string(k) + " of the moving lights";
    if (!blocks_only)
      check_map(pm.map.width(), pm.map.height(), pm.map.channels(), layout, 3, 3, j.what);
    jobs.push_back(j);
  }
  std::vector<const ShadowMap*> shadows;
  for (const ShadowMap& s : maps.shadows) shadows.push_back(&s);
  std::sort(shadows.begin(), shadows.end(), [](const ShadowMap* a, const ShadowMap* b) {
    return std::tie(a->light, a->object) < std::tie(b->light, b->object);
  });
  for (size_t k = 0; k < shadows.size(); ++k) {
    const ShadowMap& s = *shadows[k];
    if (s.light < 0 || size_t(s.light) >= maps.lights.size() || s.object < 0 ||
        size_t(s.object) >= scene.objects.size()) {
      throw CookError("shadow map (light " + std::to_string(s.light) + ", object " +
                      std::to_string(s.object) +
                      ") refers to a light or object that does not exist");
    }
    if (k > 0 && shadows[k - 1]->light == s.light && shadows[k - 1]->object == s.object) {
      throw CookError("two shadow maps for light " + std::to_string(s.light) + ", object " +
                      std::to_string(s.object));
    }
    MapJob j;
    j.map = &s.map;
    j.indirect = &s.indirect;
    j.direct = &s.direct;
    j.own_peak = light_own_peak[size_t(s.light)] != 0;
    j.prototype.kind = kGroupShadow;
    j.prototype.light = s.light;
    j.prototype.object = s.object;
    j.prototype.weight = authored[size_t(s.light)];
    j.threshold = light_threshold[size_t(s.light)];
    j.what = "shadow map of object '" + scene.objects[size_t(s.object)].name + "' for light '" +
             scene.lights[size_t(maps.lights[size_t(s.light)])].name + "'";
    check_map(s.map, layout, 1, 3, j.what);
    jobs.push_back(j);
  }

  std::vector<const PairCorrectionMap*> corrections;
  for (const PairCorrectionMap& p : maps.pair_corrections) corrections.push_back(&p);
  std::sort(corrections.begin(), corrections.end(),
            [](const PairCorrectionMap* a, const PairCorrectionMap* b) {
              return std::tie(a->light, a->object_a, a->object_b) <
                     std::tie(b->light, b->object_a, b->object_b);
            });
  for (size_t k = 0; k < corrections.size(); ++k) {
    const PairCorrectionMap& p = *corrections[k];
    if (p.light < 0 || size_t(p.light) >= maps.lights.size() || p.object_a < 0 ||
        p.object_b <= p.object_a || size_t(p.object_b) >= scene.objects.size()) {
      throw CookError("pair correction (light " + std::to_string(p.light) + ", objects " +
                      std::to_string(p.object_a) + ", " + std::to_string(p.object_b) +
                      ") refers to a light or objects that do not exist, or not in order");
    }
    if (k > 0 && corrections[k - 1]->light == p.light &&
        corrections[k - 1]->object_a == p.object_a && corrections[k - 1]->object_b == p.object_b) {
      throw CookError("two pair corrections for one light and pair");
    }
    MapJob j;
    j.map = &p.map;
    j.indirect = &p.indirect;
    j.direct = &p.direct;
    j.own_peak = light_own_peak[size_t(p.light)] != 0;
    j.prototype.kind = kGroupPairCorrection;
    j.prototype.light = p.light;
    j.prototype.object = p.object_a;
    j.prototype.object_b = p.object_b;
    j.prototype.weight = authored[size_t(p.light)];
    j.threshold = light_threshold[size_t(p.light)];
    j.what = "overlap correction of objects '" + scene.objects[size_t(p.object_a)].name +
             "' and '" + scene.objects[size_t(p.object_b)].name + "' for light '" +
             scene.lights[size_t(maps.lights[size_t(p.light)])].name + "'";
    check_map(p.map, layout, 1, 3, j.what);
    jobs.push_back(j);
  }
  std::vector<const StaticShadowMap*> statics;
  for (const StaticShadowMap& s : maps.static_shadows) statics.push_back(&s);
  std::sort(statics.begin(), statics.end(), [](const StaticShadowMap* a, const StaticShadowMap* b) {
    return a->object < b->object;
  });
  for (size_t k = 0; k < statics.size(); ++k) {
    const StaticShadowMap& s = *statics[k];
    if (s.object < 0 || size_t(s.object) >= scene.objects.size())
      throw CookError("static shadow map of object " + std::to_string(s.object) +
                      ", which does not exist");
    if (k > 0 && statics[k - 1]->object == s.object)
      throw CookError("two static shadow maps for object " + std::to_string(s.object));
    MapJob j;
    j.map = &s.map;
    j.indirect = &s.indirect;
    j.direct = &s.direct;
    j.own_peak = base_own_peak;
    j.prototype.kind = kGroupStaticShadow;
    j.prototype.object = s.object;
    j.threshold = base_threshold;  // absolute irradiance, like the base map
    j.what = "static-light shadow map of object '" + scene.objects[size_t(s.object)].name + "'";
    check_map(s.map, layout, 3, 3, j.what);
    jobs.push_back(j);
  }

  // The indirect map (pack_format.h, "Two target maps"): a map whose bounce part the bake made on
  // s x s blocks (BakedMaps::base_indirect, ...) is stored as that block image (indirect-map
  // patches) plus light-map patches of the rest, the map less the block image's magnification
  // (map_split.h), where that takes fewer atlas texels than light-map patches alone.
  const int scale = layout.align;
  const bool can_split = scale > 1 && layout.width % scale == 0 && layout.height % scale == 0;
  const int coarse_w = can_split ? layout.width / scale : 0;
  const int coarse_h = can_split ? layout.height / scale : 0;
  const std::vector<Region> coarse =
      can_split ? coarse_regions(layout.regions, scale, coarse_w, coarse_h) : std::vector<Region>{};
  for (const MapJob& j : jobs) {
    if (!j.has_indirect() || !can_split) continue;
    const glm::ivec3 size =
        j.tiled_indirect ? glm::ivec3(j.tiled_indirect->width(), j.tiled_indirect->height(),
                                      j.tiled_indirect->channels())
                         : glm::ivec3(j.indirect->width, j.indirect->height, j.indirect->channels);
    if (size != glm::ivec3(coarse_w, coarse_h, 3))
      throw CookError(j.what + ": its indirect block image does not match the layout's " +
                      std::to_string(scale) + "x" + std::to_string(scale) + " blocks");
  }

  // Patches (paper Alg. 4) and their quantization, one map per work item.
  const int threads = worker_count(0);
  std::vector<std::vector<SourcePatch>> per_job(jobs.size());
  std::vector<std::vector<QuantizedPatch>> per_job_q(jobs.size());  // indirect patches, quantized
  struct ColourDecision {
    int three = 0, one = 0;  // 3-channel patches kept, collapsed to 1
    int tinted = 0;          // final pieces collapsed to 1 channel with a tint
    int two_tints = 0;       // final pieces collapsed to 2 channels with a tint each
    float max_spread = 0.0f;
  };
  std::vector<ColourDecision> colour(jobs.size());
  struct SplitDecision {
    bool split = false;
    uint64_t plain = 0, detail = 0, indirect = 0;  // atlas channel-texels
  };
  std::vector<SplitDecision> split(jobs.size());
  std::vector<std::vector<SourcePatch>> split_patches(jobs.size());  // light-map + indirect parts
  std::vector<ColourDecision> split_colour(jobs.size());
  // Direct and bounce parts (PackOptions::bounce_tolerance): what each map with a direct part
  // costs stored whole and as its two parts.
  struct PartsDecision {
    bool considered = false, chosen = false;
    uint64_t whole_bytes = 0, parts_bytes = 0;     // atlas channel-texels, records, quads
    uint64_t whole_texels = 0, parts_texels = 0;   // destination texels drawn
    uint64_t stored_bytes = 0, stored_texels = 0;  // of the patches kept
    int sets_used = 0, sets_in_parts = 0;          // sets of charts no patch leaves; those in parts
    // Until assembled: both cuts, each patch's set of charts, and each set's costs and choice.
    std::vector<SourcePatch> whole, parts;
    std::vector<int> whole_set, parts_set;
    std::vector<ChartSetChoice> sets;
    ColourDecision parts_colour;
  };
  std::vector<PartsDecision> parts(jobs.size());
  const ChartUnits units = chart_units(layout);
  parallel_for(int(jobs.size()), threads, [&](int i) {
    MapJob j = jobs[size_t(i)];
    FloatImage tiled_map, tiled_indirect;  // a pane's, dense while it is cut
    if (j.tiled_map) {
      tiled_map = j.tiled_map->dense();
      j.map = &tiled_map;
    }
    if (j.tiled_indirect) {
      tiled_indirect = j.tiled_indirect->dense();
      j.indirect = &tiled_indirect;
    }
    // How a map is cut: its significance threshold (map units) and each texel's factor on the
    // level tolerance, if any.
    struct CutRule {
      float threshold;
      const FloatImage* scale = nullptr;
    };
    const CutRule whole{j.threshold};
    // A piece's colours (the last step of a cut, below): one tint, else two, else three
    // channels; returns the channels it keeps.
    const bool tint_pieces = !options.keep_colour && options.tint_pieces;
    auto decide_colour = [&](SourcePatch& p) {
      const float tolerance = 0.5f * j.threshold;
      if (collapse_to_tint(p, tolerance)) return 1;
      if (collapse_to_two_tints(p, tolerance)) return 2;
      return 3;
    };
    // Cuts one map into patches; bounce tints C_l and S_ol, a light's colour is a run-time factor,
    // so a patch keeps three channels only where the tint shows above the 8-bit step (B is
    // always 3: authored colours).
    auto cut = [&](const FloatImage& map, const std::vector<Region>& regions, uint8_t target,
                   std::vector<SourcePatch>& out, ColourDecision& d, const CutRule& rule) {
      const size_t first = out.size();
      SourcePatch prototype = j.prototype;
      prototype.target = target;
      extract_patches(map, regions, rule.threshold, max_dim, prototype, j.what, out, rule.scale);
      if (j.prototype.kind != kGroupBase) {
        for (size_t k = first; k < out.size(); ++k) {
          SourcePatch& p = out[k];
          if (p.channels != 3) continue;
          const float spread = colour_spread(p);
          const bool collapsed = !options.keep_colour && collapse_untinted(p, spread);
          (collapsed ? d.one : d.three)++;
          d.max_spread = std::max(d.max_spread, spread * j.prototype.weight);
        }
      }
      // Smooth light-map patches (bounce light, soft falloff) at a coarser level, each chosen by
      // its own error, so that sharp ones (shadow edges, creases) keep level 0. A patch is cut
      // into its charts, and a part that must keep level 0 into tiles, each chosen again, where
      // that takes fewer bytes (atlas bytes, records and kPatchDrawBytes a quad): the smooth part
      // of a tile with one shadow edge still shrinks. Level 0 first within a job, so that the
      // runtime's runs of one program stay long.
      if (target == kTargetLightMap && options.max_patch_level > 0) {
        // The job's threshold is half an output step.
        const float tolerance = 2.0f * options.level_tolerance * j.threshold;
        // What a piece costs once its colour is decided (the last step below): a patch whose
        // light mixes many colours may leave pieces of one or two.
        auto piece_bytes = [&](const SourcePatch& p) -> uint64_t {
          if (!tint_pieces || p.channels != 3) return patch_bytes(p);
          SourcePatch c = p;
          decide_colour(c);
          return patch_bytes(c);
        };
        // Stores p at the coarsest level its error allows; returns that level.
        auto store_coarsest = [&](SourcePatch& p) {
          SourcePatch reduced;
          const int level = coarsest_level(p, options.max_patch_level, tolerance, &reduced);
          if (level > 0) p = std::move(reduced);
          return level;
        };
        // A level-0 patch (its level chosen) cut into tiles of `tile` texels where that takes
        // fewer bytes, each tile at level 0 cut again into tiles half as wide, down to
        // kMinLevelTile: a sharp feature keeps only the small tiles it crosses at level 0.
        std::function<std::vector<SourcePatch>(SourcePatch, int)> tiled = [&](SourcePatch p,
                                                                              int tile) {
          std::vector<SourcePatch> one;
          if (p.level == 0 && (p.dest.w > tile || p.dest.h > tile)) {
            std::vector<SourcePatch> tiles;
            uint64_t split_bytes = 0;
            for (SourcePatch& t : split_patch(p, tile)) {
              store_coarsest(t);
              std::vector<SourcePatch> finer;
              if (tile / 2 >= kMinLevelTile)
                finer = tiled(std::move(t), tile / 2);
              else
                finer.push_back(std::move(t));
              for (SourcePatch& f : finer) {
                split_bytes += piece_bytes(f);
                tiles.push_back(std::move(f));
              }
            }
            // Cut where the tiles cost less counted either way: after their colour decision
            // (tiles of one or two colours where the whole mixes more), or in the channels they
            // have now (the cost the levels' tiles were tuned with: each quad's overhead weighs
            // against three channels' bytes). Either alone took more atlas bytes (README,
            // "Patches of two colours").
            uint64_t plain_bytes = 0;
            for (const SourcePatch& t : tiles) plain_bytes += patch_bytes(t);
            if (!tiles.empty() && (split_bytes < piece_bytes(p) || plain_bytes < patch_bytes(p)))
              return tiles;
          }
          one.push_back(std::move(p));
          return one;
        };
        const int inset_cut = std::max(0, layout.border - 1);
        const size_t end = out.size();
        for (size_t k = first; k < end; ++k) {
          SourcePatch& p = out[k];
          const SourcePatch whole = p;
          store_coarsest(p);
          // Charts side by side in the page are different surfaces: their light breaks at the
          // border, which no magnification follows. Cut along them first, each chart's piece
          // chosen (and tiled) again.
          auto chart_pieces = [&](int inset, uint64_t* total) {
            std::vector<SourcePatch> pieces;
            for (SourcePatch& c : split_by_charts(whole, regions, inset)) {
              store_coarsest(c);
              for (SourcePatch& t : tiled(std::move(c), kLevelTile)) {
                *total += piece_bytes(t);
                pieces.push_back(std::move(t));
              }
            }
            return pieces;
          };
          uint64_t pieces_bytes = 0;
          std::vector<SourcePatch> pieces = chart_pieces(0, &pieces_bytes);
          std::vector<SourcePatch> tiles = tiled(p, kLevelTile);
          uint64_t tiles_bytes = 0;
          for (const SourcePatch& t : tiles) tiles_bytes += piece_bytes(t);
          if (!pieces.empty() && pieces_bytes < tiles_bytes) {
            // Chosen on whole chart rectangles; stored without the border's outer rings, which
            // no mesh reads (choosing on the inset pieces cut 2.5x as many patches on the full
            // inn, whose GLES rebuild then drew at 1.7x the fill-rate floor).
            uint64_t inset_bytes = 0;
            tiles = inset_cut ? chart_pieces(inset_cut, &inset_bytes) : std::move(pieces);
            if (tiles.empty()) tiles = std::move(pieces);
          }
          p = std::move(tiles[0]);
          for (size_t t = 1; t < tiles.size(); ++t) out.push_back(std::move(tiles[t]));
        }
        std::stable_sort(
            out.begin() + std::ptrdiff_t(first), out.end(),
            [](const SourcePatch& a, const SourcePatch& b) { return a.level < b.level; });
      }
      // The pieces still in colour whose light has one colour (one light on one albedo) or two
      // (two lights' colours, a light's direct light and its bounce off one albedo): one channel
      // and a tint, or two channels and a tint each, within a quarter of an output step
      // (collapse_untinted's bound), at bounce-only texels too: their bounce tolerance there
      // darkened dim texels (README).
      if (tint_pieces) {
        for (size_t k = first; k < out.size(); ++k) {
          if (out[k].channels != 3) continue;
          const int channels = decide_colour(out[k]);
          d.tinted += channels == 1 ? 1 : 0;
          d.two_tints += channels == 2 ? 1 : 0;
        }
      }
    };
    std::vector<SourcePatch>& plain = per_job[size_t(i)];
    const bool indirect_part = can_split && j.indirect && !j.indirect->data.empty();
    if (!(j.indirect_only && indirect_part)) {
      if (!j.map)
        throw CookError(j.what + ": held as a block image, but the pack has no indirect map");
      const FloatImage* direct =
          !indirect_part && j.direct && !j.direct->data.empty() ? j.direct : nullptr;
      if (!direct) {
        cut(*j.map, layout.regions, kTargetLightMap, plain, colour[size_t(i)], whole);
      } else {
        check_map(*direct, layout, 1, j.map->channels, j.what + "'s direct part");
        const FloatImage& m = *j.map;
        const size_t n = size_t(m.width) * size_t(m.height);
        const size_t mc = size_t(m.channels), dc = size_t(direct->channels);
        // Bounce light's tolerance (bounce_scale, capped at what the authored image shows: a
        // blur lifts dark corners, where every map's error adds up), on the whole map only where
        // the direct part stays under the level at which cut pieces keep dim light; none for a
        // map whose threshold is its own peak's.
        const FloatImage* loose = j.own_peak ? nullptr : &bounce_scale;
        FloatImage whole_scale, own_scale;
        if (loose) {
          // ... and at kBounceShare of this map's own light there: each map's error is then a
          // share of its own light, not of the light of all maps, whose errors add up.
          own_scale = FloatImage(m.width, m.height, 1);
          for (size_t t = 0; t < n; ++t) {
            float v = 0.0f;
            for (size_t c = 0; c < mc; ++c) v = std::max(v, std::fabs(m.data[t * mc + c]));
            const float own_steps = v / (2.0f * j.threshold);  // the threshold is half a step
            const float cap = std::clamp(kBounceShare * own_steps, options.level_tolerance,
                                         options.bounce_tolerance) /
                              options.level_tolerance;
            own_scale.data[t] = std::min(cap, loose->data[t]);
          }
          loose = &own_scale;
          whole_scale = FloatImage(m.width, m.height, 1);
          const float dim = kCutKeepFraction * j.threshold;
          for (size_t t = 0; t < n; ++t) {
            float d = 0.0f;
            for (size_t c = 0; c < dc; ++c) d = std::max(d, std::fabs(direct->data[t * dc + c]));
            whole_scale.data[t] = d > dim ? 1.0f : loose->data[t];
          }
        }
        // The bounce part: the map less the direct part (a grey part in every channel).
        FloatImage bounce = m;
        for (size_t t = 0; t < n; ++t)
          for (size_t c = 0; c < mc; ++c)
            bounce.data[t * mc + c] -= direct->data[t * dc + (dc == mc ? c : 0)];
        std::vector<SourcePatch> split_into;
        ColourDecision split_colours;
        cut(m, layout.regions, kTargetLightMap, plain, colour[size_t(i)],
            CutRule{j.threshold, loose ? &whole_scale : nullptr});
        cut(*direct, layout.regions, kTargetLightMap, split_into, split_colours, whole);
        // Significant from a fraction of the threshold: each part alone drops its dim tail,
        // which the whole map carried beside the other part's light.
        cut(bounce, layout.regions, kTargetLightMap, split_into, split_colours,
            CutRule{kBounceThresholdFraction * j.threshold, loose});
        PartsDecision& pd = parts[size_t(i)];
        pd.considered = true;
        auto weigh = [](const std::vector<SourcePatch>& v, uint64_t* bytes, uint64_t* texels) {
          for (const SourcePatch& p : v) {
            *bytes += patch_bytes(p);
            *texels += dest_texels(p);
          }
        };
        weigh(plain, &pd.whole_bytes, &pd.whole_texels);
        weigh(split_into, &pd.parts_bytes, &pd.parts_texels);
        // Per set of charts that no patch of either cut leaves, the cut that costs less there:
        // both store the map's light on every chart within the tolerance, so a map may be whole
        // on one surface (direct light and bounce mixed in one colour, a shadow's edge) and in
        // parts on another (bounce light over a lit wall). The direct part's patches and the
        // bounce part's reach the same charts, so their components are joined by each other's.
        std::vector<int> parent = units.parent;
        const int none = int(parent.size());  // patches on no chart: one set of their own
        parent.push_back(none);
        std::vector<int> whole_unit(plain.size()), parts_unit(split_into.size());
        for (size_t k = 0; k < plain.size(); ++k)
          whole_unit[k] = join_patch_units(units, parent, plain[k].dest, none);
        for (size_t k = 0; k < split_into.size(); ++k)
          parts_unit[k] = join_patch_units(units, parent, split_into[k].dest, none);
        pd.sets.assign(parent.size(), ChartSetChoice{});
        for (size_t k = 0; k < plain.size(); ++k) {
          whole_unit[k] = find_unit(parent, whole_unit[k]);
          ChartSetChoice& c = pd.sets[size_t(whole_unit[k])];
          c.whole_bytes += patch_bytes(plain[k]);
          c.whole_texels += dest_texels(plain[k]);
        }
        for (size_t k = 0; k < split_into.size(); ++k) {
          parts_unit[k] = find_unit(parent, parts_unit[k]);
          ChartSetChoice& c = pd.sets[size_t(parts_unit[k])];
          c.parts_bytes += patch_bytes(split_into[k]);
          c.parts_texels += dest_texels(split_into[k]);
        }
        for (ChartSetChoice& c : pd.sets) {
          c.used = c.whole_texels > 0 || c.parts_texels > 0;
          c.in_parts = c.used && (options.always_parts || c.parts_cost() < c.whole_cost());
        }
        // Stored once every map is cut (below), when each light's texels are known.
        pd.whole = std::move(plain);
        pd.parts = std::move(split_into);
        pd.whole_set = std::move(whole_unit);
        pd.parts_set = std::move(parts_unit);
        pd.parts_colour = split_colours;
        plain.clear();
      }
    }
    SplitDecision& sd = split[size_t(i)];
    sd.plain = channel_texels(plain);
    if (indirect_part) {
      std::vector<SourcePatch> indirect;
      // A grey map's bounce part is grey too (one channel where the bounce is untinted).
      cut(*j.indirect, coarse, kTargetIndirectMap, indirect, split_colour[size_t(i)], whole);
      // A pane is bounce light alone, smooth, and has no light-map part to take back what a
      // coarser level blurs: stored at options.pane_level (pack_format.h, "Magnified patches").
      if (j.indirect_only && options.pane_level > 0) {
        for (SourcePatch& p : indirect) reduce_patch(p, options.pane_level);
      }
      std::vector<QuantizedPatch>& indirect_q = per_job_q[size_t(i)];
      indirect_q.resize(indirect.size());
      for (size_t k = 0; k < indirect.size(); ++k)
        indirect_q[k] = quantize_patch(indirect[k], options.encoding);
      std::vector<SourcePatch>& detail = split_patches[size_t(i)];
      if (!j.indirect_only) {
        FloatImage decoded(coarse_w, coarse_h, 3);
        for (size_t k = 0; k < indirect.size(); ++k)
          add_decoded(indirect[k], indirect_q[k], decoded);
        cut(light_map_part(*j.map, decoded, scale), layout.regions, kTargetLightMap, detail,
            split_colour[size_t(i)], whole);
      }
      sd.detail = channel_texels(detail);
      sd.indirect = channel_texels(indirect);
      // A group's light-map patches first, then its indirect ones (pack_format.h).
      for (SourcePatch& p : indirect) detail.push_back(std::move(p));
    }
  });
  // Each map in parts on the sets of charts where that costs less (above), but no light's change
  // drawing more texels than the costliest light change with every map whole: a light's sets
  // that save the most per texel added go first. (The base map and the static shadows are drawn
  // on a full rebuild and object toggles only.) Per set, the full inn's costliest light change
  // rose from 618,996 to 765,450 texels without this bound.
  if (!options.always_parts) {
    std::map<int, uint64_t> light_texels;  // per light: its maps' texels, each stored whole
    for (size_t i = 0; i < jobs.size(); ++i) {
      const int l = jobs[i].prototype.light;
      if (l < 0) continue;
      uint64_t t = parts[i].whole_texels;
      if (!parts[i].considered) {
        t = 0;
        for (const SourcePatch& p : per_job[i]) t += dest_texels(p);
      }
      light_texels[l] += t;
    }
    uint64_t cap = 0;
    for (const auto& [l, t] : light_texels) cap = std::max(cap, t);
    struct Candidate {
      size_t job, set;
      double saving;  // weighed cost, whole less parts (> 0)
      int64_t extra;  // texels drawn, parts less whole
    };
    std::map<int, std::vector<Candidate>> by_light;
    for (size_t i = 0; i < jobs.size(); ++i) {
      if (jobs[i].prototype.light < 0 || !parts[i].considered) continue;
      for (size_t k = 0; k < parts[i].sets.size(); ++k) {
        const ChartSetChoice& c = parts[i].sets[k];
        if (!c.in_parts) continue;
        by_light[jobs[i].prototype.light].push_back(
            Candidate{i, k, c.whole_cost() - c.parts_cost(),
                      int64_t(c.parts_texels) - int64_t(c.whole_texels)});
      }
    }
    for (auto& [l, cands] : by_light) {
      // Sets that draw no more texels first, then by saving per texel added; ties in job order.
      auto rank = [](const Candidate& c) {
        return c.extra <= 0 ? std::numeric_limits<double>::infinity() : c.saving / double(c.extra);
      };
      std::stable_sort(cands.begin(), cands.end(),
                       [&](const Candidate& a, const Candidate& b) { return rank(a) > rank(b); });
      int64_t texels = int64_t(light_texels[l]);
      for (const Candidate& c : cands) {
        if (c.extra <= 0 || texels + c.extra <= int64_t(cap))
          texels += c.extra;
        else
          parts[c.job].sets[c.set].in_parts = false;
      }
    }
  }
  parallel_for(int(jobs.size()), threads, [&](int ii) {
    const size_t i = size_t(ii);
    PartsDecision& pd = parts[i];
    if (!pd.considered) return;
    std::vector<SourcePatch>& plain = per_job[i];
    plain.clear();
    for (size_t k = 0; k < pd.whole.size(); ++k)
      if (!pd.sets[size_t(pd.whole_set[k])].in_parts) plain.push_back(std::move(pd.whole[k]));
    for (size_t k = 0; k < pd.parts.size(); ++k)
      if (pd.sets[size_t(pd.parts_set[k])].in_parts) plain.push_back(std::move(pd.parts[k]));
    // Level 0 first within a job (each cut's patches already are).
    std::stable_sort(plain.begin(), plain.end(),
                     [](const SourcePatch& a, const SourcePatch& b) { return a.level < b.level; });
    for (const ChartSetChoice& c : pd.sets) {
      pd.sets_used += c.used ? 1 : 0;
      pd.sets_in_parts += c.in_parts ? 1 : 0;
    }
    pd.chosen = pd.sets_in_parts > 0;
    if (pd.chosen) {
      // The cut's counts are those of the cut with the most sets; the final pieces' colours are
      // counted again.
      ColourDecision& cd = colour[i];
      if (2 * pd.sets_in_parts > pd.sets_used) cd = pd.parts_colour;
      cd.tinted = cd.two_tints = 0;
      for (const SourcePatch& p : plain) {
        cd.two_tints += p.channels == 2 ? 1 : 0;
        cd.tinted +=
            p.channels == 1 && (p.tint[0] != 255 || p.tint[1] != 255 || p.tint[2] != 255) ? 1 : 0;
      }
    }
    for (const SourcePatch& p : plain) {
      pd.stored_bytes += patch_bytes(p);
      pd.stored_texels += dest_texels(p);
    }
    split[i].plain = channel_texels(plain);
    pd.whole.clear();
    pd.parts.clear();
    pd.sets.clear();
  });
  // One choice per light group (the base map with the static shadows; a light's C_l with its
  // S_ol and pair corrections), so that a state's indirect part is the bounce light of the groups
  // that split, whole. The light-map part may be negative where the indirect map's filter blends
  // across a crease; the runtime presents both maps signed and a game clamps L + I.
  std::map<int, uint64_t> group_plain, group_split;
  for (size_t i = 0; i < jobs.size(); ++i) {
    const bool splittable = can_split && jobs[i].has_indirect();
    group_plain[jobs[i].prototype.light] += split[i].plain;
    group_split[jobs[i].prototype.light] +=
        splittable ? split[i].detail + split[i].indirect : split[i].plain;
  }
  for (size_t i = 0; i < jobs.size(); ++i) {
    const int g = jobs[i].prototype.light;
    const bool split_group = can_split && (options.always_split || jobs[i].indirect_only ||
                                           group_split[g] < group_plain[g]);
    if (!split_group || !jobs[i].has_indirect()) {
      per_job_q[i].clear();
      continue;
    }
    split[i].split = true;
    per_job[i] = std::move(split_patches[i]);
    colour[i] = split_colour[i];
  }
  split_patches.clear();
  std::vector<SourcePatch> patches;
  std::vector<QuantizedPatch> quantized;
  std::vector<uint8_t> to_quantize;
  bool any_split = false;
  for (size_t i = 0; i < per_job.size(); ++i) {
    const size_t detail = per_job[i].size() - per_job_q[i].size();
    for (size_t k = 0; k < per_job[i].size(); ++k) {
      patches.push_back(std::move(per_job[i][k]));
      quantized.push_back(k < detail ? QuantizedPatch{} : std::move(per_job_q[i][k - detail]));
      to_quantize.push_back(k < detail ? 1 : 0);
    }
    any_split = any_split || split[i].split;
  }
  per_job.clear();
  per_job_q.clear();
  parallel_for(int(patches.size()), threads, [&](int i) {
    if (to_quantize[size_t(i)])
      quantized[size_t(i)] = quantize_patch(patches[size_t(i)], options.encoding);
  });
  // A patch whose light spans more than its 8 bits hold (quantize.h) is cut where it stands, so
  // that its group's patches stay together and in their order.
  int range_cut = 0, range_pieces = 0;
  {
    std::vector<SourcePatch> kept;
    std::vector<QuantizedPatch> kept_q;
    kept.reserve(patches.size());
    kept_q.reserve(patches.size());
    for (size_t i = 0; i < patches.size(); ++i) {
      const QuantizedPatch& q = quantized[i];
      if (to_quantize[i] && patches[i].level == 0 &&
          q.error[q.encoding].worst_over_allowance > 1.0) {
        const bool light_map = patches[i].target == kTargetLightMap;
        const size_t n =
            split_for_range(std::move(patches[i]), light_map ? &layout.regions : nullptr,
                            options.encoding, kept, kept_q);
        range_cut += n > 1 ? 1 : 0;
        range_pieces += n > 1 ? int(n) : 0;
        continue;
      }
      kept.push_back(std::move(patches[i]));
      kept_q.push_back(std::move(quantized[i]));
    }
    patches = std::move(kept);
    quantized = std::move(kept_q);
  }

  PackContents c;
  c.lightmap_width = uint32_t(layout.width);
  c.lightmap_height = uint32_t(layout.height);
  c.indirect_scale = any_split ? uint32_t(scale) : 0;
  // A scene light's record: its name (or light_<index>), authored colour, intensity and type.
  auto light_record = [&](int li) {
    const Light& l = scene.lights[size_t(li)];
    LightRecord r{};
    const std::string name = l.name.empty() ? "light_" + std::to_string(li) : l.name;
    c.add_name(name, &r.name_offset, &r.name_length);
    for (int k = 0; k < 3; ++k) r.color[k] = l.color[k];
    r.intensity = l.intensity;
    if (!std::isfinite(r.intensity) || r.intensity < 0.0f || !std::isfinite(max3(l.color)) ||
        std::min({l.color.x, l.color.y, l.color.z}) < 0.0f) {
      throw CookError("light '" + name + "': colour and intensity must be finite and >= 0");
    }
    r.type = l.type == LightType::kPoint  ? kLightPoint
             : l.type == LightType::kSpot ? kLightSpot
                                          : kLightDirectional;
    return r;
  };
  for (int li : maps.lights) c.lights.push_back(light_record(li));
  // Moving lights (no groups) and the panes (pack_format.h, "Moving lights"); a pane's authored
  // colour is its factor for the moving lights' authored poses, by the runtime's own weights.
  for (int li : maps.moving_lights) {
    const Light& l = scene.lights[size_t(li)];
    LightRecord r = light_record(li);
    r.flags = kLightFlagMoving;
    MovingLightRecord m{};
    m.light = uint32_t(c.lights.size());
    for (int k = 0; k < 3; ++k) {
      m.position[k] = l.position[k];
      m.direction[k] = l.direction[k];
    }
    m.range = l.range;
    m.inner_cone = l.type == LightType::kSpot ? l.inner_cone : 0.0f;
    m.outer_cone = l.type == LightType::kSpot ? l.outer_cone : 0.0f;
    m.radius = l.radius;
    c.lights.push_back(r);
    c.moving_lights.push_back(m);
  }
  std::vector<PaneRecord> records;  // an anchor's weight reads every anchor (its normalizer)
  for (const PaneMap& p : maps.panes) records.push_back(p.record);
  std::vector<float> normalizer(c.moving_lights.size(), 0.0f);
  if (!records.empty() && is_anchor(records[0]))
    for (size_t m = 0; m < c.moving_lights.size(); ++m)
      normalizer[m] =
          anchor_normalizer(records.data(), uint32_t(records.size()), c.moving_lights[m].position);
  for (size_t k = 0; k < maps.panes.size(); ++k) {
    PaneRecord pr = maps.panes[k].record;
    pr.light = uint32_t(c.lights.size());
    glm::vec3 factor(0.0f);
    for (size_t m = 0; m < c.moving_lights.size(); ++m) {
      const Light& l = scene.lights[size_t(maps.moving_lights[m])];
      const MovingLightRecord& ml = c.moving_lights[m];
      const float w = is_anchor(pr)
                          ? anchor_weight(pr, ml.position, normalizer[m])
                          : pane_weight(ml, c.lights[ml.light].type, authored_pose(ml), pr);
      factor += l.color * l.intensity * w;
    }
    LightRecord r{};
    for (int a = 0; a < 3; ++a) r.color[a] = std::isfinite(factor[a]) ? factor[a] : 0.0f;
    r.intensity = 1.0f;
    r.type = kLightPane;
    c.lights.push_back(r);
    c.panes.push_back(pr);
  }
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    ObjectRecord r{};
    const std::string& n = scene.objects[i].name;
    c.add_name(n.empty() ? "object_" + std::to_string(i) : n, &r.name_offset, &r.name_length);
    c.objects.push_back(r);
  }

  // The stored patches: each source patch, or its three channels apart (see split_for_alpha),
  // and their atlas places. Contribution patches are split only where that takes fewer atlas
  // texels than splitting the base and static-shadow patches alone: they cost drawing.
  std::vector<StoredPatch> stored =
      options.fill_alpha ? split_for_alpha(patches, false) : whole_patches(patches);
  AtlasLayout atlas_layout =
      pack_atlases(pack_items(patches, stored), options.max_atlas_size, threads);
  if (options.fill_alpha) {
    std::vector<StoredPatch> more = split_for_alpha(patches, true);
    if (more.size() > stored.size()) {
      AtlasLayout smaller =
          pack_atlases(pack_items(patches, more), options.max_atlas_size, threads);
      if (atlas_texels(smaller) < atlas_texels(atlas_layout)) {
        stored = std::move(more);
        atlas_layout = std::move(smaller);
      }
    }
  }

  // Groups: consecutive patches with one owner (jobs are already in group order).
  for (size_t i = 0; i < stored.size(); ++i) {
    const SourcePatch& p = patches[stored[i].source];
    const uint16_t light = p.light < 0 ? kNone16 : uint16_t(p.light);
    const uint16_t object = p.object < 0 ? kNone16 : uint16_t(p.object);
    const uint16_t object_b = p.object_b < 0 ? kNone16 : uint16_t(p.object_b);
    if (c.groups.empty() || c.groups.back().kind != p.kind || c.groups.back().light != light ||
        c.groups.back().object_a != object || c.groups.back().object_b != object_b) {
      c.groups.push_back(GroupRecord{p.kind, light, object, object_b, uint32_t(i), 0});
    }
    c.groups.back().patch_count++;
  }
  if (c.groups.size() > 0x10000u) throw CookError("more than 65536 patch groups");

  // Atlases.
  for (const AtlasSize& a : atlas_layout.atlases) {
    PackContents::Atlas atlas;
    atlas.width = uint32_t(a.width);
    atlas.height = uint32_t(a.height);
    atlas.rgba.assign(size_t(a.width) * a.height * 4, 0);
    c.atlases.push_back(std::move(atlas));
  }
  for (size_t i = 0; i < stored.size(); ++i) {
    const SourcePatch& p = patches[stored[i].source];
    const QuantizedPatch& q = quantized[stored[i].source];
    const Placement& pl = atlas_layout.placements[i];
    const int destination = stored[i].destination;
    // Channels of the source patch stored: all, or the destination's.
    const int first = std::max(destination, 0), count = destination >= 0 ? 1 : p.channels;
    PackContents::Atlas& atlas = c.atlases[size_t(pl.atlas)];
    // The patch texels only: the runtime never reads outside a patch's rectangle.
    for (int y = 0; y < p.stored_h(); ++y) {
      for (int x = 0; x < p.stored_w(); ++x) {
        uint8_t* dst = &atlas.rgba[(size_t(pl.y + y) * atlas.width + size_t(pl.x + x)) * 4 +
                                   size_t(pl.channel)];
        const uint8_t* src =
            &q.codes[(size_t(y) * p.stored_w() + size_t(x)) * size_t(p.channels) + size_t(first)];
        for (int ch = 0; ch < count; ++ch) dst[ch] = src[ch];
      }
    }
    PatchRecord r{};
    r.atlas_x = uint16_t(pl.x);
    r.atlas_y = uint16_t(pl.y);
    r.width = uint16_t(p.dest.w);
    r.height = uint16_t(p.dest.h);
    r.dest_x = uint16_t(p.dest.x);
    r.dest_y = uint16_t(p.dest.y);
    r.atlas = uint8_t(pl.atlas);
    r.channel = uint8_t(pl.channel);
    r.channel_count = uint8_t(count);
    r.encoding = q.encoding;
    r.scale = q.scale;
    r.flags = uint8_t((p.negative ? kFlagNegative : 0) |
                      (destination >= 0 ? (destination + 1) << kFlagDestinationShift : 0) |
                      (uint32_t(p.level) << kFlagLevelShift));
    r.target = p.target;
    for (int ch = 0; ch < 3; ++ch) {
      r.tint[ch] = p.tint[ch];
      r.tint_b[ch] = p.channels == 2 ? p.tint_b[ch] : 0;
    }
    c.patches.push_back(r);
  }
  for (size_t g = 0; g < c.groups.size(); ++g) {
    for (uint32_t k = 0; k < c.groups[g].patch_count; ++k)
      c.patches[c.groups[g].first_patch + k].group = uint16_t(g);
  }

  // Light-map UVs of the baked meshes.
  if (!layout.meshes.empty()) {
    if (layout.meshes.size() != scene.meshes.size()) {
      throw CookError("layout has " + std::to_string(layout.meshes.size()) + " meshes, scene " +
                      std::to_string(scene.meshes.size()));
    }
    for (size_t i = 0; i < scene.meshes.size(); ++i) {
      const MeshInstance& mi = scene.meshes[i];
      const MeshLayout& ml = layout.meshes[i];
      if (ml.indices.empty()) continue;  // kept out of the light map (lightmapExclude)
      if (ml.source_vertex.size() != ml.uv.size())
        throw CookError("mesh layout " + std::to_string(i) + ": UV count");
      PackContents::Mesh m;
      c.add_name(mi.name, &m.record.name_offset, &m.record.name_length);
      m.record.node_index = mi.node_index < 0 ? 0xFFFFFFFFu : uint32_t(mi.node_index);
      m.record.primitive = uint32_t(mi.primitive_index);
      m.record.object = mi.object < 0 ? kNone16 : uint16_t(mi.object);
      if (ml.from_uv1) {
        m.record.flags = kMeshFlagTexcoord1;
        for (int k = 0; k < 4; ++k) m.record.lightmap_scale_offset[k] = ml.uv1_scale_offset[k];
      }
      // Vertices name the glTF vertex: the importer's unwelded vertex maps back to it.
      for (size_t v = 0; v < ml.uv.size(); ++v) {
        const uint32_t src = ml.source_vertex[v];
        const uint32_t gltf = mi.gltf_vertex.empty() ? src : mi.gltf_vertex[src];
        m.vertices.push_back(MeshVertex{gltf, ml.uv[v].x, ml.uv[v].y});
      }
      m.indices = ml.indices;
      for (uint32_t idx : m.indices) {
        if (idx >= m.vertices.size())
          throw CookError("mesh layout " + std::to_string(i) + ": index out of range");
      }
      if (m.indices.size() % 3 != 0)
        throw CookError("mesh layout " + std::to_string(i) + ": index count");
      c.meshes.push_back(std::move(m));
    }
  }

  if (probes != nullptr)
    add_probes(*probes, c.lights.size(), c.objects.size(), light_threshold, first_pane,
               pane_threshold, base_threshold, c);

  std::vector<uint8_t> bytes = write_pack(c);
  {
    // The writer's output must pass the loader's validation (the format; whether it is within a
    // runtime's limits is the tool's warning).
    PackView view;
    Error error;
    if (PackView::open(bytes.data(), bytes.size(), RecomposeLimits::format_only(), &view, &error) !=
        Status::kOk) {
      throw CookError(std::string("internal: the written pack does not validate: ") +
                      error.message);
    }
  }

  // Report: patches, the encoding decision with measured errors, atlas bytes vs a light map.
  EncodingError total[2], chosen;
  int chose[2] = {0, 0};
  int beyond_allowance = 0;  // patches whose chosen encoding misses a texel's allowance
  std::map<std::string, int> by_kind;
  uint64_t negative = 0;
  const char* kind_names[kGroupKindMax + 1] = {"base", "contribution", "shadow", "pair_correction",
                                               "static_shadow"};
  for (size_t i = 0; i < patches.size(); ++i) {
    total[0].add(quantized[i].error[0]);
    total[1].add(quantized[i].error[1]);
    chosen.add(quantized[i].error[quantized[i].encoding]);
    chose[quantized[i].encoding]++;
    beyond_allowance += quantized[i].error[quantized[i].encoding].worst_over_allowance > 1.0;
    by_kind[kind_names[patches[i].kind]]++;
    negative += patches[i].negative ? 1 : 0;
  }
  uint64_t atlas_bytes = 0;
  nlohmann::json atlases = nlohmann::json::array();
  for (const auto& a : c.atlases) {
    atlas_bytes += a.rgba.size();
    atlases.push_back({{"width", a.width}, {"height", a.height}});
  }
  const uint64_t lightmap_bytes = uint64_t(layout.width) * layout.height * 3;
  std::lock_guard<std::mutex> lock(report.mutex());
  nlohmann::json& j = report.root()["pack"];
  j["patches"] = stored.size();
  {
    uint64_t split = 0, texels = 0, lit = 0, lit_texels = 0;
    for (const StoredPatch& sp : stored) {
      if (sp.destination != 0) continue;
      const SourcePatch& p = patches[sp.source];
      const uint64_t t = dest_texels(p);
      ++split;
      texels += t;
      lit += group_has_light(p.kind) ? 1 : 0;
      lit_texels += group_has_light(p.kind) ? t : 0;
    }
    j["split_for_alpha"] = {
        {"patches", split},
        {"texels", texels},
        {"contribution_patches", lit},
        {"contribution_texels", lit_texels},
        {"rule",
         "tinted patches stored as three 1-channel patches, largest first, while the 1-channel "
         "channel-texels fit the alpha plane under the 3-channel ones: first those of the groups "
         "without a light (base, static shadows), then light contributions, from the light whose "
         "change draws the fewest texels, never beyond the texels of the costliest light change "
         "unsplit, and only where that takes fewer atlas texels; each split texel is drawn 3 "
         "times when its group is drawn"}};
  }
  j["patches_by_kind"] = by_kind;
  j["negative_patches"] = negative;
  {
    uint64_t count[2] = {0, 0}, texels[2] = {0, 0};
    for (const SourcePatch& p : patches) {
      count[p.target != 0] += 1;
      texels[p.target != 0] += dest_texels(p);
    }
    uint64_t magnified = 0, magnified_texels = 0, magnified_atlas = 0;
    // Light-map patches of light groups by level: patches, destination texels, atlas texels.
    nlohmann::json by_level = nlohmann::json::array();
    uint64_t lc[pack::kMaxPatchLevel + 1][3] = {};
    for (const SourcePatch& p : patches) {
      const uint64_t dest = dest_texels(p);
      const uint64_t atlas = uint64_t(p.stored_w()) * uint64_t(p.stored_h());
      if (p.target == kTargetLightMap) {
        uint64_t* l = lc[std::clamp(p.level, 0, int(pack::kMaxPatchLevel))];
        l[0] += 1;
        l[1] += dest;
        l[2] += atlas;
      }
      if (p.level == 0) continue;
      ++magnified;
      magnified_texels += dest;
      magnified_atlas += atlas;
    }
    for (const auto& l : lc)
      by_level.push_back({{"patches", l[0]}, {"destination_texels", l[1]}, {"atlas_texels", l[2]}});
    j["magnified_patches"] = {
        {"pane_level", options.pane_level},
        {"max_patch_level", options.max_patch_level},
        {"level_tolerance_steps", options.level_tolerance},
        {"patches", magnified},
        {"destination_texels", magnified_texels},
        {"atlas_texels", magnified_atlas},
        {"light_map_patches_by_level", by_level},
        {"rule",
         "moving lights' panes are stored at 1/2^pane_level of the indirect map's resolution; "
         "each light-map patch at the coarsest level up to max_patch_level whose magnification "
         "stays within level_tolerance_steps 8-bit output steps of the patch at every texel and "
         "channel; a light-map patch's level stores values fitted (least squares, each texel "
         "weighted by its tolerance) so that their bilinear magnification inside the patch, by "
         "the runtime, matches its texels; a pane's level stores the means of 2^level x 2^level "
         "texel blocks"}};
    {
      nlohmann::json per = nlohmann::json::array();
      int considered = 0, chosen = 0;
      uint64_t whole_bytes = 0, stored_bytes = 0, whole_texels = 0, stored_texels = 0;
      for (size_t i = 0; i < jobs.size(); ++i) {
        const PartsDecision& d = parts[i];
        if (!d.considered) continue;
        ++considered;
        chosen += d.chosen ? 1 : 0;
        whole_bytes += d.whole_bytes;
        whole_texels += d.whole_texels;
        stored_bytes += d.stored_bytes;
        stored_texels += d.stored_texels;
        per.push_back({{"map", jobs[i].what},
                       {"parts", d.chosen},
                       {"chart_sets", d.sets_used},
                       {"chart_sets_in_parts", d.sets_in_parts},
                       {"stored_bytes", d.stored_bytes},
                       {"stored_texels", d.stored_texels},
                       {"whole_bytes", d.whole_bytes},
                       {"parts_bytes", d.parts_bytes},
                       {"whole_texels", d.whole_texels},
                       {"parts_texels", d.parts_texels}});
      }
      j["direct_and_bounce_parts"] = {
          {"bounce_tolerance_steps", options.bounce_tolerance},
          {"bounce_threshold_fraction", kBounceThresholdFraction},
          {"draw_texel_bytes", kDrawTexelBytes},
          {"maps_with_direct_part", considered},
          {"maps_in_parts", chosen},
          {"bytes_whole", whole_bytes},
          {"bytes_stored", stored_bytes},
          {"texels_whole", whole_texels},
          {"texels_stored", stored_texels},
          {"maps", per},
          {"rule",
           "a map with a direct part: texels whose direct light stays below a fifth of the "
           "threshold take bounce_tolerance_steps instead of level_tolerance_steps, at most the "
           "output steps the authored image shows there and at least level_tolerance_steps; the "
           "map is stored as its direct part's patches plus its bounce part's (the map less the "
           "direct part, significant from bounce_threshold_fraction of the threshold, within that "
           "tolerance at every texel) where that costs less, chosen per set of charts that no "
           "patch of either cut leaves (chart_sets; parts: any set in parts): bytes (atlas "
           "channel-texels, records, a quad each) plus draw_texel_bytes per destination texel; a "
           "map whose threshold is a step of its own peak keeps level_tolerance_steps"}};
    }
    j["patches_by_target"] = {{"light_map", count[0]}, {"indirect_map", count[1]}};
    j["texels_by_target"] = {{"light_map", texels[0]}, {"indirect_map", texels[1]}};
    nlohmann::json& im = j["indirect_map"];
    im["scale"] = c.indirect_scale;
    im["layout_align"] = layout.align;
    im["width"] = c.indirect_scale ? layout.width / int(c.indirect_scale) : 0;
    im["height"] = c.indirect_scale ? layout.height / int(c.indirect_scale) : 0;
    im["rule"] =
        "each map is stored either as light-map patches only, or as the means of its s x s texel "
        "blocks (indirect-map patches) plus light-map patches of what their bilinear "
        "magnification leaves out (taken against the quantized block means), whichever takes "
        "fewer atlas channel-texels";
    int n_split = 0;
    uint64_t plain = 0, stored = 0;
    nlohmann::json per_map = nlohmann::json::array();
    for (size_t i = 0; i < jobs.size(); ++i) {
      const SplitDecision& d = split[i];
      n_split += d.split ? 1 : 0;
      plain += d.plain;
      stored += d.split ? d.detail + d.indirect : d.plain;
      if (!can_split || d.plain == 0) continue;
      per_map.push_back({{"map", jobs[i].what},
                         {"split", d.split},
                         {"light_map_only", d.plain},
                         {"light_map_part", d.detail},
                         {"indirect_part", d.indirect}});
    }
    im["maps_split"] = n_split;
    im["maps_light_map_only"] = int(jobs.size()) - n_split;
    im["channel_texels_light_map_only"] = plain;
    im["channel_texels_stored"] = stored;
    im["maps"] = per_map;
  }
  j["groups"] = c.groups.size();
  j["significance_rule"] =
      "a texel is significant when some channel exceeds half an 8-bit output step at the authored "
      "exposure: 0.5 * output_step for the base map and static shadows, 0.5 * output_step / a_l "
      "for C_l and S_ol (a_l = authored max(colour) * intensity, floored at 1/100 of the "
      "brightest light), or 0.5 * peak / 255 of the base map or C_l where that is smaller (dim "
      "light alone keeps 8 bits of its own)";
  j["encoding"]["policy"] = options.encoding == EncodingPolicy::kAuto     ? "auto"
                            : options.encoding == EncodingPolicy::kLinear ? "linear"
                                                                          : "square";
  j["encoding"]["error_units"] = "final-map irradiance at the authored state, significant texels";
  j["encoding"]["linear"] = error_json(total[0]);
  j["encoding"]["square"] = error_json(total[1]);
  j["encoding"]["chosen"] = error_json(chosen);
  j["encoding"]["patches_linear"] = chose[0];
  j["encoding"]["patches_square"] = chose[1];
  // Patches whose 8-bit codes miss a significant texel by more than its quantization_allowance
  // (quantize.h: a step, or 1/128 of a bright texel) in both encodings: a range of light too wide
  // for one patch's 8 bits.
  j["encoding"]["patches_beyond_allowance"] = beyond_allowance;
  // Level-0 patches cut into pieces for that (split_for_range), and the pieces they became.
  j["encoding"]["patches_cut_for_range"] = range_cut;
  j["encoding"]["pieces_cut_for_range"] = range_pieces;
  j["encoding"]["output_step"] = maps.output_step;
  j["atlases"] = atlases;
  j["atlas_bytes"] = atlas_bytes;
  j["conventional_lightmap_bytes"] = lightmap_bytes;
  j["atlas_to_lightmap_ratio"] =
      lightmap_bytes > 0 ? double(atlas_bytes) / double(lightmap_bytes) : 0.0;
  j["pack_bytes"] = bytes.size();
  j["probes"] = probe_report(c);
  nlohmann::json maps_colour = nlohmann::json::array();
  int three = 0, one = 0, tinted = 0, two_tints = 0;
  for (size_t i = 0; i < jobs.size(); ++i) {
    const ColourDecision& d = colour[i];
    if (d.three + d.one + d.tinted + d.two_tints == 0) continue;
    three += d.three;
    one += d.one;
    tinted += d.tinted;
    two_tints += d.two_tints;
    maps_colour.push_back({{"map", jobs[i].what},
                           {"patches_3_channel", d.three},
                           {"patches_1_channel", d.one},
                           {"pieces_1_channel_tinted", d.tinted},
                           {"pieces_2_channel_tinted", d.two_tints},
                           {"max_tint", d.max_spread}});
  }
  j["colour"]["rule"] =
      "a 3-channel (bounce-tinted) patch of C_l or S_ol keeps 3 channels where some texel's "
      "max - min over channels exceeds half an output step (final-map units at the authored "
      "state); otherwise it is stored as 1 channel holding (max + min) / 2. After the cut into "
      "pieces and levels, a piece of any map still in 3 channels whose colours fit one colour "
      "(the least-squares tint, 8 bits a channel) within a quarter of an output step at every "
      "stored texel is stored as 1 channel with that tint";
  j["colour"]["forced"] = options.keep_colour;
  j["colour"]["patches_3_channel"] = three;
  j["colour"]["patches_1_channel_from_3"] = one;
  j["colour"]["pieces_1_channel_tinted"] = tinted;
  j["colour"]["pieces_2_channel_tinted"] = two_tints;
  j["colour"]["maps"] = maps_colour;
  return bytes;
}

}  // namespace lightpatch::cooker
