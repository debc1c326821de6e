// The `cook` and `bake-state` verbs: glTF in, a pack (cook) or one state's float map (bake-state)
// out. Both run the same import, layout and texel stages with the same options, so both give the
// same light-map layout.
#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "args.h"
#include "cook_options.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/cook.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/gltf_writer.h"
#include "lightpatch/cooker/import.h"
#include "lightpatch/cooker/io.h"
#include "lightpatch/cooker/pack_builder.h"
#include "lightpatch/cooker/plan_measure.h"
#include "lightpatch/cooker/progress.h"
#include "lightpatch/cooker/reference_integrator.h"
#include "lightpatch/cooker/report.h"
#include "lightpatch/cooker/texel_builder.h"
#include "lightpatch/cooker/tracer.h"
#include "lightpatch/cooker/unwrap.h"
#include "lightpatch/pack_format.h"
#include "limit_options.h"
#include "preview_image.h"
#include "verbs.h"

namespace lightpatch::tool {

namespace {

using namespace lightpatch::cooker;

}  // namespace

CookOptions parse_cook_options(Args& args, const char* output_what) {
  CookOptions o;
  if (!args.option("-o", &o.output) && !args.option("--output", &o.output)) {
    throw ArgsError(std::string("missing -o ") + output_what);
  }
  if (o.output.empty()) throw ArgsError("-o needs a file name");
  o.layout.lightmap_size = args.int_option("--lightmap-size", 0, 8, 16384);
  o.layout.texels_per_unit = args.float_option("--texels-per-unit", 0.0f, 1e-6f, 1e6f);
  std::string unwrap;
  if (args.option("--unwrap", &unwrap)) {
    if (unwrap == "auto")
      o.layout.unwrap = UnwrapMode::kAuto;
    else if (unwrap == "always")
      o.layout.unwrap = UnwrapMode::kAlways;
    else if (unwrap == "never")
      o.layout.unwrap = UnwrapMode::kNever;
    else
      throw ArgsError("--unwrap takes auto, always or never, not '" + unwrap + "'");
  }
  std::string quality;
  if (args.option("--quality", &quality)) {
    try {
      o.bake.quality = parse_quality(quality);
    } catch (const CookError& e) {
      throw ArgsError(e.what());
    }
  }
  args.option("--report", &o.report_path);
  // Indirect light and sampling: overrides of the quality preset (0 keeps the preset's value).
  o.bake.indirect = !args.flag("--no-indirect");
  std::string integrator;
  if (args.option("--integrator", &integrator)) {
    try {
      o.bake.integrator = parse_integrator(integrator);
    } catch (const CookError& e) {
      throw ArgsError(std::string("--integrator: ") + e.what());
    }
  }
  o.bake.gather_rays = args.int_option("--gather-rays", 0, 1, 65536);
  std::string scale;
  if (args.option("--indirect-scale", &scale) && scale != "auto") {
    if (scale != "1" && scale != "2" && scale != "4" && scale != "8")
      throw ArgsError("--indirect-scale must be auto, 1, 2, 4 or 8, not '" + scale + "'");
    o.bake.indirect_scale = std::stoi(scale);
  }
  o.bake.denoise = args.int_option("--denoise", -1, 0, 3);
  o.bake.contact_texels = args.flag("--contact-texels");
  o.bake.area_samples = args.int_option("--area-samples", 0, 1, 65536);
  o.bake.texel_samples = args.int_option("--texel-samples", 0, 1, 256);
  o.bake.seed = static_cast<uint64_t>(args.int_option("--seed", 1, 0, 2'000'000'000));
  o.bake.threads = args.int_option("--threads", 0, 1, 1024);
  o.bake.plan_effects = !args.flag("--no-plan");
  o.bake.output_step = args.float_option("--output-step", 0.0f, 1e-30f, 1e30f);
  o.bake.probes.enabled = !args.flag("--no-probes");
  o.bake.probes.spacing = args.float_option("--probe-spacing", 0.0f, 1e-3f, 1e6f);
  o.bake.probes.rays = args.int_option("--probe-rays", 0, 1, 65536);
  o.bake.panes = args.int_option("--panes", 0, 1, kMaxPaneOption);
  o.bake.pane_level = args.int_option("--pane-level", -1, 0, int(pack::kMaxPatchLevel));
  o.bake.anchor_spacing = args.float_option("--anchors", 0.0f, kMinAnchorSpacing, 1e6f);
  o.bake.max_patch_level = args.int_option("--max-patch-level", -1, 0, int(pack::kMaxPatchLevel));
  o.bake.level_tolerance = args.float_option("--level-tolerance", 0.0f, 0.01f, kMaxLevelTolerance);
  o.bake.bounce_tolerance =
      args.float_option("--bounce-tolerance", 0.0f, 0.01f, kMaxLevelTolerance);
  o.quiet = args.flag("--quiet", "-q");
  o.layout.align = layout_align(o.bake);
  o.layout.align_required = o.bake.indirect_scale > 0;
  o.import = parse_import_limits(args);
  return o;
}

void probe_output_folder(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const std::string dir =
      slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  std::string probe = dir + "/.lightpatch-probe.XXXXXX";
  const int fd = ::mkstemp(probe.data());
  if (fd < 0) throw CookError("cannot write into '" + dir + "' (for '" + path + "')");
  ::close(fd);
  ::unlink(probe.c_str());
}

namespace {

void finish_report(const CookOptions& o, Report& report, double seconds) {
  if (o.report_path.empty()) return;
  {
    std::lock_guard<std::mutex> lock(report.mutex());
    report.root()["total_seconds"] = seconds;
  }
  report.write(o.report_path);
}

double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// Bakes and packs the scene with the plan off (same options and seed), then with the plan again,
// neither pack written, and adds the comparison to `report` (plan_measure.h). The cook's own bake
// pays one-time costs (first touch of the tracer's and the maps' memory: about 0.5 s of 8 in the
// small inn) that would credit the forced run, so both timed runs follow it.
void measure_plan(const CookOptions& o, const PreparedScene& p, Progress& progress, Report& report,
                  const std::vector<uint8_t>& pack) {
  BakeOptions forced = o.bake;
  forced.plan_effects = false;
  Report fr, pr;
  progress.message("measure plan: baking again with everything forced on, then as planned");
  cook_pack(p, forced, progress, fr);
  const std::vector<uint8_t> again = cook_pack(p, o.bake, progress, pr);
  std::lock_guard<std::mutex> lock(report.mutex());
  add_plan_measurement(pr.root(), fr.root());
  // The same decisions in the same order (the bake is deterministic), now with saved times.
  report.root()["decisions"] = pr.root()["decisions"];
  report.root()["plan"] = pr.root()["plan"];
  report.root()["plan"]["planned_pack_identical"] = again == pack;
  const nlohmann::json& plan = report.root()["plan"];
  char line[320];
  std::snprintf(line, sizeof line,
                "plan: saved %.3f s (bake+finalize+pack %.3f s planned, %.3f s forced) and %.0f "
                "pack bytes (%.0f planned, %.0f forced), %.0f patches",
                plan["saved"]["seconds"].get<double>(), plan["planned"]["seconds"].get<double>(),
                plan["forced"]["seconds"].get<double>(), plan["saved"]["pack_bytes"].get<double>(),
                plan["planned"]["pack_bytes"].get<double>(),
                plan["forced"]["pack_bytes"].get<double>(), plan["saved"]["patches"].get<double>());
  progress.message(line);
}

}  // namespace

int verb_cook(Args& args) {
  const bool measure = args.flag("--measure-plan");
  std::string gltf_path;
  args.option("--write-gltf", &gltf_path);
  CookOptions o = parse_cook_options(args, "OUT.lpk");
  o.scene_path = args.positional("SCENE");
  args.finish();
  if (measure && !o.bake.plan_effects) {
    throw ArgsError("--measure-plan compares the plan with --no-plan; give one of them");
  }
  if (o.bake.integrator == Integrator::kReference) {
    throw ArgsError(
        "--integrator reference bakes single states (bake-state, accuracy), not packs; cook uses "
        "gather");
  }
  const auto t0 = std::chrono::steady_clock::now();
  check_command_files({o.scene_path}, {o.output, o.report_path, gltf_path});
  probe_output_folder(o.output);
  if (!o.report_path.empty()) probe_output_folder(o.report_path);
  if (!gltf_path.empty()) probe_output_folder(gltf_path);
  Progress progress(o.quiet);
  Report report;
  const PreparedScene p = prepare_scene(o.scene_path, o.layout, progress, report, o.import);
  BakedMaps maps;
  const std::vector<uint8_t> pack = cook_pack(p, o.bake, progress, report, &maps);
  if (const std::string w = check_cooked_pack(pack); !w.empty())
    std::fprintf(stderr, "lightpatch cook: warning: %s\n", w.c_str());
  progress.begin("write", 1);
  write_file_atomic(o.output, pack.data(), pack.size());
  if (!gltf_path.empty()) {
    const std::vector<uint8_t> glb = gltf_with_lightmap_uvs(o.scene_path, p.scene, p.layout);
    write_file_atomic(gltf_path, glb.data(), glb.size());
  }
  report.stage_time("write", progress.end());
  const double cook_s = since(t0);
  progress.message("wrote " + o.output + " (" + std::to_string(pack.size()) + " bytes, " +
                   std::to_string(maps.contribution.size()) + " lights, " +
                   std::to_string(maps.shadows.size()) + " shadow pairs) in " +
                   std::to_string(cook_s) + " s");
  if (measure) {
    maps = BakedMaps{};  // the forced run's maps take its place
    measure_plan(o, p, progress, report, pack);
  }
  finish_report(o, report, cook_s);
  return 0;
}

// The standard-error map beside MAP.pfm: MAP.stderr.pfm (".stderr.pfm" appended to other names).
std::string std_error_path(const std::string& map_path) {
  const std::string ext = ".pfm";
  if (map_path.size() > ext.size() &&
      map_path.compare(map_path.size() - ext.size(), ext.size(), ext) == 0) {
    return map_path.substr(0, map_path.size() - ext.size()) + ".stderr.pfm";
  }
  return map_path + ".stderr.pfm";
}

int verb_bake_state(Args& args) {
  std::string state_path, std_error_out;
  args.option("--state", &state_path);
  ReferenceOptions ref;
  ref.samples = args.int_option("--samples", 0, 2, 1 << 20);
  const bool has_samples = ref.samples != 0;
  if (!has_samples) ref.samples = kDefaultReferenceSamples;
  const bool has_std_error = args.option("--std-error", &std_error_out);
  const float target_percent = args.float_option("--target-noise", 0.0f, 1e-3f, 100.0f);
  ref.target_noise = 0.01 * target_percent;
  const PreviewOptions picture = parse_preview_options(args, "--png");
  if (picture.view == PreviewView::kAtlases)
    throw ArgsError("--view atlases shows a pack's atlases: use lightpatch preview");
  const bool moving_direct = args.flag("--moving-direct");
  CookOptions o = parse_cook_options(args, "MAP.pfm");
  o.bake.moving_direct = moving_direct;
  o.scene_path = args.positional("SCENE");
  args.finish();
  const bool reference = o.bake.integrator == Integrator::kReference;
  if (!reference && (has_samples || has_std_error || target_percent > 0.0f)) {
    throw ArgsError("--samples, --target-noise and --std-error need --integrator reference");
  }
  if (reference) {
    if (!has_std_error) std_error_out = std_error_path(o.output);
    if (std_error_out.empty()) throw ArgsError("--std-error needs a file name");
    if (std_error_out == o.output) throw ArgsError("--std-error names the map itself");
  }
  const auto t0 = std::chrono::steady_clock::now();
  check_command_files({o.scene_path, state_path},
                      {o.output, o.report_path, picture.png, reference ? std_error_out : ""});
  const StateSpec state = state_path.empty() ? StateSpec{} : load_state_file(state_path);
  probe_output_folder(o.output);
  if (!picture.png.empty()) probe_output_folder(picture.png);
  if (!o.report_path.empty()) probe_output_folder(o.report_path);
  if (reference) probe_output_folder(std_error_out);
  Progress progress(o.quiet);
  Report report;
  const PreparedScene p = prepare_scene(o.scene_path, o.layout, progress, report, o.import);
  FloatImage map, std_error;
  if (reference) {
    ref.seed = o.bake.seed;
    ref.threads = o.bake.threads;
    ref.texel_patch = o.bake.texel_samples != 1;
    ref.moving_direct = o.bake.moving_direct;
    ReferenceBake rb = cook_reference_state(p, state, ref, progress, report);
    progress.message("reference: " + std::to_string(rb.samples) + " samples, " +
                     std::to_string(rb.rays) + " rays, mean relative standard error " +
                     std::to_string(100.0 * rb.mean_rel_std_error) + " %, noise rel. RMSE " +
                     std::to_string(100.0 * rb.rel_rmse_noise) + " %, paths from inside solids " +
                     std::to_string(100.0 * rb.inside_path_fraction) + " % (dropped; " +
                     std::to_string(rb.inside_texels) + " texels had only such, left 0)");
    map = std::move(rb.map);
    std_error = std::move(rb.std_error);
  } else {
    map = cook_state(p, state, o.bake, progress, report);
  }
  progress.begin("write", 1);
  write_pfm(o.output, map);
  if (reference) write_pfm(std_error_out, std_error);
  if (!picture.png.empty()) write_preview(picture, map, layout_charts(p.scene, p.layout), nullptr);
  report.stage_time("write", progress.end());
  finish_report(o, report, since(t0));
  progress.message("wrote " + o.output + (reference ? " and " + std_error_out : std::string()) +
                   " (" + std::to_string(map.width) + "x" + std::to_string(map.height) + ") in " +
                   std::to_string(since(t0)) + " s");
  return 0;
}

}  // namespace lightpatch::tool
