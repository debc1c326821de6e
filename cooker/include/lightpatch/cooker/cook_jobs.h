// A cook as jobs: one job per light group of the bake plan (bake_plan.h; job 0 the static lights
// with the base map and static shadows, then one per semi-dynamic light with its contribution,
// shadow and pair-correction maps), each named by a content hash of everything that determines
// its output, and an assembly that finalizes every job's maps and packs them. `lightpatch cook`
// runs the jobs in-process (cook_pack, cook.h); `plan`, `cook-job` and `assemble` run them as
// separate processes through a job folder (job_dir.h); the pack is the same bytes either way.
//
// A job's hash covers what its group reads, so an edit re-runs only the jobs it can change:
// the build of the tool (its GNU build id), the bake options (not the thread count), the light
// map's size and the scene's scale, the output step (rounded to a quarter octave, context.cpp),
// the static geometry and emissive surfaces, and then per group: its light (for the static
// group every static light, colour included; for a semi-dynamic light its position, direction,
// cone, range and radius, and its significance, which is where its colour and intensity enter),
// the objects that can block it (their geometry), and the texels it can light (those of the
// layout regions within its reach). With bounce light on, a group also reads the gather
// operator, which every texel and every object's geometry shapes: moving an object then re-runs
// every group (it receives and changes the bounce light of every light); with --no-indirect only
// the groups whose light reaches it.
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/bake_plan.h"
#include "lightpatch/cooker/cook.h"
#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/progress.h"
#include "lightpatch/cooker/report.h"

namespace lightpatch::cooker {

// 128 bits: the first half of a SHA-256 digest of the job's inputs.
struct JobHash {
  std::array<uint8_t, 16> bytes{};
  std::string hex() const;  // 32 lowercase hex digits
  bool operator==(const JobHash&) const = default;
};

// The build of the running program: its GNU build id (a digest the linker writes), or, without
// one, the SHA-256 of the executable. Part of every job's hash: another build may round
// differently, and then its maps are not the same bytes.
const std::string& tool_identity();

struct CookJob {
  size_t group = 0;   // BakePlan::groups index (a light group's job)
  std::string label;  // "static lights", the light's name, or "gather rays"
  JobHash hash;
  // "g<group>-<hash hex>" for a light group, "gather-<hash hex>" for the gather rays: the name
  // of the job's files.
  std::string name;
  bool gather = false;  // the gather rays the light groups share (bounce light on)
};

// A prepared scene's cook as jobs. Planning traces nothing; the first run() traces the gather
// rays the groups share (once per CookJobs). Job i bakes light group i. Hashing the jobs' inputs
// reads every texel, so it happens on the first call of jobs() or find() (`cook` never calls
// them).
class CookJobs {
 public:
  // `p` must outlive this. Plan decisions go into `report`. `store` (may be null) keeps traced
  // gather rays between processes (job_dir.cpp).
  CookJobs(const PreparedScene& p, const BakeOptions& bake, Progress& progress, Report& report,
           GatherStore* store = nullptr);
  ~CookJobs();
  CookJobs(const CookJobs&) = delete;
  CookJobs& operator=(const CookJobs&) = delete;

  size_t size() const;
  // The light groups' jobs in plan order, which is also an order they may run in (none reads
  // another's result).
  const std::vector<CookJob>& jobs() const;
  // The gather rays as a job of their own (null with bounce light off): its result, when there,
  // saves each light-group job of this scene its own tracing.
  const CookJob* gather() const;
  const BakeSession& session() const { return *session_; }
  // Index in jobs() of the job named `name`; throws CookError when there is none.
  size_t find(const std::string& name) const;
  // The most maps job i's result can hold (group_file.h's reader bound).
  size_t max_maps(size_t i) const;

  GroupBake run(size_t i, Progress& progress, Report& report) const;
  // run() of each of `jobs` (indices, each at most once), in that order, the same results as
  // each run alone, solved side by side (BakeSession::bake_groups): an in-process cook.
  std::vector<GroupBake> run(const std::vector<size_t>& jobs, Progress& progress,
                             Report& report) const;
  // Every job's result (any order, each once) finalized and packed: the pack's bytes.
  // `maps_out`, if not null, receives the finalized maps.
  std::vector<uint8_t> assemble(std::vector<GroupBake> results, Progress& progress, Report& report,
                                BakedMaps* maps_out = nullptr) const;

 private:
  const PreparedScene& p_;
  BakeOptions bake_;
  std::unique_ptr<BakeSession> session_;
  mutable std::once_flag hashed_;
  mutable std::vector<CookJob> jobs_;
  mutable CookJob gather_;
  mutable bool has_gather_ = false;
};

}  // namespace lightpatch::cooker
