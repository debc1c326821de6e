#include "lightpatch/cooker/cook.h"

#include <algorithm>
#include <mutex>

#include "lightpatch/cooker/cook_jobs.h"
#include "lightpatch/cooker/import.h"
#include "lightpatch/cooker/texel_builder.h"
#include "lightpatch/cooker/unwrap.h"

namespace lightpatch::cooker {

namespace {

template <typename F>
auto timed(Progress& progress, Report& report, const std::string& stage, F&& f) {
  progress.begin(stage, 1);
  auto result = f();
  report.stage_time(stage, progress.end());
  return result;
}

}  // namespace

PreparedScene prepare_scene(Scene scene, const LayoutOptions& given, Progress& progress,
                            Report& report) {
  PreparedScene p;
  p.scene = std::move(scene);
  LayoutOptions options = given;
  // Moving lights' panes are bounce light only and live on the indirect map: auto lays the charts
  // out on 2 x 2 blocks for them (docs/moving_lights.md; at 1 their maps would take full-size
  // light-map patches, which the pack builder still makes if asked for --indirect-scale 1).
  bool moving = false;
  for (const Light& l : p.scene.lights) moving = moving || l.moving;
  if (moving && !options.align_required && options.align == 1) {
    options.align = 2;
    progress.message(
        "note: moving lights: the charts are laid out on 2x2 blocks for the "
        "indirect map their panes are stored on (--indirect-scale auto)");
  }
  p.layout = timed(progress, report, "layout", [&] { return build_layout(p.scene, options); });
  for (const std::string& note : p.layout.notes) progress.message("note: " + note);
  p.tracer = timed(progress, report, "trace setup", [&] { return make_embree_tracer(p.scene); });
  p.texels = timed(progress, report, "texels",
                   [&] { return build_texels(p.scene, p.layout, p.tracer.get()); });

  size_t valid = 0;
  for (uint8_t v : p.texels.valid) valid += v ? 1 : 0;
  int semi_lights = 0;
  for (const Light& l : p.scene.lights) semi_lights += l.semi_dynamic ? 1 : 0;
  if (semi_lights == 0 && p.scene.objects.empty())
    progress.message(
        "note: the scene marks no light or object semi-dynamic (a node's extras "
        "\"semiDynamic\": true), so everything is baked static and nothing can change at run "
        "time. Blender writes custom properties only with Include > Custom Properties on in its "
        "glTF export (off by default)");
  std::lock_guard<std::mutex> lock(report.mutex());
  nlohmann::json& s = report.root()["scene"];
  s["triangles"] = p.scene.triangle_count();
  s["meshes"] = p.scene.meshes.size();
  s["lights"] = p.scene.lights.size();
  s["semi_dynamic_lights"] = semi_lights;
  s["objects"] = p.scene.objects.size();
  s["scale_m"] = p.scene.scale();
  nlohmann::json& l = report.root()["layout"];
  l["width"] = p.layout.width;
  l["height"] = p.layout.height;
  l["texels_per_unit"] = p.layout.texels_per_unit;
  l["verbatim_uv1"] = p.layout.verbatim_uv1;
  l["uv1_regions"] = p.layout.uv1_regions;
  l["unwrapped_regions"] = p.layout.unwrapped_regions;
  l["regions"] = p.layout.regions.size();
  l["notes"] = p.layout.notes;
  l["texels"] = p.texels.position.size();
  l["valid_texels"] = valid;
  return p;
}

PreparedScene prepare_scene(const std::string& path, const LayoutOptions& options,
                            Progress& progress, Report& report, const ImportLimits& limits) {
  Scene scene = timed(progress, report, "import", [&] { return import_gltf(path, limits); });
  {
    std::lock_guard<std::mutex> lock(report.mutex());
    report.root()["scene"]["path"] = path;
  }
  return prepare_scene(std::move(scene), options, progress, report);
}

void finalize_maps(BakedMaps& maps, const PreparedScene& p, Progress& progress, Report& report) {
  progress.begin("finalize maps", 1);
  finalize_maps(maps, p.scene, p.layout, p.texels);
  report.stage_time("finalize", progress.end());
}

int layout_align(const BakeOptions& bake) {
  // auto keeps bounce light in the light map: magnified from blocks with the texture filter, it
  // blurs across the creases and contacts inside a chart that the gather's own magnification
  // respects (production, against the path tracer: the small inn 1.26 % -> 6.49 % relative RMSE
  // at scale 2, room_soft 1.21 % -> 2.82 %), far over the 1 point the smaller packs may cost.
  return bake.indirect_scale > 0 ? bake.indirect_scale : 1;
}

PackOptions pack_options(const BakeOptions& bake) {
  PackOptions po;
  po.keep_colour = !bake.plan_effects;
  po.pane_level = bake.pane_level >= 0 ? bake.pane_level : kDefaultPaneLevel;
  po.max_patch_level = bake.max_patch_level >= 0 ? bake.max_patch_level : kDefaultMaxPatchLevel;
  po.level_tolerance = bake.level_tolerance > 0.0f ? bake.level_tolerance : kDefaultLevelTolerance;
  const float preset_bounce =
      bake.quality == Quality::kProduction ? kProductionBounceTolerance : kDefaultBounceTolerance;
  po.bounce_tolerance = std::max(
      bake.bounce_tolerance > 0.0f ? bake.bounce_tolerance : preset_bounce, po.level_tolerance);
  return po;
}

ProbeOptions probe_options(const BakeOptions& bake) {
  ProbeOptions po = bake.probes;
  po.seed = bake.seed;
  po.threads = bake.threads;
  if (po.rays <= 0) po.rays = kProbePresetRays[static_cast<int>(bake.quality)];
  return po;
}

ProbeBake cook_probes(const PreparedScene& p, const BakedMaps& maps, const BakeOptions& bake,
                      Progress& progress, Report& report) {
  const ProbeOptions po = probe_options(bake);
  ProbeBake probes = place_probes(p.scene, *p.tracer, po, report);
  bake_probes(probes, p.scene, p.layout, p.texels, *p.tracer, maps, po, progress, report);
  return probes;
}

std::vector<uint8_t> cook_pack(const PreparedScene& p, const BakeOptions& bake, Progress& progress,
                               Report& report, BakedMaps* maps_out) {
  // The cook's jobs in-process: the same code as `plan`, `cook-job` and `assemble`.
  const CookJobs jobs(p, bake, progress, report);
  std::vector<size_t> all(jobs.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = i;
  return jobs.assemble(jobs.run(all, progress, report), progress, report, maps_out);
}

FloatImage cook_state(const PreparedScene& p, const StateSpec& state, const BakeOptions& bake,
                      Progress& progress, Report& report) {
  FloatImage map =
      bake_state(p.scene, p.layout, p.texels, *p.tracer, state, bake, progress, report);
  progress.begin("finalize maps", 1);
  finalize_map(map, p.scene, p.layout, p.texels);
  report.stage_time("finalize", progress.end());
  return map;
}

ReferenceBake cook_reference_state(const PreparedScene& p, const StateSpec& state,
                                   const ReferenceOptions& options, Progress& progress,
                                   Report& report) {
  ReferenceBake rb = bake_reference(p.scene, p.texels, *p.tracer, state, options, progress, report);
  progress.begin("finalize maps", 2);
  finalize_map(rb.map, p.scene, p.layout, p.texels);
  progress.advance();
  finalize_map(rb.std_error, p.scene, p.layout, p.texels);
  report.stage_time("finalize", progress.end());
  return rb;
}

}  // namespace lightpatch::cooker
