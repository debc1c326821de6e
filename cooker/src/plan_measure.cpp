#include "lightpatch/cooker/plan_measure.h"

#include <map>
#include <string>

namespace lightpatch::cooker {

namespace {

using nlohmann::json;

bool starts_with(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

double number(const json& j, const char* a, const char* b) {
  if (!j.contains(a) || !j[a].is_object() || !j[a].contains(b) || !j[a][b].is_number()) return 0.0;
  return j[a][b].get<double>();
}

// The stages a cook repeats for the forced run: the bake, finalize and pack (not the import,
// layout and texels they share, nor the write the forced pack skips).
json run_summary(const json& root) {
  json out;
  json stages = json::object();
  double total = number(root, "bake", "seconds");
  if (root.contains("stages")) {
    for (const auto& [name, seconds] : root["stages"].items()) {
      if (starts_with(name, "bake.") || name == "finalize" || name == "pack")
        stages[name] = seconds;
      if (name == "finalize" || name == "pack") total += seconds.get<double>();
    }
  }
  stages["bake"] = number(root, "bake", "seconds");
  out["stage_seconds"] = stages;
  out["seconds"] = total;
  out["rays"] = number(root, "bake", "rays");
  out["pack_bytes"] = number(root, "pack", "pack_bytes");
  out["atlas_bytes"] = number(root, "pack", "atlas_bytes");
  out["patches"] = number(root, "pack", "patches");
  out["groups"] = number(root, "pack", "groups");
  return out;
}

json count_decisions(const json& root, const std::string& kind) {
  int taken = 0, skipped = 0;
  if (root.contains("decisions")) {
    for (const json& d : root["decisions"]) {
      if (d.value("kind", "") != kind) continue;
      (d["taken"].get<bool>() ? taken : skipped)++;
    }
  }
  return {{"taken", taken}, {"skipped", skipped}};
}

json colour_counts(const json& root) {
  return {{"taken", number(root["pack"], "colour", "patches_3_channel")},
          {"skipped", number(root["pack"], "colour", "patches_1_channel_from_3")}};
}

}  // namespace

void add_plan_measurement(json& planned, const json& forced) {
  json plan;
  plan["planned"] = run_summary(planned);
  plan["forced"] = run_summary(forced);
  const json& p = plan["planned"];
  const json& f = plan["forced"];
  for (const char* k : {"seconds", "rays", "pack_bytes", "atlas_bytes", "patches"})
    plan["saved"][k] = f[k].get<double>() - p[k].get<double>();
  // Report categories by decision kind (bake_plan.h).
  const std::pair<const char*, const char*> categories[] = {{"pairs", "pair"},
                                                            {"overlap_corrections", "overlap"},
                                                            {"indirect_groups", "group_bounce"},
                                                            {"object_bounce", "object_bounce"},
                                                            {"static_shadows", "static_shadow"}};
  for (const auto& [name, kind] : categories) {
    plan["categories"][name] = {{"planned", count_decisions(planned, kind)},
                                {"forced", count_decisions(forced, kind)}};
  }
  plan["categories"]["colour"] = {{"planned", colour_counts(planned)},
                                  {"forced", colour_counts(forced)},
                                  {"unit", "3-channel patches kept (taken) or stored as 1"}};

  // Per light group: its whole pass in each run.
  const json none = json::object();
  auto group_seconds = [&](const json& root) -> const json& {
    return root.contains("bake") && root["bake"].contains("group_seconds")
               ? root["bake"]["group_seconds"]
               : none;
  };
  const json& pg = group_seconds(planned);
  const json& fg = group_seconds(forced);
  json groups = json::array();
  for (const auto& [group, seconds] : fg.items()) {
    const double before = pg.contains(group) ? pg[group].get<double>() : 0.0;
    groups.push_back({{"group", group},
                      {"planned_s", before},
                      {"forced_s", seconds.get<double>()},
                      {"saved_s", seconds.get<double>() - before}});
  }
  plan["groups"] = groups;

  // Decisions whose saved time is measured on its own.
  std::map<std::string, const json*> forced_decision;
  if (forced.contains("decisions")) {
    for (const json& d : forced["decisions"]) forced_decision[d["what"].get<std::string>()] = &d;
  }
  int timed = 0;
  if (planned.contains("decisions")) {
    for (json& d : planned["decisions"]) {
      const std::string what = d["what"].get<std::string>();
      const auto it = forced_decision.find(what);
      if (d["taken"].get<bool>() || it == forced_decision.end() ||
          !(*it->second)["taken"].get<bool>())
        continue;
      if (d.value("kind", "") == "group_bounce") {
        const std::string group = d.value("light", "static lights");
        if (!pg.contains(group) || !fg.contains(group)) continue;
        d["time_saved_s"] = fg[group].get<double>() - pg[group].get<double>();
        d["time_saved_covers"] =
            "the group's whole pass, forced minus planned: its bounce light, its objects' "
            "changes to it and the pairs it keeps";
        ++timed;
      } else if (it->second->contains("seconds")) {
        d["time_saved_s"] = (*it->second)["seconds"];
        d["time_saved_covers"] =
            "the forced run's work for this decision alone (an object's change to a group's "
            "bounce light; changes are solved several at once, so its share of theirs by the "
            "rays it gathered)";
        ++timed;
      }
    }
  }
  plan["decisions_timed"] = timed;
  plan["note"] =
      "forced: the same scene, options and seed with the effect plan off (--no-plan): every "
      "light group keeps its bounce light with every object's change to it, every "
      "light-object pair is traced and kept, every measured overlap correction kept, every "
      "3-channel patch kept at 3 channels. Both runs are timed after the cook's own bake (which "
      "pays one-time warm-up costs), forced first; seconds are wall-clock on a possibly shared "
      "machine.";
  planned["plan"] = std::move(plan);
}

}  // namespace lightpatch::cooker
