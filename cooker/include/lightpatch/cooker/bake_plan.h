// The effect plan as data (DESIGN.md, "Only what the scene calls for"): the light groups a bake
// runs, each group's significance and candidates, and every decision with its reason. The plan
// is made once before baking (plan_bake); decisions measured while baking (a map's peak against
// its bar) are added by the groups. The report writes both; tests read the typed records.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/report.h"
#include "lightpatch/cooker/scene.h"
#include "lightpatch/cooker/texels.h"
#include "lightpatch/cooker/tracer.h"

namespace lightpatch::cooker {

enum class DecisionKind {
  kSoftShadows,    // light: sampled as a sphere (lightRadius) or a point
  kEmissive,       // emissive static surfaces sampled as area lights
  kIndirect,       // bounce light for the bake as a whole
  kGroupBounce,    // light (or the static lights): its bounce light kept
  kObjectBounce,   // light, object: the object's change to the light's bounce light solved
  kPair,           // light, object: the shadow map S_ol kept
  kOverlap,        // light, object, object_b: the pair correction kept
  kStaticShadow,   // object: what it changes in the static lights' light kept
  kStaticOverlap,  // object, object_b: overlapping static shadows (no correction in the pack)
  kTripleOverlap,  // light: light blocked by three or more objects (not corrected)
};
const char* decision_kind_name(DecisionKind kind);

// Where a keep/skip decision was made.
enum class DecisionStage {
  kPlan,    // before any tracing (reach, cone, presets)
  kTraced,  // from the traced map's peak
  kBounce,  // from the object's change to the bounce light only
};

struct Decision {
  DecisionKind kind = DecisionKind::kPair;
  DecisionStage stage = DecisionStage::kPlan;
  int light = -1;     // Scene::lights index; -1: none or the static lights
  int object = -1;    // Scene::objects index or -1
  int object_b = -1;  // Scene::objects index or -1
  bool taken = false;
  bool forced = false;  // taken because the plan was off (--no-plan)
  std::string reason;   // for people
  // The measured quantity and the bar it was held against (irradiance, the map's units); NaN
  // where the decision compares no number.
  double value = std::nan("");
  double bound = std::nan("");
  double seconds = std::nan("");  // the decision's own work, where it is timed on its own
};

// One unit of baking: the static lights (B and the static shadows) or one semi-dynamic light (C_l,
// its S_ol and pair corrections). Its output depends on the scene, the options and the seed only.
struct LightGroup {
  int light = -1;                // Scene::lights index; -1 for the static lights
  std::string name;              // "static lights" or the light's name
  float threshold = 0.0f;        // significance of its maps (irradiance at intensity 1 for a light)
  std::vector<int> candidates;   // objects that can block its direct light (traced per ray)
  std::vector<int> bounce_only;  // objects that can change only its bounce light
  std::vector<std::string> bounce_only_why;  // why each cannot block its direct light
};

struct BakePlan {
  float output_step = 0.0f;         // BakedMaps::output_step
  float static_step = 0.0f;         // significance of the static group
  std::vector<LightGroup> groups;   // [0] the static lights, then the semi-dynamic lights
  std::vector<Decision> decisions;  // made before baking
};

// Writes decisions into the report's "decisions" array: {what, kind, stage, taken, reason, light,
// object, object_b, value, bound, seconds} (names for indices).
void report_decisions(const Scene& scene, const std::vector<Decision>& decisions, Report& report);
// The English line a decision reads as in progress output and the report's "what".
std::string decision_what(const Scene& scene, const Decision& d);

}  // namespace lightpatch::cooker
