#include "lightpatch/cooker/job_dir.h"

#include <filesystem>
#include <fstream>
#include <mutex>

#include "farm/gather_file.h"
#include "indirect/integrator.h"
#include "lightpatch/cooker/cook.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/group_file.h"
#include "lightpatch/cooker/io.h"
#include "lightpatch/cooker/pack_builder.h"
#include "lightpatch/pack_format.h"

namespace lightpatch::cooker {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kManifestFormat = "lightpatch-cook-plan";
constexpr const char* kJobFormat = "lightpatch-cook-job";
constexpr const char* kGatherPrefix = "gather-";

bool is_gather(const std::string& name) {
  return name.rfind(kGatherPrefix, 0) == 0;
}

std::string manifest_path(const std::string& dir) {
  return (fs::path(dir) / "manifest.json").string();
}
std::string job_path(const std::string& dir, const std::string& name) {
  return (fs::path(dir) / "jobs" / (name + ".json")).string();
}
std::string result_path(const std::string& dir, const std::string& name) {
  return (fs::path(dir) / "results" / (name + (is_gather(name) ? ".gather" : ".lpg"))).string();
}

// A job name as plan makes them: "g" and digits, or "gather", then "-" and 32 hex digits.
// Anything else (a path, a typo) is refused before it names a file.
void check_name(const std::string& name) {
  const size_t dash = name.find('-');
  bool ok = dash != std::string::npos && name.size() - dash - 1 == 32 && name[0] == 'g';
  if (ok && !is_gather(name)) {
    ok = dash > 1;
    for (size_t i = 1; ok && i < dash; ++i) ok = name[i] >= '0' && name[i] <= '9';
  }
  for (size_t i = dash + 1; ok && i < name.size(); ++i)
    ok = (name[i] >= '0' && name[i] <= '9') || (name[i] >= 'a' && name[i] <= 'f');
  if (!ok)
    throw CookError("'" + name +
                    "' is not a job name (g<group>-<32 hex digits> or gather-<32 hex digits>)");
}

JobHash hash_of(const std::string& name) {
  JobHash h;
  const std::string hex = name.substr(name.size() - 32);
  for (size_t i = 0; i < 16; ++i)
    h.bytes[i] = uint8_t(std::stoi(hex.substr(2 * i, 2), nullptr, 16));
  return h;
}

// Every option is stored (threads aside): an option added to these structs must be added here and
// to settings_from_json, or a job would run with its default. (Sizes on 64-bit Linux.)
static_assert(sizeof(LayoutOptions) == 28, "LayoutOptions changed: update job_dir.cpp");
static_assert(sizeof(BakeOptions) == 112, "BakeOptions changed: update job_dir.cpp");
static_assert(sizeof(ImportLimits) == 48, "ImportLimits changed: update job_dir.cpp");

json settings_json(const CookSettings& s) {
  const BakeOptions& b = s.bake;
  return {{"scene", s.scene_path},
          {"lightmap_size", s.layout.lightmap_size},
          {"texels_per_unit", s.layout.texels_per_unit},
          {"border_texels", s.layout.border_texels},
          {"max_lightmap_size", s.layout.max_lightmap_size},
          {"align", s.layout.align},
          {"align_required", s.layout.align_required},
          {"unwrap", s.layout.unwrap == UnwrapMode::kAlways  ? "always"
                     : s.layout.unwrap == UnwrapMode::kNever ? "never"
                                                             : "auto"},
          {"quality", quality_name(b.quality)},
          {"area_samples", b.area_samples},
          {"texel_samples", b.texel_samples},
          {"seed", b.seed},
          {"indirect", b.indirect},
          {"integrator", integrator_name(b.integrator)},
          {"gather_rays", b.gather_rays},
          {"indirect_scale", b.indirect_scale},
          {"denoise", b.denoise},
          {"contact_texels", b.contact_texels},
          {"plan_effects", b.plan_effects},
          {"output_step", b.output_step},
          {"probes", b.probes.enabled},
          {"probe_spacing", b.probes.spacing},
          {"probe_rays", b.probes.rays},
          {"panes", b.panes},
          {"pane_level", b.pane_level},
          {"anchor_spacing", b.anchor_spacing},
          {"max_patch_level", b.max_patch_level},
          {"level_tolerance", b.level_tolerance},
          {"bounce_tolerance", b.bounce_tolerance},
          {"moving_direct", b.moving_direct},
          {"max_triangles", s.import.max_triangles},
          {"max_vertices", s.import.max_vertices},
          {"max_texture_pixels", s.import.max_texture_pixels},
          {"uri_roots", s.import.uri_roots}};
}

template <typename T>
T field(const json& j, const char* key, const std::string& file) {
  if (!j.contains(key)) throw CookError(file + ": no \"" + key + "\"");
  try {
    return j.at(key).get<T>();
  } catch (const json::exception&) {
    throw CookError(file + ": \"" + key + "\" has the wrong type");
  }
}

int int_field(const json& j, const char* key, int lo, int hi, const std::string& file) {
  const int64_t v = field<int64_t>(j, key, file);
  if (v < lo || v > hi)
    throw CookError(file + ": \"" + key + "\" out of range [" + std::to_string(lo) + ", " +
                    std::to_string(hi) + "]");
  return int(v);
}

CookSettings settings_from_json(const json& j, const std::string& file) {
  if (!j.is_object()) throw CookError(file + ": settings are not an object");
  CookSettings s;
  s.scene_path = field<std::string>(j, "scene", file);
  s.layout.lightmap_size = int_field(j, "lightmap_size", 0, 16384, file);
  s.layout.texels_per_unit = field<float>(j, "texels_per_unit", file);
  if (!(s.layout.texels_per_unit >= 0.0f && s.layout.texels_per_unit <= 1e6f))
    throw CookError(file + ": \"texels_per_unit\" out of range");
  s.layout.border_texels = int_field(j, "border_texels", 0, 64, file);
  s.layout.max_lightmap_size = int_field(j, "max_lightmap_size", 8, 16384, file);
  s.layout.align = int_field(j, "align", 1, 8, file);  // unwrap checks it is 1, 2, 4 or 8
  s.layout.align_required = field<bool>(j, "align_required", file);
  const std::string unwrap = field<std::string>(j, "unwrap", file);
  if (unwrap == "auto")
    s.layout.unwrap = UnwrapMode::kAuto;
  else if (unwrap == "always")
    s.layout.unwrap = UnwrapMode::kAlways;
  else if (unwrap == "never")
    s.layout.unwrap = UnwrapMode::kNever;
  else
    throw CookError(file + ": \"unwrap\" is not auto, always or never");
  s.bake.quality = parse_quality(field<std::string>(j, "quality", file));
  s.bake.area_samples = int_field(j, "area_samples", 0, 65536, file);
  s.bake.texel_samples = int_field(j, "texel_samples", 0, 256, file);
  s.bake.seed = field<uint64_t>(j, "seed", file);
  s.bake.indirect = field<bool>(j, "indirect", file);
  s.bake.integrator = parse_integrator(field<std::string>(j, "integrator", file));
  s.bake.gather_rays = int_field(j, "gather_rays", 0, 65536, file);
  s.bake.indirect_scale = int_field(j, "indirect_scale", 0, 8, file);
  s.bake.denoise = int_field(j, "denoise", -1, 3, file);
  s.bake.contact_texels = field<bool>(j, "contact_texels", file);
  s.bake.plan_effects = field<bool>(j, "plan_effects", file);
  s.bake.output_step = field<float>(j, "output_step", file);
  if (!(s.bake.output_step >= 0.0f && s.bake.output_step <= 1e30f))
    throw CookError(file + ": \"output_step\" out of range");
  s.bake.probes.enabled = field<bool>(j, "probes", file);
  s.bake.probes.spacing = field<float>(j, "probe_spacing", file);
  if (!(s.bake.probes.spacing >= 0.0f && s.bake.probes.spacing <= 1e30f))
    throw CookError(file + ": \"probe_spacing\" out of range");
  s.bake.probes.rays = int_field(j, "probe_rays", 0, 1 << 20, file);
  s.bake.panes = int_field(j, "panes", 0, kMaxPaneOption, file);
  s.bake.pane_level = int_field(j, "pane_level", -1, int(pack::kMaxPatchLevel), file);
  s.bake.anchor_spacing = field<float>(j, "anchor_spacing", file);
  if (!(s.bake.anchor_spacing == 0.0f ||
        (s.bake.anchor_spacing >= kMinAnchorSpacing && s.bake.anchor_spacing <= 1e6f)))
    throw CookError(file + ": \"anchor_spacing\" out of range");
  s.bake.max_patch_level = int_field(j, "max_patch_level", -1, int(pack::kMaxPatchLevel), file);
  s.bake.level_tolerance = field<float>(j, "level_tolerance", file);
  if (!(s.bake.level_tolerance <= kMaxLevelTolerance))  // <= 0 (or -0): the default
    throw CookError(file + ": \"level_tolerance\" out of range");
  s.bake.bounce_tolerance = field<float>(j, "bounce_tolerance", file);
  if (!(s.bake.bounce_tolerance <= kMaxLevelTolerance))  // <= 0 (or -0): the default
    throw CookError(file + ": \"bounce_tolerance\" out of range");
  s.bake.moving_direct = field<bool>(j, "moving_direct", file);
  s.import.max_triangles = field<uint64_t>(j, "max_triangles", file);
  s.import.max_vertices = field<uint64_t>(j, "max_vertices", file);
  s.import.max_texture_pixels = field<uint64_t>(j, "max_texture_pixels", file);
  s.import.uri_roots = field<std::vector<std::string>>(j, "uri_roots", file);
  return s;
}

json read_json(const std::string& path, const char* format) {
  const std::vector<uint8_t> bytes = read_file(path);
  json j = json::parse(bytes.begin(), bytes.end(), nullptr, false);
  if (j.is_discarded() || !j.is_object()) throw CookError(path + ": not a JSON object");
  if (field<std::string>(j, "format", path) != format)
    throw CookError(path + ": not a " + std::string(format) + " file");
  const int version = int_field(j, "version", 0, 1 << 30, path);
  if (version != kJobDirVersion)
    throw CookError(path + ": version " + std::to_string(version) + ", this lightpatch reads " +
                    std::to_string(kJobDirVersion));
  return j;
}

void write_json(const std::string& path, const json& j) {
  const std::string text = j.dump(2) + "\n";
  write_file_atomic(path, text.data(), text.size());
}

json job_json(const CookJob& job) {
  json j = {{"name", job.name},
            {"kind", job.gather ? "gather" : "group"},
            {"label", job.label},
            {"hash", job.hash.hex()}};
  if (!job.gather) j["group"] = job.group;
  return j;
}

void check_tool(const json& j, const std::string& file) {
  const std::string planned = field<std::string>(j, "tool", file);
  if (planned != tool_identity())
    throw CookError(file + " was planned by another build of lightpatch (" + planned +
                    "; this is " + tool_identity() +
                    "): another build may give other bytes; plan again with this one");
}

// Whether `dir` holds a valid result for `job`; `problem` says why not. `check_body`: its
// checksum too (reads the whole file), else its header and size.
bool result_ok(const std::string& dir, const CookJob& job, bool check_body, std::string* problem) {
  const std::string path = result_path(dir, job.name);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    *problem = "missing";
    return false;
  }
  try {
    std::vector<uint8_t> bytes;
    size_t size = 0;
    if (check_body) {
      bytes = read_file(path);
      size = bytes.size();
    } else {
      size = size_t(fs::file_size(path, ec));
      if (ec) throw CookError("cannot read its size: " + ec.message());
      std::ifstream in(path, std::ios::binary);
      bytes.resize(std::min<size_t>(size, 64));
      if (!in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(bytes.size())))
        throw CookError("cannot read its header");
    }
    const std::array<uint8_t, 16> hash = job.gather
                                             ? gather_file_hash(bytes.data(), size, check_body)
                                             : group_file_hash(bytes.data(), size, check_body);
    if (hash != job.hash.bytes) {
      *problem = "holds another job's result";
      return false;
    }
  } catch (const CookError& e) {
    *problem = e.what();
    return false;
  }
  return true;
}

struct Plan {
  CookSettings settings;
  std::vector<CookJob> jobs;  // the gather rays first, when there
};

Plan read_manifest(const std::string& dir) {
  const std::string path = manifest_path(dir);
  const json j = read_json(path, kManifestFormat);
  Plan p;
  check_tool(j, path);
  p.settings = settings_from_json(j.value("settings", json()), path);
  const json& jobs = j.value("jobs", json());
  if (!jobs.is_array()) throw CookError(path + ": \"jobs\" is not a list");
  for (const json& e : jobs) {
    CookJob job;
    job.name = field<std::string>(e, "name", path);
    check_name(job.name);
    job.gather = is_gather(job.name);
    if (!job.gather) job.group = size_t(int_field(e, "group", 0, 1 << 30, path));
    job.label = field<std::string>(e, "label", path);
    if (job.name.substr(job.name.size() - 32) != field<std::string>(e, "hash", path))
      throw CookError(path + ": job " + job.name + " has another hash");
    job.hash = hash_of(job.name);
    p.jobs.push_back(std::move(job));
  }
  return p;
}

// The gather rays in the job folder: loaded by every light-group job whose plan has them,
// written only by the gather job.
class DirGatherStore final : public GatherStore {
 public:
  DirGatherStore(std::string dir, bool write) : dir_(std::move(dir)), write_(write) {}
  void bind(const CookJob* job, const PreparedScene& p, const BakeOptions& bake) {
    job_ = job;
    expect_.texels = p.texels.position.size();
    expect_.objects = p.scene.objects.size();
    const GatherPreset gp = gather_preset(bake);
    expect_.rays = gp.rays;
    expect_.level = gp.level;
    if (job) expect_.job_hash = job->hash.bytes;
  }
  bool load(GatherOperator& op, Progress& progress) override {
    if (!job_ || write_) return false;
    const std::string path = result_path(dir_, job_->name);
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) return false;
    try {
      const std::vector<uint8_t> bytes = read_file(path);
      op = decode_gather(bytes.data(), bytes.size(), expect_);
      return true;
    } catch (const CookError& e) {
      progress.message("note: " + path + " not used (" + e.what() + "); tracing the rays here");
      return false;
    }
  }
  void save(const GatherOperator& op, Progress& progress) override {
    if (!job_ || !write_) return;
    const std::vector<uint8_t> bytes = encode_gather(op, job_->hash.bytes);
    write_file_atomic(result_path(dir_, job_->name), bytes.data(), bytes.size());
    progress.message(job_->name + ": wrote the gather rays (" + std::to_string(bytes.size()) +
                     " bytes)");
  }

 private:
  std::string dir_;
  bool write_;
  const CookJob* job_ = nullptr;
  GatherFileExpect expect_;
};

// The scene prepared and planned again, as the job files say. (The jobs keep references into
// the scene and the store: all live on the heap.)
struct Replanned {
  std::unique_ptr<PreparedScene> scene;
  std::unique_ptr<DirGatherStore> store;
  std::unique_ptr<CookJobs> jobs;
  // The plan's jobs as the manifest lists them: the gather rays first, then the groups.
  std::vector<CookJob> all() const {
    std::vector<CookJob> out;
    if (jobs->gather()) out.push_back(*jobs->gather());
    out.insert(out.end(), jobs->jobs().begin(), jobs->jobs().end());
    return out;
  }
};

Replanned replan(const std::string& dir, const CookSettings& s, int threads, bool write_gather,
                 Progress& progress, Report& report) {
  Replanned r;
  r.scene = std::make_unique<PreparedScene>(
      prepare_scene(s.scene_path, s.layout, progress, report, s.import));
  BakeOptions bake = s.bake;
  bake.threads = threads;
  r.store = std::make_unique<DirGatherStore>(dir, write_gather);
  r.jobs = std::make_unique<CookJobs>(*r.scene, bake, progress, report, r.store.get());
  r.store->bind(r.jobs->gather(), *r.scene, bake);
  return r;
}

std::string stale_message(const std::string& name) {
  return "job " + name +
         " no longer matches the scene and options it was planned for (the scene or a file it "
         "reads changed since plan): run plan again";
}

}  // namespace

PlannedJobs plan_job_dir(const std::string& dir, const CookSettings& settings, Progress& progress,
                         Report& report) {
  CookSettings s = settings;
  s.scene_path = fs::absolute(s.scene_path).lexically_normal().string();
  // The folder only once the scene has imported and planned: a bad scene leaves nothing behind.
  const Replanned r = replan(dir, s, s.bake.threads, false, progress, report);
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "jobs", ec);
  if (!ec) fs::create_directories(fs::path(dir) / "results", ec);
  if (ec) throw CookError("cannot create the job folder '" + dir + "': " + ec.message());
  const std::vector<CookJob> jobs = r.all();
  const json settings_j = settings_json(s);
  json list = json::array();
  for (const CookJob& job : jobs) {
    json j = {{"format", kJobFormat},
              {"version", kJobDirVersion},
              {"tool", tool_identity()},
              {"settings", settings_j}};
    j.update(job_json(job));
    write_json(job_path(dir, job.name), j);
    list.push_back(job_json(job));
  }
  write_json(manifest_path(dir), {{"format", kManifestFormat},
                                  {"version", kJobDirVersion},
                                  {"tool", tool_identity()},
                                  {"settings", settings_j},
                                  {"output_step", r.jobs->session().output_step()},
                                  {"jobs", list}});
  return {jobs, r.jobs->session().output_step()};
}

std::vector<JobState> job_dir_state(const std::string& dir) {
  const Plan plan = read_manifest(dir);
  std::vector<JobState> out;
  for (const CookJob& job : plan.jobs) {
    JobState s;
    s.job = job;
    s.done = result_ok(dir, job, true, &s.problem);
    out.push_back(std::move(s));
  }
  return out;
}

std::vector<bool> run_jobs(const std::string& dir, const std::vector<std::string>& names,
                           int threads, Progress& progress, Report& report) {
  json first;
  std::vector<bool> baked(names.size(), false);
  bool any = false, gather = false;
  for (size_t k = 0; k < names.size(); ++k) {
    check_name(names[k]);
    const std::string path = job_path(dir, names[k]);
    const json j = read_json(path, kJobFormat);
    if (field<std::string>(j, "name", path) != names[k])
      throw CookError(path + ": holds job " + field<std::string>(j, "name", path));
    const CookSettings s = settings_from_json(j.value("settings", json()), path);
    if (k == 0) first = settings_json(s);
    if (settings_json(s) != first)
      throw CookError("jobs " + names[0] + " and " + names[k] + " come from different plans");
    CookJob job;
    job.name = names[k];
    job.gather = is_gather(names[k]);
    job.hash = hash_of(names[k]);
    std::string problem;
    baked[k] = !result_ok(dir, job, true, &problem);
    if (baked[k]) {
      check_tool(j, path);
      any = true;
      gather = gather || job.gather;
    } else {
      progress.message(names[k] + ": result present, nothing to do");
    }
  }
  if (!any) return baked;
  // A gather job writes the rays it traces; the light groups in the same call use them.
  const Replanned r =
      replan(dir, settings_from_json(first, "job"), threads, gather, progress, report);
  for (size_t k = 0; k < names.size(); ++k) {
    if (!baked[k] || !is_gather(names[k])) continue;
    if (!r.jobs->gather() || r.jobs->gather()->name != names[k])
      throw CookError(stale_message(names[k]));
    r.jobs->session().trace_shared(progress, report);
  }
  for (size_t k = 0; k < names.size(); ++k) {
    if (!baked[k] || is_gather(names[k])) continue;
    size_t i = 0;
    try {
      i = r.jobs->find(names[k]);
    } catch (const CookError&) {
      throw CookError(stale_message(names[k]));
    }
    const GroupBake g = r.jobs->run(i, progress, report);
    const std::vector<uint8_t> bytes = encode_group(g, r.jobs->jobs()[i].hash.bytes);
    write_file_atomic(result_path(dir, names[k]), bytes.data(), bytes.size());
    progress.message(names[k] + ": baked " + r.jobs->jobs()[i].label + " (" +
                     std::to_string(bytes.size()) + " bytes)");
  }
  return baked;
}

std::vector<uint8_t> assemble_job_dir(const std::string& dir, int threads, Progress& progress,
                                      Report& report) {
  const Plan plan = read_manifest(dir);
  std::string problems;
  int bad = 0, groups = 0;
  for (const CookJob& job : plan.jobs) {
    if (job.gather) continue;  // the light groups' input, not the pack's
    ++groups;
    std::string problem;
    if (result_ok(dir, job, false, &problem)) continue;
    problems += "\n  " + job.name + " (" + job.label + "): " + problem;
    ++bad;
  }
  if (bad > 0)
    throw CookError(std::to_string(bad) + " of " + std::to_string(groups) +
                    " light-group jobs have no valid result in '" + dir + "':" + problems);
  const Replanned r = replan(dir, plan.settings, threads, false, progress, report);
  const std::vector<CookJob> all = r.all();
  bool same = all.size() == plan.jobs.size();
  for (size_t i = 0; same && i < all.size(); ++i) same = all[i].name == plan.jobs[i].name;
  if (!same)
    throw CookError("the scene or a file it reads changed since plan ('" +
                    plan.settings.scene_path + "'): run plan again");
  const std::vector<CookJob>& jobs = r.jobs->jobs();
  progress.begin("read results", jobs.size());
  std::vector<GroupBake> results;
  const Layout& layout = r.scene->layout;
  for (size_t i = 0; i < jobs.size(); ++i) {
    const std::string path = result_path(dir, jobs[i].name);
    const std::vector<uint8_t> bytes = read_file(path);
    GroupFileExpect e;
    e.job_hash = jobs[i].hash.bytes;
    e.group = jobs[i].group;
    e.width = layout.width;
    e.height = layout.height;
    if (layout.align > 1) {
      e.indirect_width = layout.width / layout.align;
      e.indirect_height = layout.height / layout.align;
    }
    e.objects = r.scene->scene.objects.size();
    e.lights = r.scene->scene.lights.size();
    e.max_maps = r.jobs->max_maps(i);
    try {
      results.push_back(decode_group(bytes.data(), bytes.size(), e));
    } catch (const CookError& err) {
      throw CookError(path + ": " + err.what());
    }
    progress.advance();
  }
  report.stage_time("read results", progress.end());
  return r.jobs->assemble(std::move(results), progress, report);
}

}  // namespace lightpatch::cooker
