// The pack verbs: `info`, `verify`, `recompose` and `preview` (README.md; DESIGN.md, Command
// line).
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "args.h"
#include "gles_backend.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/io.h"
#include "lightpatch/cooker/printable.h"
#include "lightpatch/cooker/state_spec.h"
#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/platform/file_mapping.h"
#include "lightpatch/scene_state.h"
#include "limit_options.h"
#include "preview_image.h"
#include "state_apply.h"
#include "verbs.h"

namespace lightpatch::tool {

namespace {

using cooker::CookError;

// A mapped, validated pack. Throws CookError naming the file and the problem.
struct OpenPack {
  platform::FileMapping mapping;
  PackView view;
  OpenPack(const std::string& path, const RecomposeLimits& limits) {
    char message[256] = {};
    if (!mapping.open(path.c_str(), message, sizeof(message))) throw CookError(message);
    Error error;
    if (open_pack(mapping.data(), mapping.size(), limits, &view, &error) != Status::kOk) {
      throw CookError(path + ": " + pack_error_text(error));
    }
  }
};

std::string name_string(const Name& n) {
  return std::string(n.data, n.length);
}

const char* section_label(uint32_t type) {
  switch (type) {
    case pack::kSectionLights:
      return "lights";
    case pack::kSectionObjects:
      return "objects";
    case pack::kSectionGroups:
      return "groups";
    case pack::kSectionPatches:
      return "patches";
    case pack::kSectionAtlases:
      return "atlases";
    case pack::kSectionAtlasData:
      return "atlas_data";
    case pack::kSectionStrings:
      return "strings";
    case pack::kSectionMeshes:
      return "meshes";
    case pack::kSectionMeshData:
      return "mesh_data";
    case pack::kSectionProbes:
      return "probes";
    case pack::kSectionProbeGrid:
      return "probe_grid";
    case pack::kSectionProbeSets:
      return "probe_sets";
    case pack::kSectionProbeEntries:
      return "probe_entries";
    case pack::kSectionMovingLights:
      return "moving_lights";
    case pack::kSectionPanes:
      return "panes";
  }
  return "unknown";
}

nlohmann::ordered_json describe(const PackView& p, const std::string& path) {
  nlohmann::ordered_json j;
  j["file"] = path;
  j["version"] = p.header().version;
  j["bytes"] = p.size();
  j["lightmap"] = {{"width", p.lightmap_width()}, {"height", p.lightmap_height()}};
  // 0 x 0 and scale 0 without one (pack_format.h, "Two target maps").
  j["indirect_map"] = {{"width", p.indirect_width()},
                       {"height", p.indirect_height()},
                       {"scale", p.indirect_scale()}};
  nlohmann::ordered_json lights = nlohmann::ordered_json::array();
  for (uint32_t i = 0; i < p.light_count(); ++i) {
    if (p.light_is_pane(i)) continue;  // a moving lights' pane, counted under "panes"
    const pack::LightRecord& l = p.light(i);
    lights.push_back({{"name", name_string(p.light_name(i))},
                      {"color", {l.color[0], l.color[1], l.color[2]}},
                      {"intensity", l.intensity}});
  }
  // Moving lights (pack_format.h, "Moving lights") with their authored pose, and the panes that
  // carry their bounce light.
  nlohmann::ordered_json moving = nlohmann::ordered_json::array();
  for (uint32_t k = 0; k < p.moving_light_count(); ++k) {
    const pack::MovingLightRecord& m = p.moving_light(k);
    moving.push_back({{"name", name_string(p.light_name(m.light))},
                      {"type", p.light(m.light).type == pack::kLightSpot ? "spot" : "point"},
                      {"position", {m.position[0], m.position[1], m.position[2]}}});
  }
  nlohmann::ordered_json objects = nlohmann::ordered_json::array();
  for (uint32_t i = 0; i < p.object_count(); ++i) objects.push_back(name_string(p.object_name(i)));
  j["lights"] = lights;
  j["objects"] = objects;
  j["moving_lights"] = moving;
  j["panes"] = {{"count", p.pane_count()}, {"bytes", p.pane_bytes()}};
  uint64_t by_kind[pack::kGroupKindMax + 1] = {}, texels = 0, negative = 0, one_channel = 0,
                                         square = 0, indirect = 0, magnified = 0, atlas_texels = 0,
                                         tinted = 0, two_channel = 0;
  static_assert(pack::kMaxPatchLevel == 3, "by_level below lists four levels");
  uint64_t by_level[pack::kMaxPatchLevel + 1] = {};
  for (uint32_t i = 0; i < p.patch_count(); ++i) {
    const pack::PatchRecord& r = p.patch(i);
    by_kind[p.group(r.group).kind]++;
    texels += uint64_t(r.width) * r.height * r.channel_count;
    const uint32_t level = pack::patch_level(r.flags);
    by_level[level]++;
    atlas_texels += uint64_t(pack::patch_atlas_side(r.width, level)) *
                    pack::patch_atlas_side(r.height, level) * r.channel_count;
    negative += (r.flags & pack::kFlagNegative) ? 1 : 0;
    one_channel += r.channel_count == 1 ? 1 : 0;
    two_channel += r.channel_count == 2 ? 1 : 0;
    tinted += pack::patch_has_tint(r) ? 1 : 0;
    square += r.encoding == pack::kEncodingSquare ? 1 : 0;
    indirect += r.target == pack::kTargetIndirectMap ? 1 : 0;
    magnified += pack::patch_level(r.flags) > 0 ? 1 : 0;
  }
  j["groups"] = p.group_count();
  j["patches"] = {{"total", p.patch_count()},
                  {"base", by_kind[0]},
                  {"contribution", by_kind[1]},
                  {"shadow", by_kind[2]},
                  {"pair_correction", by_kind[3]},
                  {"static_shadow", by_kind[4]},
                  {"negative", negative},
                  {"one_channel", one_channel},
                  // Two tinted channels (PatchRecord::tint_b).
                  {"two_channel", two_channel},
                  {"three_channel", p.patch_count() - one_channel - two_channel},
                  // Patches with a tint other than 255, 255, 255 (PatchRecord::tint), and every
                  // 2-channel patch.
                  {"tinted", tinted},
                  {"square_encoded", square},
                  {"indirect_map", indirect},
                  {"magnified", magnified},
                  // Patches at level 0, 1, 2 and 3 (pack_format.h, "Magnified patches").
                  {"by_level", {by_level[0], by_level[1], by_level[2], by_level[3]}},
                  // Destination channel-texels (what drawing every patch writes), and what the
                  // patches take in the atlases (less where they are magnified).
                  {"channel_texels", texels},
                  {"atlas_channel_texels", atlas_texels}};
  nlohmann::ordered_json atlases = nlohmann::ordered_json::array();
  uint64_t atlas_bytes = 0;
  for (uint32_t i = 0; i < p.atlas_count(); ++i) {
    atlases.push_back({{"width", p.atlas(i).width}, {"height", p.atlas(i).height}});
    atlas_bytes += uint64_t(p.atlas(i).width) * p.atlas(i).height * 4;
  }
  j["atlases"] = atlases;
  j["meshes"] = p.mesh_count();
  // Each baked mesh instance; those laid out by their own TEXCOORD_1 with the scale and offset a
  // game applies to it (uv = TEXCOORD_1 * xy + zw).
  nlohmann::ordered_json instances = nlohmann::ordered_json::array();
  for (uint32_t i = 0; i < p.mesh_count(); ++i) {
    const pack::MeshRecord& m = p.mesh(i);
    nlohmann::ordered_json e = {{"name", name_string(p.mesh_name(i))},
                                {"node", m.node_index},
                                {"primitive", m.primitive},
                                {"vertices", m.vertex_count},
                                {"triangles", m.index_count / 3}};
    if (m.flags & pack::kMeshFlagTexcoord1) {
      const float* so = m.lightmap_scale_offset;
      e["lightmap_scale_offset"] = {so[0], so[1], so[2], so[3]};
    }
    instances.push_back(e);
  }
  j["mesh_instances"] = instances;
  nlohmann::ordered_json sections = nlohmann::ordered_json::object();
  const pack::SectionEntry* entries =
      reinterpret_cast<const pack::SectionEntry*>(p.bytes() + sizeof(pack::Header));
  for (uint32_t i = 0; i < p.header().section_count; ++i)
    sections[section_label(entries[i].type)] = entries[i].length;
  j["section_bytes"] = sections;
  j["bytes_per_patch_record"] = sizeof(pack::PatchRecord);
  const uint64_t lightmap_bytes = uint64_t(p.lightmap_width()) * p.lightmap_height() * 3;
  j["atlas_bytes"] = atlas_bytes;
  j["conventional_lightmap_bytes"] = lightmap_bytes;
  j["atlas_to_lightmap_ratio"] = double(atlas_bytes) / double(lightmap_bytes);
  // Packing waste: atlas bytes no patch channel covers (unused channels, rounding of sizes).
  uint64_t patch_bytes = 0;
  for (uint32_t i = 0; i < p.patch_count(); ++i) {
    const pack::PatchRecord& r = p.patch(i);
    const uint32_t level = pack::patch_level(r.flags);
    patch_bytes += uint64_t(pack::patch_atlas_side(r.width, level)) *
                   pack::patch_atlas_side(r.height, level) * r.channel_count;
  }
  j["atlas_patch_bytes"] = patch_bytes;
  j["atlas_waste"] = atlas_bytes ? 1.0 - double(patch_bytes) / double(atlas_bytes) : 0.0;
  // Light probes (pack_format.h, "Light probes").
  nlohmann::ordered_json probes;
  probes["count"] = p.probe_count();
  uint32_t named = 0;
  for (uint32_t i = 0; i < p.probe_count(); ++i) named += p.probe_name(i).length > 0 ? 1 : 0;
  probes["named"] = named;
  if (p.has_probe_grid()) {
    const pack::ProbeGridRecord& g = p.probe_grid();
    uint32_t with_probe = 0;
    for (uint32_t i = 0; i < p.probe_grid_point_count(); ++i)
      with_probe += p.probe_grid_indices()[i] != pack::kNone32 ? 1 : 0;
    probes["grid"] = {{"size", {g.size[0], g.size[1], g.size[2]}},
                      {"spacing", g.spacing},
                      {"origin", {g.origin[0], g.origin[1], g.origin[2]}},
                      {"points_with_probe", with_probe}};
  } else {
    probes["grid"] = nullptr;
  }
  probes["sets"] = p.probe_set_count();
  probes["entries"] = p.probe_entry_count();
  probes["bytes"] = p.probe_bytes();
  j["probes"] = probes;
  return j;
}

// The light map after `states` (none: the authored state), on the CPU reference or GLES.
// What a game samples (the light map, plus the indirect map magnified where the pack has one).
// `costs` (optional): the texels written by target, the first build then each state's change.
cooker::FloatImage recomposed(const PackView& view, const std::vector<cooker::StateSpec>& states,
                              bool gles, std::vector<TargetTexels>* costs = nullptr) {
  cooker::FloatImage map(int(view.lightmap_width()), int(view.lightmap_height()), 3);
  std::vector<TargetTexels> written;
  if (gles) {
    std::vector<float> rgb;
    recompose_gles(view, states, &rgb, &written);
    if (rgb.size() != map.data.size())
      throw CookError("GLES backend returned a map of the wrong size");
    map.data = std::move(rgb);
  } else {
    Error error;
    SceneState state;
    CpuRecomposer recomposer;
    if (state.init(view, &error) != Status::kOk || recomposer.init(view, &error) != Status::kOk) {
      throw CookError(std::string("recompose: ") + error.message);
    }
    // Every state is relative to the authored one (DESIGN.md, Scene state); the first full build
    // is of the authored state, then each state goes through the incremental path.
    auto cost = [&recomposer]() {
      const CpuRecomposer::Stats& s = recomposer.stats();
      return TargetTexels{s.texels_drawn - s.indirect_texels_drawn, s.indirect_texels_drawn};
    };
    recomposer.rebuild(state);
    written.push_back(cost());
    for (const cooker::StateSpec& spec : states) {
      state.reset_to_authored(view);
      apply_state(spec, view, &state);
      if (recomposer.apply(state) != Status::kOk)
        throw CookError("recompose: state does not match the pack");
      written.push_back(cost());
    }
    std::copy(recomposer.rgb(), recomposer.rgb() + map.data.size(), map.data.begin());
  }
  for (float v : map.data) {
    if (!std::isfinite(v)) throw CookError("recompose: the light map has a non-finite texel");
  }
  if (costs) *costs = std::move(written);
  return map;
}

}  // namespace

int verb_info(Args& args) {
  const bool json = args.flag("--json");
  const RecomposeLimits limits = parse_recompose_limits(args);
  const std::string path = args.positional("PACK");
  args.finish();
  OpenPack pack(path, limits);
  const nlohmann::ordered_json j = describe(pack.view, path);
  if (json) {
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  const auto& pt = j["patches"];
  std::printf("%s: lightpatch pack v%u, %llu bytes\n", cooker::printable(path, SIZE_MAX).c_str(),
              pack.view.header().version, static_cast<unsigned long long>(pack.view.size()));
  std::printf("light map      %ux%u\n", pack.view.lightmap_width(), pack.view.lightmap_height());
  if (pack.view.has_indirect_map()) {
    std::printf(
        "indirect map   %ux%u (1/%u of the light map per axis), %llu patches draw into it\n",
        pack.view.indirect_width(), pack.view.indirect_height(), pack.view.indirect_scale(),
        pt["indirect_map"].get<unsigned long long>());
  }
  std::printf("lights         %zu\n", j["lights"].size());
  for (const auto& l : j["lights"]) {
    std::printf("  %s  colour (%g, %g, %g)  intensity %g\n",
                cooker::printable(l["name"].get<std::string>(), SIZE_MAX).c_str(),
                l["color"][0].get<double>(), l["color"][1].get<double>(),
                l["color"][2].get<double>(), l["intensity"].get<double>());
  }
  if (pack.view.moving_light_count() > 0) {
    std::printf("moving lights  %u\n", pack.view.moving_light_count());
    for (const auto& m : j["moving_lights"]) {
      std::printf("  %s  %s at (%g, %g, %g)\n",
                  cooker::printable(m["name"].get<std::string>(), SIZE_MAX).c_str(),
                  m["type"].get<std::string>().c_str(), m["position"][0].get<double>(),
                  m["position"][1].get<double>(), m["position"][2].get<double>());
    }
    std::printf("panes          %u (%llu bytes)\n", pack.view.pane_count(),
                static_cast<unsigned long long>(pack.view.pane_bytes()));
  }
  std::printf("objects        %u\n", pack.view.object_count());
  for (const auto& o : j["objects"])
    std::printf("  %s\n", cooker::printable(o.get<std::string>(), SIZE_MAX).c_str());
  std::printf("groups         %u\n", pack.view.group_count());
  std::printf(
      "patches        %u (base %llu, contribution %llu, shadow %llu, pair correction %llu, "
      "static shadow %llu; negative %llu, 1-channel %llu, 2-channel %llu, tinted %llu, "
      "square-encoded %llu, "
      "magnified %llu: level 1 %llu, 2 %llu, 3 %llu)\n",
      pack.view.patch_count(), pt["base"].get<unsigned long long>(),
      pt["contribution"].get<unsigned long long>(), pt["shadow"].get<unsigned long long>(),
      pt["pair_correction"].get<unsigned long long>(),
      pt["static_shadow"].get<unsigned long long>(), pt["negative"].get<unsigned long long>(),
      pt["one_channel"].get<unsigned long long>(), pt["two_channel"].get<unsigned long long>(),
      pt["tinted"].get<unsigned long long>(), pt["square_encoded"].get<unsigned long long>(),
      pt["magnified"].get<unsigned long long>(), pt["by_level"][1].get<unsigned long long>(),
      pt["by_level"][2].get<unsigned long long>(), pt["by_level"][3].get<unsigned long long>());
  std::printf("atlases        %u:", pack.view.atlas_count());
  for (uint32_t i = 0; i < pack.view.atlas_count(); ++i) {
    std::printf(" %ux%u", pack.view.atlas(i).width, pack.view.atlas(i).height);
  }
  std::printf("\nmeshes         %u\n", pack.view.mesh_count());
  const auto& pr = j["probes"];
  std::printf("probes         %u (%u named)", pack.view.probe_count(), pr["named"].get<unsigned>());
  if (pack.view.has_probe_grid()) {
    const pack::ProbeGridRecord& g = pack.view.probe_grid();
    std::printf(", grid %ux%ux%u at %g m (%u points with a probe)", g.size[0], g.size[1], g.size[2],
                double(g.spacing), pr["grid"]["points_with_probe"].get<unsigned>());
  }
  std::printf(", %u sets, %u entries, %llu bytes\nsection bytes ", pack.view.probe_set_count(),
              pack.view.probe_entry_count(),
              static_cast<unsigned long long>(pack.view.probe_bytes()));
  for (const auto& [k, v] : j["section_bytes"].items()) {
    std::printf(" %s %llu", k.c_str(), v.get<unsigned long long>());
  }
  std::printf("\npatch record   %zu bytes\n", sizeof(pack::PatchRecord));
  std::printf("atlas bytes    %llu vs conventional RGB8 light map %llu: ratio %.3f\n",
              j["atlas_bytes"].get<unsigned long long>(),
              j["conventional_lightmap_bytes"].get<unsigned long long>(),
              j["atlas_to_lightmap_ratio"].get<double>());
  std::printf("atlas waste    %.1f %% (patches fill %llu of the atlas bytes)\n",
              100.0 * j["atlas_waste"].get<double>(),
              j["atlas_patch_bytes"].get<unsigned long long>());
  return 0;
}

int verb_verify(Args& args) {
  const RecomposeLimits limits = parse_recompose_limits(args);
  const std::string path = args.positional("PACK");
  args.finish();
  platform::FileMapping mapping;
  char message[256] = {};
  if (!mapping.open(path.c_str(), message, sizeof(message))) {
    std::fprintf(stderr, "lightpatch verify: %s\n", message);
    return 1;
  }
  PackView view;
  Error error;
  if (open_pack(mapping.data(), mapping.size(), limits, &view, &error) != Status::kOk) {
    std::fprintf(stderr, "%s: INVALID: %s\n", path.c_str(), pack_error_text(error).c_str());
    return 1;
  }
  std::printf("%s: OK (%llu bytes, %u lights, %u objects, %u patches, %u atlases)\n", path.c_str(),
              static_cast<unsigned long long>(mapping.size()), view.light_count(),
              view.object_count(), view.patch_count(), view.atlas_count());
  return 0;
}

int verb_recompose(Args& args) {
  std::string state_path, states_path, backend, output;
  args.option("--state", &state_path);
  args.option("--states", &states_path);
  if (!args.option("--backend", &backend)) backend = "cpu";
  if (!args.option("-o", &output)) args.option("--output", &output);
  const RecomposeLimits limits = parse_recompose_limits(args);
  const std::string path = args.positional("PACK");
  args.finish();
  if (output.empty()) throw ArgsError("-o MAP.pfm is required");
  if (!state_path.empty() && !states_path.empty())
    throw ArgsError("give --state or --states, not both");
  if (backend != "cpu" && backend != "gles")
    throw ArgsError("--backend takes cpu or gles, got '" + backend + "'");
  cooker::check_command_files({path, state_path, states_path}, {output});

  std::vector<cooker::StateSpec> states;
  if (!state_path.empty()) states.push_back(cooker::load_state_file(state_path));
  if (!states_path.empty()) states = cooker::load_states_jsonl(states_path);
  OpenPack pack(path, limits);
  const PackView& view = pack.view;

  std::vector<TargetTexels> costs;
  const cooker::FloatImage map = recomposed(view, states, backend == "gles", &costs);
  cooker::write_pfm(output, map);
  // What each step wrote, by target (the cost a game's budget pays, in each map's own texels).
  if (view.has_indirect_map()) {
    std::printf("indirect map %ux%u (1/%u of the light map per axis)\n", view.indirect_width(),
                view.indirect_height(), view.indirect_scale());
  }
  for (size_t i = 0; i < costs.size(); ++i) {
    char step[32];
    if (i == 0) {
      std::snprintf(step, sizeof step, "first build");
    } else {
      std::snprintf(step, sizeof step, "state %zu", i);
    }
    std::printf("%-12s %llu texels written: %llu light map, %llu indirect map\n", step,
                static_cast<unsigned long long>(costs[i].total()),
                static_cast<unsigned long long>(costs[i].light_map),
                static_cast<unsigned long long>(costs[i].indirect_map));
  }
  return 0;
}

int verb_preview(Args& args) {
  std::string state_path;
  args.option("--state", &state_path);
  PreviewOptions o = parse_preview_options(args, nullptr);
  if (!args.option("-o", &o.png)) args.option("--output", &o.png);
  const RecomposeLimits limits = parse_recompose_limits(args);
  const std::string path = args.positional("PACK");
  args.finish();
  if (o.png.empty()) throw ArgsError("-o OUT.png is required");
  cooker::check_command_files({path, state_path}, {o.png});
  std::vector<cooker::StateSpec> states;
  if (!state_path.empty()) states.push_back(cooker::load_state_file(state_path));
  OpenPack pack(path, limits);
  const cooker::FloatImage map = o.view == PreviewView::kAtlases
                                     ? cooker::FloatImage(1, 1, 3)
                                     : recomposed(pack.view, states, false);
  write_preview(o, map, pack_charts(pack.view), &pack.view);
  return 0;
}

}  // namespace lightpatch::tool
