#include "bake/plan.h"

#include <mutex>

namespace lightpatch::cooker {

const char* decision_kind_name(DecisionKind kind) {
  switch (kind) {
    case DecisionKind::kSoftShadows:
      return "soft_shadows";
    case DecisionKind::kEmissive:
      return "emissive";
    case DecisionKind::kIndirect:
      return "indirect";
    case DecisionKind::kGroupBounce:
      return "group_bounce";
    case DecisionKind::kObjectBounce:
      return "object_bounce";
    case DecisionKind::kPair:
      return "pair";
    case DecisionKind::kOverlap:
      return "overlap";
    case DecisionKind::kStaticShadow:
      return "static_shadow";
    case DecisionKind::kStaticOverlap:
      return "static_overlap";
    case DecisionKind::kTripleOverlap:
      return "triple_overlap";
  }
  return "unknown";
}

namespace {

const char* stage_name(DecisionStage s) {
  switch (s) {
    case DecisionStage::kPlan:
      return "plan";
    case DecisionStage::kTraced:
      return "traced";
    case DecisionStage::kBounce:
      return "bounce";
  }
  return "unknown";
}

std::string light_label(const Scene& scene, int li) {
  if (li < 0) return "static lights";
  const std::string& n = scene.lights[size_t(li)].name;
  return n.empty() ? "light#" + std::to_string(li) : n;
}

std::string object_label(const Scene& scene, int o) {
  return o < 0 ? std::string() : scene.objects[size_t(o)].name;
}

}  // namespace

std::string decision_what(const Scene& scene, const Decision& d) {
  const std::string l = light_label(scene, d.light);
  const std::string a = object_label(scene, d.object), b = object_label(scene, d.object_b);
  switch (d.kind) {
    case DecisionKind::kSoftShadows:
      return "soft shadows: " + l;
    case DecisionKind::kEmissive:
      return "emissive area lights";
    case DecisionKind::kIndirect:
      return "indirect light";
    case DecisionKind::kGroupBounce:
      return "indirect light: " + l;
    case DecisionKind::kObjectBounce:
      return "indirect bounce: " + l + " / " + a;
    case DecisionKind::kPair:
      return "pair " + l + " / " + a;
    case DecisionKind::kOverlap:
      return "overlap correction " + l + " / " + a + " + " + b;
    case DecisionKind::kStaticShadow:
      return "static shadow of object " + a;
    case DecisionKind::kStaticOverlap:
      return "static shadow overlap " + a + " + " + b;
    case DecisionKind::kTripleOverlap:
      return "triple overlap corrections: " + l;
  }
  return "decision";
}

void report_decisions(const Scene& scene, const std::vector<Decision>& decisions, Report& report) {
  std::lock_guard<std::mutex> lock(report.mutex());
  nlohmann::json& out = report.root()["decisions"];
  if (!out.is_array()) out = nlohmann::json::array();
  for (const Decision& d : decisions) {
    nlohmann::json j = {{"what", decision_what(scene, d)},
                        {"kind", decision_kind_name(d.kind)},
                        {"stage", stage_name(d.stage)},
                        {"taken", d.taken},
                        {"forced", d.forced},
                        {"reason", d.reason}};
    if (d.light >= 0) j["light"] = light_label(scene, d.light);
    if (d.object >= 0) j["object"] = object_label(scene, d.object);
    if (d.object_b >= 0) j["object_b"] = object_label(scene, d.object_b);
    if (!std::isnan(d.value)) j["value"] = d.value;
    if (!std::isnan(d.bound)) j["bound"] = d.bound;
    if (!std::isnan(d.seconds)) j["seconds"] = d.seconds;
    out.push_back(std::move(j));
  }
}

BakePlan make_plan(const BakeContext& b) {
  const Scene& scene = b.scene;
  const bool plan = b.options.plan_effects;
  const bool bounce = b.options.indirect;
  BakePlan p;
  p.output_step = b.output_step;
  p.static_step = b.static_step;
  auto decide = [&](Decision d) { p.decisions.push_back(std::move(d)); };
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    const Light& l = scene.lights[i];
    Decision d;
    d.kind = DecisionKind::kSoftShadows;
    d.light = int(i);
    if (l.radius > 0.0f && l.type == LightType::kDirectional) {
      d.reason = "directional light: a radius in metres has no angular size";
    } else if (l.radius > 0.0f) {
      d.taken = true;
      d.reason = "radius " + std::to_string(l.radius) + " m, " +
                 std::to_string(b.lights[i].samples) + " samples";
    } else {
      d.reason = plan ? "no lightRadius: a point source gives hard shadows"
                      : "no lightRadius: a point source has no size, nothing to force";
    }
    decide(d);
  }
  {
    Decision d;
    d.kind = DecisionKind::kEmissive;
    d.taken = !b.emissive.empty();
    d.reason = b.emissive.empty()
                   ? "no emissive static surfaces"
                   : std::to_string(b.emissive.triangle_count()) + " emissive triangles, " +
                         std::to_string(b.area_samples) + " samples/texel";
    decide(d);
  }
  {
    Decision d;
    d.kind = DecisionKind::kIndirect;
    d.taken = bounce;
    if (!bounce) {
      d.reason = "turned off by the bake options";
    } else {
      const GatherPreset gp = gather_preset(b.options);
      d.reason = "final gathering: " + std::to_string(gp.rays) + " rays per coarse texel of " +
                 std::to_string(gp.level) + " x " + std::to_string(gp.level) + " texels, " +
                 std::to_string(gp.denoise) + " denoise passes";
    }
    decide(d);
  }
  std::vector<Bounds> bounds;
  for (const Object& o : scene.objects) bounds.push_back(object_bounds(scene, o));

  // The static lights: objects some static light reaches, or emissive surfaces (sampled
  // everywhere); with bounce light on, the others may still change the static bounce.
  LightGroup st;
  st.light = -1;
  st.name = "static lights";
  st.threshold = b.static_step;
  for (size_t o = 0; o < scene.objects.size(); ++o) {
    bool reach = !plan || !b.emissive.empty();
    for (size_t i = 0; i < scene.lights.size() && !reach; ++i) {
      reach = !scene.lights[i].semi_dynamic &&
              precull_pair(scene.lights[i], b.lights[i], bounds[o]).empty();
    }
    if (reach) {
      st.candidates.push_back(int(o));
    } else if (bounce && !bounds[o].empty()) {
      st.bounce_only.push_back(int(o));
      st.bounce_only_why.push_back("no static light or emissive surface reaches it");
    } else {
      Decision d;
      d.kind = DecisionKind::kStaticShadow;
      d.object = int(o);
      d.reason = "no static light, emissive surface or static bounce reaches it";
      decide(d);
    }
  }
  p.groups.push_back(std::move(st));

  for (size_t i = 0; i < scene.lights.size(); ++i) {
    const Light& l = scene.lights[i];
    // A moving light has no maps of its own: its bounce light is the panes' (bake_panes).
    if (!l.semi_dynamic || l.moving) continue;
    LightGroup g;
    g.light = int(i);
    g.name = b.light_name(int(i));
    g.threshold = b.lights[i].threshold;
    for (size_t o = 0; o < scene.objects.size(); ++o) {
      const std::string why = precull_pair(l, b.lights[i], bounds[o]);
      if (!plan || why.empty()) {
        g.candidates.push_back(int(o));
      } else if (bounce && !bounds[o].empty()) {
        g.bounce_only.push_back(int(o));
        g.bounce_only_why.push_back(why);
      } else {
        Decision d;
        d.kind = DecisionKind::kPair;
        d.light = int(i);
        d.object = int(o);
        d.reason = why;
        decide(d);
      }
    }
    p.groups.push_back(std::move(g));
  }
  return p;
}

}  // namespace lightpatch::cooker
