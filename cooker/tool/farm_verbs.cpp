// The cook as separate jobs (job_dir.h): `plan` writes a job folder, `cook-job` runs jobs from
// it, `jobs` lists them, `assemble` packs their results. tools/farm/lightpatch-farm runs them on
// Slurm.
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "args.h"
#include "cook_options.h"
#include "lightpatch/cooker/io.h"
#include "lightpatch/cooker/job_dir.h"
#include "lightpatch/cooker/progress.h"
#include "lightpatch/cooker/report.h"
#include "limit_options.h"
#include "verbs.h"

namespace lightpatch::tool {

namespace {

using namespace lightpatch::cooker;

double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

void write_report(const std::string& path, Report& report, double seconds) {
  if (path.empty()) return;
  report.root()["total_seconds"] = seconds;
  report.write(path);
}

// Enough digits to give the same float back (for --output-step).
std::string step_text(float v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", double(v));
  return text;
}

// --threads, --quiet and --report of the verbs that run work.
struct RunOptions {
  int threads = 0;
  bool quiet = false;
  std::string report_path;
};

RunOptions parse_run_options(Args& args) {
  RunOptions o;
  o.threads = args.int_option("--threads", 0, 1, 1024);
  o.quiet = args.flag("--quiet", "-q");
  args.option("--report", &o.report_path);
  if (!o.report_path.empty()) probe_output_folder(o.report_path);
  return o;
}

}  // namespace

int verb_plan(Args& args) {
  CookOptions o = parse_cook_options(args, "DIR");
  o.scene_path = args.positional("SCENE");
  args.finish();
  const auto t0 = std::chrono::steady_clock::now();
  if (!o.report_path.empty()) probe_output_folder(o.report_path);
  Progress progress(o.quiet);
  Report report;
  CookSettings s;
  s.scene_path = o.scene_path;
  s.layout = o.layout;
  s.bake = o.bake;
  s.import = o.import;
  const PlannedJobs planned = plan_job_dir(o.output, s, progress, report);
  const std::vector<CookJob>& jobs = planned.jobs;
  size_t done = 0;
  for (const JobState& j : job_dir_state(o.output)) done += j.done ? 1 : 0;
  for (const CookJob& j : jobs) std::printf("%s\n", j.name.c_str());
  std::fflush(stdout);
  progress.message("planned " + std::to_string(jobs.size()) + " jobs in " + o.output + ": " +
                   std::to_string(done) + " have their result, " +
                   std::to_string(jobs.size() - done) + " to run; output step " +
                   step_text(planned.output_step) +
                   (o.bake.output_step > 0.0f ? " (pinned)" : " (--output-step pins it)"));
  write_report(o.report_path, report, since(t0));
  return 0;
}

int verb_cook_job(Args& args) {
  const RunOptions o = parse_run_options(args);
  const std::string dir = args.positional("DIR");
  std::vector<std::string> names;
  names.push_back(args.positional("JOB"));
  while (!args.items.empty()) names.push_back(args.positional("JOB"));
  args.finish();
  const auto t0 = std::chrono::steady_clock::now();
  Progress progress(o.quiet);
  Report report;
  const std::vector<bool> baked = run_jobs(dir, names, o.threads, progress, report);
  size_t n = 0;
  for (bool b : baked) n += b ? 1 : 0;
  progress.message("baked " + std::to_string(n) + " of " + std::to_string(names.size()) +
                   " jobs in " + std::to_string(since(t0)) + " s");
  write_report(o.report_path, report, since(t0));
  return 0;
}

int verb_jobs(Args& args) {
  const bool pending = args.flag("--pending");
  const std::string dir = args.positional("DIR");
  args.finish();
  size_t done = 0;
  const std::vector<JobState> state = job_dir_state(dir);
  for (const JobState& j : state) {
    done += j.done ? 1 : 0;
    if (!pending || !j.done) std::printf("%s\n", j.job.name.c_str());
  }
  std::fflush(stdout);
  std::fprintf(stderr, "%zu jobs, %zu with their result, %zu to run\n", state.size(), done,
               state.size() - done);
  return 0;
}

int verb_assemble(Args& args) {
  std::string output;
  if (!args.option("-o", &output) && !args.option("--output", &output))
    throw ArgsError("missing -o OUT.lpk");
  if (output.empty()) throw ArgsError("-o needs a file name");
  const RunOptions o = parse_run_options(args);
  const std::string dir = args.positional("DIR");
  args.finish();
  const auto t0 = std::chrono::steady_clock::now();
  probe_output_folder(output);
  Progress progress(o.quiet);
  Report report;
  const std::vector<uint8_t> pack = assemble_job_dir(dir, o.threads, progress, report);
  // The same warning as `cook` gives: the pack is byte for byte the one cook would write.
  if (const std::string w = check_cooked_pack(pack); !w.empty())
    std::fprintf(stderr, "lightpatch assemble: warning: %s\n", w.c_str());
  progress.begin("write", 1);
  write_file_atomic(output, pack.data(), pack.size());
  report.stage_time("write", progress.end());
  progress.message("wrote " + output + " (" + std::to_string(pack.size()) + " bytes) in " +
                   std::to_string(since(t0)) + " s");
  write_report(o.report_path, report, since(t0));
  return 0;
}

}  // namespace lightpatch::tool
