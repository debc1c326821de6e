#include "lightpatch/cooker/cook_jobs.h"

#include <elf.h>
#include <link.h>

#include <cstring>
#include <fstream>

#include "bake/session.h"
#include "farm/content_hash.h"
#include "farm/group_inputs.h"
#include "lightpatch/cooker/error.h"

namespace lightpatch::cooker {

namespace {

// The NT_GNU_BUILD_ID note of the main program, as hex; empty when it has none.
std::string gnu_build_id() {
  std::string id;
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void* out) -> int {
        // The first object is the main program.
        for (int i = 0; i < info->dlpi_phnum; ++i) {
          const ElfW(Phdr)& ph = info->dlpi_phdr[i];
          if (ph.p_type != PT_NOTE) continue;
          const auto* p = reinterpret_cast<const uint8_t*>(info->dlpi_addr + ph.p_vaddr);
          size_t at = 0;
          while (at + sizeof(ElfW(Nhdr)) <= ph.p_memsz) {
            ElfW(Nhdr) n;
            std::memcpy(&n, p + at, sizeof n);
            const size_t name_at = at + sizeof n;
            const size_t desc_at = name_at + ((n.n_namesz + 3) & ~size_t(3));
            const size_t next = desc_at + ((n.n_descsz + 3) & ~size_t(3));
            if (next > ph.p_memsz) break;
            if (n.n_type == NT_GNU_BUILD_ID && n.n_namesz == 4 &&
                std::memcmp(p + name_at, "GNU", 4) == 0) {
              *static_cast<std::string*>(out) = hex(p + desc_at, n.n_descsz);
              return 1;
            }
            at = next;
          }
        }
        return 1;
      },
      &id);
  return id;
}

std::string executable_digest() {
  std::ifstream in("/proc/self/exe", std::ios::binary);
  if (!in) return {};
  ContentHash h;
  std::vector<char> buf(1 << 20);
  while (in) {
    in.read(buf.data(), std::streamsize(buf.size()));
    h.bytes(buf.data(), size_t(in.gcount()));
  }
  const Digest d = h.finish();
  return hex(d.data(), d.size());
}

}  // namespace

std::string JobHash::hex() const {
  return cooker::hex(bytes.data(), bytes.size());
}

const std::string& tool_identity() {
  static const std::string id = [] {
    std::string s = gnu_build_id();
    if (!s.empty()) return "build-id " + s;
    s = executable_digest();
    if (!s.empty()) return "sha256 " + s;
    throw CookError(
        "cannot identify this build of lightpatch (no build id, executable unreadable)");
  }();
  return id;
}

CookJobs::CookJobs(const PreparedScene& p, const BakeOptions& bake, Progress& progress,
                   Report& report, GatherStore* store)
    : p_(p), bake_(bake) {
  session_ = std::make_unique<BakeSession>(p.scene, p.layout, p.texels, *p.tracer, bake, progress,
                                           report, store);
}

size_t CookJobs::size() const {
  return session_->plan().groups.size();
}

const std::vector<CookJob>& CookJobs::jobs() const {
  std::call_once(hashed_, [&] {
    const BakePlan& plan = session_->plan();
    const JobDigests digests = job_input_digests(p_, session_->impl().ctx, plan, tool_identity());
    if (digests.has_gather) {
      has_gather_ = true;
      gather_.label = "gather rays";
      gather_.gather = true;
      std::memcpy(gather_.hash.bytes.data(), digests.gather.data(), gather_.hash.bytes.size());
      gather_.name = "gather-" + gather_.hash.hex();
    }
    for (size_t g = 0; g < plan.groups.size(); ++g) {
      CookJob j;
      j.group = g;
      j.label = plan.groups[g].name;
      std::memcpy(j.hash.bytes.data(), digests.groups[g].data(), j.hash.bytes.size());
      char prefix[32];
      std::snprintf(prefix, sizeof prefix, "g%03zu-", g);
      j.name = prefix + j.hash.hex();
      jobs_.push_back(std::move(j));
    }
  });
  return jobs_;
}

CookJobs::~CookJobs() = default;

const CookJob* CookJobs::gather() const {
  jobs();
  return has_gather_ ? &gather_ : nullptr;
}

size_t CookJobs::find(const std::string& name) const {
  for (size_t i = 0; i < jobs().size(); ++i)
    if (jobs_[i].name == name) return i;
  throw CookError("no job '" + name + "' in this cook's plan");
}

size_t CookJobs::max_maps(size_t i) const {
  const LightGroup& lg = session_->plan().groups.at(i);
  const size_t c = lg.candidates.size();
  return 1 + c + lg.bounce_only.size() + c * (c - (c > 0 ? 1 : 0)) / 2;
}

GroupBake CookJobs::run(size_t i, Progress& progress, Report& report) const {
  return session_->bake_group(i, progress, report);
}

std::vector<GroupBake> CookJobs::run(const std::vector<size_t>& jobs, Progress& progress,
                                     Report& report) const {
  return session_->bake_groups(jobs, progress, report);
}

std::vector<uint8_t> CookJobs::assemble(std::vector<GroupBake> results, Progress& progress,
                                        Report& report, BakedMaps* maps_out) const {
  BakedMaps maps = session_->assemble(std::move(results), report);
  session_->bake_panes(maps, progress, report);
  finalize_maps(maps, p_, progress, report);
  const ProbeBake probes = cook_probes(p_, maps, bake_, progress, report);
  progress.begin("pack", 1);
  std::vector<uint8_t> pack =
      build_pack(p_.scene, p_.layout, maps, pack_options(bake_), report, &probes);
  report.stage_time("pack", progress.end());
  if (maps_out) *maps_out = std::move(maps);
  return pack;
}

}  // namespace lightpatch::cooker
