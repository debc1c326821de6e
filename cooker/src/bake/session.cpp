#include <algorithm>
#include <mutex>

#include "bake/group.h"
#include "bake/plan.h"
#include "bake/session.h"
#include "indirect/integrator.h"
#include "lightpatch/cooker/error.h"

namespace lightpatch::cooker {

namespace {

GatherPreset preset_gather(Quality q) {
  switch (q) {
    case Quality::kDraft:
      return {64, 4, 2};
    case Quality::kPreview:
      return {256, 2, 2};
    case Quality::kProduction:
      return {256, 1, 2};
  }
  return {256, 2, 2};
}

}  // namespace

const char* quality_name(Quality q) {
  switch (q) {
    case Quality::kDraft:
      return "draft";
    case Quality::kPreview:
      return "preview";
    case Quality::kProduction:
      return "production";
  }
  return "preview";
}

Quality parse_quality(const std::string& name) {
  if (name == "draft") return Quality::kDraft;
  if (name == "preview") return Quality::kPreview;
  if (name == "production") return Quality::kProduction;
  throw CookError("unknown quality '" + name + "' (expected draft, preview or production)");
}

const char* integrator_name(Integrator i) {
  return i == Integrator::kReference ? "reference" : "gather";
}

Integrator parse_integrator(const std::string& name) {
  if (name == "gather") return Integrator::kGather;
  if (name == "reference") return Integrator::kReference;
  throw CookError("unknown integrator '" + name + "' (expected gather or reference)");
}

GatherPreset gather_preset(const BakeOptions& options) {
  GatherPreset p = preset_gather(options.quality);
  if (options.gather_rays > 0) p.rays = options.gather_rays;
  if (options.indirect_scale > 0) p.level = options.indirect_scale;
  if (options.denoise >= 0) p.denoise = options.denoise;
  p.contact_texels = options.contact_texels;
  return p;
}

void report_bake(const BakeSession::Impl& impl, Report& report) {
  const BakeContext& b = impl.ctx;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - impl.start).count();
  const uint64_t rays = b.tracer.rays_traced() - impl.rays0;
  std::lock_guard<std::mutex> lock(report.mutex());
  nlohmann::json& j = report.root()["bake"];
  j["output_step"] = b.output_step;
  j["static_step"] = b.static_step;
  j["output_step_definition"] =
      "99th percentile over valid texels of the authored state's unshadowed direct irradiance "
      "(max channel) / 255";
  j["static_step_definition"] =
      "min(output_step, the brightest static light's peak unshadowed irradiance / 255): the "
      "significance of the base map, static indirect light and static shadows";
  j["quality"] = quality_name(b.options.quality);
  j["plan_effects"] = b.options.plan_effects;
  j["area_samples"] = b.area_samples;
  j["threads"] = b.threads;
  j["epsilon"] = b.eps;
  j["rays"] = j.value("rays", uint64_t{0}) + rays;
  j["seconds"] = j.value("seconds", 0.0) + seconds;
  const double total_s = j["seconds"].get<double>();
  j["rays_per_second"] =
      total_s > 0.0 ? static_cast<double>(j["rays"].get<uint64_t>()) / total_s : 0.0;
  nlohmann::json& ind = report.root()["indirect"];
  ind["enabled"] = b.options.indirect;
  if (b.indirect) ind.update(b.indirect->describe());
}

BakeSession::BakeSession(const Scene& scene, const Layout& layout, const TexelSet& texels,
                         const Tracer& tracer, const BakeOptions& options, Progress& progress,
                         Report& report, GatherStore* store) {
  if (options.integrator == Integrator::kReference)
    throw CookError("the reference path tracer bakes single states (bake_reference), not maps");
  progress.begin("plan", 1);
  impl_ = std::make_unique<Impl>(scene, layout, texels, tracer, options, store);
  impl_->rays0 = tracer.rays_traced();
  impl_->plan = make_plan(impl_->ctx);
  report_decisions(scene, impl_->plan.decisions, report);
  progress.end();
}

void BakeSession::Impl::trace_shared(Progress& progress, Report& report) {
  std::call_once(traced, [&] {
    if (ctx.options.indirect)
      ctx.indirect = make_gather_integrator(ctx, gather_store, progress, report);
  });
}

void BakeSession::trace_shared(Progress& progress, Report& report) const {
  impl_->trace_shared(progress, report);
}

BakeSession::~BakeSession() = default;

const BakeSession::Impl& BakeSession::impl() const {
  return *impl_;
}

const BakePlan& BakeSession::plan() const {
  return impl_->plan;
}

float BakeSession::output_step() const {
  return impl_->ctx.output_step;
}

GroupBake BakeSession::bake_group(size_t group, Progress& progress, Report& report) const {
  return std::move(bake_groups({group}, progress, report).front());
}

std::vector<GroupBake> BakeSession::bake_groups(const std::vector<size_t>& groups,
                                                Progress& progress, Report& report) const {
  for (size_t g : groups)
    if (g >= impl_->plan.groups.size())
      throw CookError("bake: no light group " + std::to_string(g));
  impl_->trace_shared(progress, report);
  std::vector<GroupBake> out;
  for (size_t first = 0; first < groups.size(); first += kGroupBatch) {
    const std::vector<size_t> batch(
        groups.begin() + std::ptrdiff_t(first),
        groups.begin() + std::ptrdiff_t(std::min(groups.size(), first + kGroupBatch)));
    for (GroupBake& g : bake_light_groups(impl_->ctx, impl_->plan, batch, progress, report))
      out.push_back(std::move(g));
  }
  return out;
}

BakedMaps BakeSession::assemble(std::vector<GroupBake> groups, Report& report) const {
  const BakePlan& plan = impl_->plan;
  const Scene& scene = impl_->ctx.scene;
  std::sort(groups.begin(), groups.end(),
            [](const GroupBake& a, const GroupBake& b) { return a.group < b.group; });
  for (size_t i = 0; i < groups.size(); ++i) {
    if (groups[i].group != i || groups.size() != plan.groups.size())
      throw CookError("bake: assembling needs every light group exactly once");
  }
  BakedMaps maps;
  maps.output_step = plan.output_step;
  nlohmann::json pairs = nlohmann::json::array();
  auto pair_record = [&](const Decision& d) {
    pairs.push_back({{"light", scene.lights[size_t(d.light)].name},
                     {"object", scene.objects[size_t(d.object)].name},
                     {"kept", d.taken},
                     {"stage", d.stage == DecisionStage::kPlan     ? "geometric"
                               : d.stage == DecisionStage::kBounce ? "bounce"
                                                                   : "traced"},
                     {"reason", d.reason}});
    if (!std::isnan(d.value)) pairs.back()["peak"] = d.value;
  };
  for (const Decision& d : plan.decisions)
    if (d.kind == DecisionKind::kPair) pair_record(d);
  for (GroupBake& g : groups) {
    report_decisions(scene, g.decisions, report);
    for (const Decision& d : g.decisions)
      if (d.kind == DecisionKind::kPair) pair_record(d);
    {
      std::lock_guard<std::mutex> lock(report.mutex());
      report.root()["bake"]["group_seconds"][plan.groups[g.group].name] = g.seconds;
    }
    if (g.group == 0) {
      maps.base = std::move(g.map);
      maps.base_indirect = std::move(g.indirect);
      maps.base_direct = std::move(g.direct);
      maps.static_shadows = std::move(g.static_shadows);
      continue;
    }
    maps.lights.push_back(plan.groups[g.group].light);
    maps.contribution.push_back(std::move(g.map));
    maps.contribution_indirect.push_back(std::move(g.indirect));
    maps.contribution_direct.push_back(std::move(g.direct));
    for (ShadowMap& s : g.shadows) maps.shadows.push_back(std::move(s));
    for (PairCorrectionMap& p : g.pair_corrections) maps.pair_corrections.push_back(std::move(p));
  }
  {
    std::lock_guard<std::mutex> lock(report.mutex());
    int kept = 0;
    for (const nlohmann::json& p : pairs) kept += p["kept"].get<bool>() ? 1 : 0;
    report.root()["pairs_kept"] = kept;
    report.root()["pairs_skipped"] = static_cast<int>(pairs.size()) - kept;
    report.root()["pairs"] = std::move(pairs);
  }
  report_bake(*impl_, report);
  return maps;
}

BakedMaps bake_maps(const Scene& scene, const Layout& layout, const TexelSet& texels,
                    const Tracer& tracer, const BakeOptions& options, Progress& progress,
                    Report& report) {
  BakeSession session(scene, layout, texels, tracer, options, progress, report);
  std::vector<size_t> all(session.plan().groups.size());
  for (size_t g = 0; g < all.size(); ++g) all[g] = g;
  BakedMaps maps = session.assemble(session.bake_groups(all, progress, report), report);
  session.bake_panes(maps, progress, report);
  return maps;
}

FloatImage bake_state(const Scene& scene, const Layout& layout, const TexelSet& texels,
                      const Tracer& tracer, const StateSpec& state, const BakeOptions& options,
                      Progress& progress, Report& report) {
  BakeSession session(scene, layout, texels, tracer, options, progress, report);
  return session.bake_state(state, progress, report);
}

}  // namespace lightpatch::cooker
