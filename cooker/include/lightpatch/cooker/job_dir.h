// A cook's job folder: what `lightpatch plan` writes and `cook-job`, `jobs` and `assemble` read
// (cook_jobs.h describes the jobs). Every file is written atomically (io.h), and each process
// writes only its own files, so jobs may run anywhere that sees the folder (a shared
// filesystem), in any order, any number at once, and be run again.
//
//   DIR/manifest.json      the plan: format, version, the tool's build, the scene's absolute
//                          path, the settings, and the jobs in an order they may run
//                          ({name, group, label, hash}); rewritten by every plan
//   DIR/jobs/NAME.json     one job: the same scene, settings and build, its group and hash
//   DIR/results/NAME.lpg   a light group's result (group_file.h), written only by its job
//   DIR/results/NAME.gather  the gather rays (farm/gather_file.h), written only by the gather
//                          job; a light-group job loads them when there, else traces its own
//
// A job's NAME is "g<group>-<hash>" or "gather-<hash>", the hash covering everything its output
// depends on: a second plan after an edit gives the jobs it cannot change their old names, whose
// results are reused. The gather job (bounce light on) comes first; no other job reads another's
// result. Results of older plans stay in DIR/results until removed.
#pragma once

#include <string>
#include <vector>

#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/cook_jobs.h"
#include "lightpatch/cooker/import.h"
#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/progress.h"
#include "lightpatch/cooker/report.h"

namespace lightpatch::cooker {

constexpr int kJobDirVersion = 1;

// What a cook's output depends on besides the build of the tool: the scene and the options.
// bake.threads is not part of it (the same bytes on any thread count) and is not stored.
struct CookSettings {
  std::string scene_path;
  LayoutOptions layout;
  BakeOptions bake;
  // Refusals only (no output depends on them), kept so that every job imports what plan did.
  ImportLimits import;
};

// Imports, lays out and plans the cook (no tracing of bounce rays), creates `dir` if needed and
// writes the manifest and the job files. Throws CookError.
struct PlannedJobs {
  std::vector<CookJob> jobs;  // in an order they may run (the gather rays first)
  // The step the jobs were planned with (BakeOptions::output_step pins it for later plans).
  float output_step = 0.0f;
};
PlannedJobs plan_job_dir(const std::string& dir, const CookSettings& settings, Progress& progress,
                         Report& report);

// The manifest's jobs and, for each, whether `dir` holds a valid result for it (its header
// names the job's hash and its checksum holds). Throws CookError if the manifest is unreadable.
struct JobState {
  CookJob job;
  bool done = false;
  std::string problem;  // why not done: "missing", or what is wrong with the file
};
std::vector<JobState> job_dir_state(const std::string& dir);

// Runs the named jobs of `dir` in one process (one import, layout and gather for all): each
// whose result is already there with its hash is skipped; the gather job first, whose rays the
// light groups of the same call then use. Returns, per name, whether it ran.
// Throws CookError when a job file is unreadable, was planned by another build of the tool, or
// no longer matches the scene (the scene or its files changed since plan: plan again).
std::vector<bool> run_jobs(const std::string& dir, const std::vector<std::string>& names,
                           int threads, Progress& progress, Report& report);

// Checks that every light-group job of the manifest has its result (an error names each missing
// or stale one), then finalizes and packs: the pack's bytes, the same as `cook` with the same
// settings.
std::vector<uint8_t> assemble_job_dir(const std::string& dir, int threads, Progress& progress,
                                      Report& report);

}  // namespace lightpatch::cooker
