// lightpatch: the cooker and the runtime's tools in one executable. See README.md for the verbs.
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "args.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/io.h"
#include "limit_options.h"
#include "verbs.h"

namespace {

struct Verb {
  const char* name;
  int (*run)(lightpatch::tool::Args&);
  const char* usage;
  const char* help;  // what the verb does and every option, for `lightpatch VERB --help`
};

constexpr const char* kCookOptionsHelp =
    "  --lightmap-size N      light-map page width in texels (8..16384); the density follows\n"
    "  --texels-per-unit F    texel density in texels per metre (default: about 160k surface\n"
    "                         texels, a page near 512x512; lowered with a note if the charts do\n"
    "                         not fit a 4096 page); a node's extras \"lightmapScale\": k\n"
    "                         multiplies it for that node's meshes\n"
    "  --unwrap MODE          where light-map UVs come from: auto (default: each node's own\n"
    "                         TEXCOORD_1 in [0,1] where all its meshes have one, placed by a\n"
    "                         scale and offset, or one TEXCOORD_1 layout over the whole scene;\n"
    "                         the cooker unwraps the other nodes), always (ignore TEXCOORD_1),\n"
    "                         never (every mesh must have TEXCOORD_1)\n"
    "  --quality Q            draft | preview (default) | production: gather rays, indirect\n"
    "                         level and denoising, area-light samples\n"
    "  --no-indirect          direct light only (no bounce)\n"
    "  --integrator I         gather (default): final gathering on coarse texels (the light\n"
    "                         map as radiance cache), bounces by iteration, a geometry-guided\n"
    "                         denoiser\n"
    "  --gather-rays N        rays per coarse texel (preset: draft 64, preview 256, production\n"
    "                         256)\n"
    "  --indirect-scale K     auto | 1 | 2 | 4 | 8: K > 1 gathers bounce light on K x K texel\n"
    "                         blocks, lays charts out on whole blocks and stores a light group's\n"
    "                         bounce light on the pack's indirect map at 1/K of the light map's\n"
    "                         resolution where that takes fewer atlas bytes (its light-map\n"
    "                         patches then hold the direct light and what the indirect map's\n"
    "                         filter gets wrong at creases and chart edges; the light is the\n"
    "                         same); 1: gathered per texel. auto (default): bounce light in the\n"
    "                         light map, gathered on the preset's blocks (draft 4, preview 2,\n"
    "                         production 1: per texel) and magnified along each surface; 2..8\n"
    "                         save bytes on rooms of large surfaces, not on props with many\n"
    "                         small charts (README, \"The indirect map\")\n"
    "  --denoise N            a-trous denoising passes over the bounce light, 0 = none (preset:\n"
    "                         draft 2, preview 2, production 1)\n"
    "  --contact-texels       a 2x2 block of bounce light that touches other geometry (a crate's\n"
    "                         foot, a wall behind a panel) gathers per texel, with half the rays\n"
    "                         a texel: preview's contact detail, for about 1.3x its CPU time on\n"
    "                         the small inn (docs/accuracy.md, section (m))\n"
    "  --no-plan              force every effect on: bounce light for every light group with\n"
    "                         every object's change to it, every light-object pair\n"
    "                         traced and kept, every measured overlap correction kept, tinted\n"
    "                         patches kept at 3 channels (for bake-state: every object's bounce)\n"

    "  --no-probes            no light probes (default: probes on a grid of the scene's free\n"
    "                         space and at nodes with extras \"lightProbe\": true, lit per light\n"
    "                         and object like the maps; README, \"Light probes\")\n"
    "  --probe-spacing M      probe grid spacing in metres (default 1, coarser where the scene\n"
    "                         would need more than 65,536 grid points)\n"
    "  --probe-rays N         gather rays per probe (preset: draft 256, preview 512, production\n"
    "                         1024)\n"
    "  --panes N              panes of the moving lights' bounce light (lights with extras\n"
    "                         \"moving\": true), before splitting those a light would light\n"
    "                         unevenly (at most 4N; default 64; 32 takes about half the\n"
    "                         bytes; docs/moving_lights.md)\n"
    "  --pane-level L         0-3: the panes' patches at 1/2^L of the indirect map's\n"
    "                         resolution, magnified by the runtime (default 1)\n"
    "  --anchors M            the moving lights' bounce light baked for light positions on a\n"
    "                         lattice of M metres over the free space (anchors), blended\n"
    "                         around the light by the runtime, instead of on panes: point\n"
    "                         lights of one range and radius only; stored at --pane-level\n"
    "                         (docs/moving_lights.md, \"Anchors\")\n"
    "  --max-patch-level L    0-3: each light-map patch stored at the coarsest level up to L\n"
    "                         (1/2^L of the light map's resolution per axis, magnified\n"
    "                         bilinearly by the runtime) whose magnification stays within\n"
    "                         --level-tolerance of the patch at every texel; a patch that\n"
    "                         cannot is cut into 16 x 16 tiles chosen alike. 0: every patch\n"
    "                         texel for texel (default 3; README, \"Magnified light-map\n"
    "                         patches\")\n"
    "  --level-tolerance S    that tolerance in 8-bit output steps of the authored state,\n"
    "                         0.01-16 (default 1: about the 8-bit rounding's own error)\n"
    "  --bounce-tolerance S   the same for texels of bounce light alone, at most the steps\n"
    "                         the authored image shows there and half a map's own light\n"
    "                         there, 0.01-16, at least --level-tolerance (default 3;\n"
    "                         production 1); each map is also stored as its direct part and\n"
    "                         its bounce part within it, where that costs less (README,\n"
    "                         \"Direct and bounce parts\")\n"
    "  --output-step E        irradiance of one 8-bit step at the authored exposure (default:\n"
    "                         the scene's 99th percentile / 255, rounded down to a quarter\n"
    "                         octave); pinned, edits keep the jobs they cannot change (plan)\n"
    "  --area-samples N       samples per texel for lights with a radius and emissive surfaces\n"
    "  --texel-samples N      points of each texel's surface patch that direct light is averaged\n"
    "                         over (anti-aliased shadow edges); 1 = the texel's sample point\n"
    "                         (preset: draft 1, preview 4, production 9; for bake-state\n"
    "                         --integrator reference, 1 samples the point, otherwise the patch)\n"
    "  --seed N               random seed (same scene, options and seed: same maps)\n"
    "  --threads N            worker threads (default: all cores)\n"
    "  --report REPORT.json   write the cook's decisions, timings and measured errors\n"
    "  -q, --quiet            no progress on stderr\n";

// The picture options of `preview` and `bake-state --png` (preview_image.h).
#define LIGHTPATCH_PREVIEW_HELP                                                                   \
  "  --view V               lightmap (default): the light map tone-mapped to sRGB, the 99th\n"    \
  "                         percentile white, negative texels magenta; atlases (preview only):\n" \
  "                         every atlas's R, G, B and A planes in grey, side by side; charts:\n"  \
  "                         each mesh instance's charts in a colour of its own (semi-dynamic\n"   \
  "                         objects saturated, static meshes pale) shaded by the light;\n"        \
  "                         checker: the same colours in a texel checker, a texture that shows\n" \
  "                         the texel density on a model through its light-map UVs\n"             \
  "  --exposure E           factor on the automatic exposure (default 1)\n"                       \
  "  --zoom N               pixels per texel, 1..16 (default 1)\n"
constexpr const char* kPreviewHelp =
    "Writes a picture of what a pack holds (PNG), from the CPU reference recomposition.\n\n"
    "options:\n"
    "  -o, --output OUT.png   the picture (written atomically)\n"
    "  --state STATE.json     the state to recompose (default: as "
    "authored)\n" LIGHTPATCH_PREVIEW_HELP;

constexpr const char* kCookHelp =
    "Bakes a glTF 2.0 scene (.gltf/.glb) into a pack: base map, per-light contribution maps,\n"
    "per-object shadow maps and pair corrections, quantized to 8-bit RGBA atlases.\n"
    "Lights and mesh nodes with extras {\"semiDynamic\": true} (or 1, as Blender writes it)\n"
    "become switchable; a mesh node with {\"lightmapExclude\": true} casts shadows but gets no\n"
    "light map.\n\n"
    "options:\n"
    "  -o, --output OUT.lpk   the pack (written atomically; an existing file survives a failure)\n"
    "  --write-gltf OUT.glb   also the scene written back with the light-map UVs the cook used\n"
    "                         in TEXCOORD_1 (uncompressed; buffers and images embedded), so any\n"
    "                         glTF loader draws it with the runtime's light map\n"
    "  --measure-plan         after the cook, bake and pack twice more, not written: with\n"
    "                         --no-plan, then as planned (both timed warm), and add to the\n"
    "                         report a \"plan\" object: seconds, rays, bytes and\n"
    "                         patches planned vs forced, what the plan saved, decisions taken and\n"
    "                         skipped per category; a one-line summary on stderr\n";

constexpr const char* kBakeStateHelp =
    "Bakes one scene state directly, as a conventional light mapper would: the ground truth a\n"
    "recomposition must match. Same layout as `cook` with the same options.\n\n"
    "options:\n"
    "  -o, --output MAP.pfm   the light map (irradiance, linear RGB float, PFM)\n"
    "  --state STATE.json     lights on/off, colour, intensity, a moving light's position and\n"
    "                         direction; objects visible (default: as authored, all on and\n"
    "                         visible)\n"
    "  --moving-direct        also the moving lights' direct light (for pictures; the map\n"
    "                         otherwise holds their bounce light only, as a pack does: their\n"
    "                         direct light is the game's)\n"
    "  --integrator I         gather (default): the cook's integrator (below);\n"
    "                         reference: unbiased path tracing from every texel (next-event\n"
    "                         estimation to every light, MIS for light spheres and emissive\n"
    "                         surfaces, Russian roulette), the independent reference; it also\n"
    "                         writes the per-texel standard error and reports its noise\n"
    "  --samples N            reference: paths per texel (2..1048576, default 256); the noise\n"
    "                         falls as 1/sqrt(N)\n"
    "  --target-noise P       reference: stop early, at the first power of two of samples (from\n"
    "                         64) whose noise is at most P percent relative RMSE; --samples is\n"
    "                         then the cap (default: off, all --samples)\n"
    "  --std-error ERR.pfm    reference: where the standard-error map goes (RGB, same units\n"
    "                         and layout as the map; default MAP.stderr.pfm beside MAP.pfm)\n"
    "  (with --integrator reference, --seed and --threads apply; the quality, gather, denoise\n"
    "  and area-sample options do not)\n"
    "  --png OUT.png          also a picture of the map (the options "
    "below)\n" LIGHTPATCH_PREVIEW_HELP;

constexpr const char* kPlanHelp =
    "Plans a cook as jobs (one per light group) in a job folder, for cook-job, assemble and\n"
    "tools/farm/lightpatch-farm (Slurm): imports, lays out and plans once, writes "
    "DIR/manifest.json\n"
    "and DIR/jobs/NAME.json, and prints the job names on stdout, one a line, in an order they may\n"
    "run. A name is g<group>-<content hash of everything its output depends on>: planning again\n"
    "after an edit keeps the names, and reuses the results, of the jobs the edit cannot change.\n\n"
    "options:\n"
    "  -o, --output DIR       the job folder (created if needed; results of earlier plans stay)\n";

constexpr const char* kCookJobHelp =
    "Runs jobs of a job folder (made by plan) and writes each result atomically to\n"
    "DIR/results/JOB.lpg. A job whose result is there with its hash is skipped; several jobs\n"
    "in one call share one import, layout and gather. Fails, writing nothing, if the scene\n"
    "changed since plan or the folder was planned by another build of lightpatch.\n\n"
    "options:\n"
    "  --threads N            worker threads (default: all cores)\n"
    "  --report REPORT.json   the jobs' decisions and timings\n"
    "  -q, --quiet            no progress on stderr\n";

constexpr const char* kJobsHelp =
    "Lists the jobs of a job folder, one a line, in an order they may run; a summary on stderr.\n\n"
    "options:\n"
    "  --pending              only the jobs without a valid result\n";

constexpr const char* kAssembleHelp =
    "Checks that every job of a job folder has its result (naming each missing or stale one),\n"
    "then finalizes and packs: the same bytes as `lightpatch cook` with the scene and options\n"
    "given to plan.\n\n"
    "options:\n"
    "  -o, --output OUT.lpk   the pack (written atomically)\n"
    "  --threads N            worker threads (default: all cores)\n"
    "  --report REPORT.json   decisions, pairs, timings and the pack's statistics\n"
    "  -q, --quiet            no progress on stderr\n";

constexpr const char* kAccuracyHelp =
    "Sweeps the cook's quality knobs and measures what each setting buys in error and costs in\n"
    "time: the quality presets, then, around the preview preset, gather rays, indirect level,\n"
    "denoising, contact texels (--contact-texels), area-light samples (when the scene has\n"
    "lights with a radius or emissive surfaces),\n"
    "texel density (coarser pages) and the 8-bit encoding (linear, square; default auto). Each\n"
    "setting is cooked (bake, finalize, pack), the authored state is recomposed from the pack on\n"
    "the CPU reference and compared with a reference bake of the same state: by default the\n"
    "path tracer (bake-state --integrator reference: up to 4096 samples per texel, stopping\n"
    "once its noise is at most 0.5 % relative RMSE; 64 samples with --quick), whose own noise\n"
    "the CSV notes give; a row whose error is within that noise is marked\n"
    "(within_noise) and does not beat other such rows on the Pareto front. The reference is\n"
    "cached next to the CSV as lightpatch-accuracy-reference-HASH.pfm (and .stderr.pfm), keyed\n"
    "by the scene, its layout and the reference options, and reused by later runs.\n\n"
    "Errors over the valid light-map texels: relative RMSE (sqrt(sum (x-r)^2 / sum r^2)), max\n"
    "relative error over texels that matter (reference luminance >= 1% of its 99th percentile;\n"
    "max_c |x_c-r_c| / max_c r_c), PSNR (peak: 99th percentile of the reference) and the\n"
    "error's sign, which the RMSE hides: bias (sum x / sum r - 1) and median_ratio (the median\n"
    "over texels that matter of a texel's light over the reference's). Density rows are\n"
    "resampled to the reference's texels (nearest texel of the same surface).\n"
    "The CSV has '#' note lines, a header and one row per setting; the table is also printed.\n\n"
    "options:\n"
    "  --csv OUT.csv          the measurements (written atomically)\n"
    "  --plot OUT.png         relative RMSE against cook time, log-log, one colour per knob,\n"
    "                         the Pareto front ringed and joined, the presets labelled\n"
    "  --lightmap-size N      light-map page of the reference and of every row but the density\n"
    "                         rows (8..4096; default 128, 32 with --quick)\n"
    "  --quick                a short sweep for tests and CI: draft, production and draft's two\n"
    "                         encodings at a 32x32 page\n"
    "  --reference-integrator I  reference (default): the path tracer; cook: the cook's own\n"
    "                         integrator at high settings (the former reference; its noise is\n"
    "                         not estimated)\n"
    "  --reference-samples N  path tracer: samples per texel at most (2..1048576; default 4096,\n"
    "                         64 with --quick); its noise falls as 1/sqrt(N), its time grows\n"
    "                         with N\n"
    "  --reference-noise P    path tracer: stop at the first power of two of samples (from 64)\n"
    "                         whose noise is at most P percent relative RMSE (default 0.5; 0 =\n"
    "                         all --reference-samples; off with --quick)\n"
    "  --reference-scale K    --reference-integrator cook: gather rays and area samples K times\n"
    "                         production's (1..16; default 4, 2 with --quick)\n"
    "  --runtime-csv OUT.csv  also the runtime: the encoding rows' bake packed with each\n"
    "                         encoding (auto, linear, square) and recomposed on the CPU reference\n"
    "                         (float32 target; median rebuild time), against the float "
    "composition\n"
    "                         of the same bake's unquantized maps; error, atlas and target bytes\n"
    "  --gles                 with --runtime-csv: also the GLES runtime's RGBA16F target (EGL\n"
    "                         surfaceless; its time is `lightpatch bench`'s)\n"
    "  --maps DIR             also each row's recomposed map (DIR/preset_preview.pfm, ...) and\n"
    "                         the reference (DIR/reference.pfm, .stderr.pfm beside it), in the\n"
    "                         reference's layout, rows from the top as max_error_x/_y count\n"
    "                         them: to see where a row's error lies (existing files replaced)\n"
    "  --no-cache             bake the reference again (the cache file is rewritten)\n"
    "  --seed N               random seed of the sweep's bakes (the reference uses N + 7919)\n"
    "  --threads N            worker threads (default: all cores)\n"
    "  -q, --quiet            no progress on stderr, no table on stdout\n";

const Verb kVerbs[] = {
    {"cook", lightpatch::tool::verb_cook,
     "cook SCENE -o OUT.lpk [--lightmap-size N] [--texels-per-unit F] "
     "[--quality draft|preview|production] [--report REPORT.json] [--no-indirect] [--no-plan] "
     "[--measure-plan] [--write-gltf OUT.glb] [--unwrap auto|always|never] [--integrator gather] "
     "[--gather-rays N] [--indirect-scale K] [--denoise N] [--contact-texels] [--area-samples N] "
     "[--texel-samples N] "
     "[--output-step E] [--no-probes] [--probe-spacing M] [--probe-rays N] [--panes N] "
     "[--anchors M] [--pane-level L] [--max-patch-level L] [--level-tolerance S] "
     "[--bounce-tolerance S] [--seed N] [--threads N] [--quiet]",
     kCookHelp},
    {"plan", lightpatch::tool::verb_plan, "plan SCENE -o DIR [cook's options]", kPlanHelp},
    {"cook-job", lightpatch::tool::verb_cook_job,
     "cook-job DIR JOB [JOB...] [--threads N] [--report REPORT.json] [--quiet]", kCookJobHelp},
    {"jobs", lightpatch::tool::verb_jobs, "jobs DIR [--pending]", kJobsHelp},
    {"assemble", lightpatch::tool::verb_assemble,
     "assemble DIR -o OUT.lpk [--threads N] [--report REPORT.json] [--quiet]", kAssembleHelp},
    {"bake-state", lightpatch::tool::verb_bake_state,
     "bake-state SCENE [--state STATE.json] -o MAP.pfm [--integrator gather|reference] "
     "[--samples N] [--std-error ERR.pfm] [--moving-direct] [cook's options]",
     kBakeStateHelp},
    {"info", lightpatch::tool::verb_info, "info PACK [--json]",
     "Prints a pack's lights, objects, groups, patches, atlases, bytes and packing waste.\n\n"
     "options:\n  --json   machine-readable output\n"},
    {"verify", lightpatch::tool::verb_verify, "verify PACK",
     "Checks a pack's header, sections, records and ranges as the runtime's loader does;\n"
     "exit 0 when the runtime would accept it, 1 with the reason when not.\n"},
    {"recompose", lightpatch::tool::verb_recompose,
     "recompose PACK [--state STATE.json | --states STATES.jsonl] [--backend cpu|gles] -o MAP.pfm",
     "Recomposes a scene state from a pack and writes the light map (linear float PFM).\n\n"
     "options:\n"
     "  -o, --output MAP.pfm   the light map\n"
     "  --state STATE.json     one state (default: as authored)\n"
     "  --states STATES.jsonl  states applied in order through the incremental path; the map\n"
     "                         after the last is written\n"
     "  --backend cpu|gles     CPU reference (default) or OpenGL ES 3 through EGL surfaceless\n"},
    {"preview", lightpatch::tool::verb_preview,
     "preview PACK [--state STATE.json] -o OUT.png [--view lightmap|atlases|charts|checker] "
     "[--exposure E] [--zoom N]",
     kPreviewHelp},
    {"bench", lightpatch::tool::verb_bench, "bench PACK [--json]",
     "Times the GLES recomposition of a pack (full rebuild, single changes) against a fill-rate\n"
     "floor measured in the same run, and lists the GPU memory it holds.\n\n"
     "options:\n  --json   machine-readable output\n"},
    {"accuracy", lightpatch::tool::verb_accuracy,
     "accuracy SCENE --csv OUT.csv --plot OUT.png [--runtime-csv OUT.csv [--gles]] "
     "[--lightmap-size N] [--quick] [--reference-integrator reference|cook] "
     "[--reference-samples N] [--reference-noise P] [--reference-scale K] [--maps DIR] "
     "[--no-cache] "
     "[--seed N] "
     "[--threads N] "
     "[--quiet]",
     kAccuracyHelp},
};

void usage(FILE* out) {
  std::fprintf(out, "usage: lightpatch VERB ...\n\nverbs:\n");
  for (const Verb& v : kVerbs) std::fprintf(out, "  lightpatch %s\n", v.usage);
  std::fprintf(out, "\n`lightpatch VERB --help` lists a verb's options.\n");
}

}  // namespace

int main(int argc, char** argv) {
  // Interrupted or killed politely, the tool leaves no temporary file behind (io.h).
  lightpatch::cooker::install_temporary_cleanup();
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    usage(argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  lightpatch::tool::Args args;
  args.verb = argv[1];
  for (int i = 2; i < argc; ++i) args.items.emplace_back(argv[i]);
  for (const Verb& v : kVerbs) {
    if (args.verb != v.name) continue;
    for (const std::string& item : args.items) {
      if (item == "--help" || item == "-h") {
        std::printf("usage: lightpatch %s\n\n%s", v.usage, v.help);
        if (v.run == lightpatch::tool::verb_cook || v.run == lightpatch::tool::verb_bake_state ||
            v.run == lightpatch::tool::verb_plan) {
          std::printf("%s", kCookOptionsHelp);
        }
        std::printf("\nlimits (README, \"Limits\"):\n");
        // A job folder's verbs import with the limits plan recorded and read no pack.
        const bool imports =
            v.run == lightpatch::tool::verb_cook || v.run == lightpatch::tool::verb_bake_state ||
            v.run == lightpatch::tool::verb_accuracy || v.run == lightpatch::tool::verb_plan;
        const bool job_folder = v.run == lightpatch::tool::verb_cook_job ||
                                v.run == lightpatch::tool::verb_jobs ||
                                v.run == lightpatch::tool::verb_assemble;
        if (imports) {
          std::printf("%s", lightpatch::tool::kImportLimitsHelp);
        } else if (!job_folder) {
          std::printf("%s", lightpatch::tool::kRecomposeLimitsHelp);
        }
        std::printf("%s", lightpatch::tool::kInputSizeHelp);
        return 0;
      }
    }
    try {
      lightpatch::tool::apply_input_size_option(args);
      return v.run(args);
    } catch (const lightpatch::tool::ArgsError& e) {
      std::fprintf(stderr, "lightpatch %s: %s\nusage: lightpatch %s\n", v.name, e.what(), v.usage);
      return 2;
    } catch (const lightpatch::cooker::CookError& e) {
      std::fprintf(stderr, "lightpatch %s: error: %s\n", v.name, e.what());
      return 1;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "lightpatch %s: error: %s\n", v.name, e.what());
      return 1;
    }
  }
  std::fprintf(stderr, "lightpatch: unknown verb '%s'\n", args.verb.c_str());
  usage(stderr);
  return 2;
}
