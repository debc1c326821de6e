#include "inn_game.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lightpatch::inn {
namespace {

constexpr float kReach = 2.6f;       // metres from the eye to something the player can use
constexpr float kAltarReach = 3.2f;  // metres from the eye to a placed copy's spot
constexpr float kMinFacing = 0.8f;   // cosine of the widest angle off the view direction

std::string pretty(const std::string& name) {
  std::string s = name;
  std::replace(s.begin(), s.end(), '_', ' ');
  return s;
}

float max3(const float v[3]) {
  return std::max(v[0], std::max(v[1], v[2]));
}

uint32_t light_index(const Runtime& rt, const std::string& name) {
  const int32_t i = rt.find_light(name.c_str());
  if (i < 0) throw std::runtime_error("the pack has no semi-dynamic light '" + name + "'");
  return static_cast<uint32_t>(i);
}

uint32_t object_index(const Runtime& rt, const std::string& name) {
  const int32_t i = rt.find_object(name.c_str());
  if (i < 0) throw std::runtime_error("the pack has no semi-dynamic object '" + name + "'");
  return static_cast<uint32_t>(i);
}

}  // namespace

InnGame::InnGame(Runtime& runtime, const World& world, const nlohmann::json& scenario)
    : rt_(runtime), world_(world) {
  lights_.resize(rt_.light_count());
  authored_factor_.resize(rt_.light_count());
  for (uint32_t l = 0; l < rt_.light_count(); ++l) {
    lights_[l] = rt_.light(l);  // the authored defaults
    float f[3];
    for (int c = 0; c < 3; ++c) f[c] = lights_[l].color[c] * lights_[l].intensity;
    authored_factor_[l] = std::max(max3(f), 1e-6f);
  }
  const auto& items = scenario.at("items");
  const auto& placed = scenario.at("placed_items");
  if (items.size() != placed.size())
    throw std::runtime_error("scenario: items and placed_items differ in length");
  for (size_t i = 0; i < items.size(); ++i) {
    Item it;
    it.name = items[i].get<std::string>();
    it.object = object_index(rt_, it.name);
    it.placed = object_index(rt_, placed[i].get<std::string>());
    items_.push_back(it);
    item_rooms_.emplace_back();
  }
  if (scenario.contains("lantern")) {
    lantern_ = static_cast<int32_t>(light_index(rt_, scenario["lantern"].get<std::string>()));
    const LightPose pose = rt_.light_pose(static_cast<uint32_t>(lantern_));
    lantern_position_ = {pose.position[0], pose.position[1], pose.position[2]};
  }
  const int32_t book = rt_.find_object("spell_book");
  book_ = book;
  for (const auto& step : scenario.at("steps")) {
    const std::string action = step.value("action", "");
    const std::string node = step.value("node", "");
    const std::string room = step.value("room", "");
    if (action == "take" && node == "spell_book") book_room_ = room;
    if (action == "take") {
      for (size_t i = 0; i < items_.size(); ++i)
        if (items_[i].name == node) item_rooms_[i] = room;
    }
    if (action == "place") altar_room_ = room;
    if (action == "spell_done" && !node.empty()) {
      spell_light_ = static_cast<int32_t>(light_index(rt_, node));
      if (step.contains("state") && step["state"].contains("lights") &&
          step["state"]["lights"].contains(node)) {
        const auto& s = step["state"]["lights"][node];
        spell_state_ = lights_[static_cast<uint32_t>(spell_light_)];
        spell_state_.on = s.value("on", true);
        if (s.contains("color")) {
          for (int c = 0; c < 3; ++c)
            spell_state_.color[c] = s["color"][static_cast<size_t>(c)].get<float>();
        }
        if (s.contains("intensity")) spell_state_.intensity = s["intensity"].get<float>();
      }
    }
  }
}

void InnGame::apply_state(const nlohmann::json& state) {
  if (state.contains("lights")) {
    for (const auto& [name, s] : state["lights"].items()) {
      const uint32_t l = light_index(rt_, name);
      if (s.contains("on")) lights_[l].on = s["on"].get<bool>();
      if (s.contains("color")) {
        for (int c = 0; c < 3; ++c)
          lights_[l].color[c] = s["color"].at(static_cast<size_t>(c)).get<float>();
      }
      if (s.contains("intensity")) lights_[l].intensity = s["intensity"].get<float>();
      push_light(l);
      if (s.contains("position")) {
        // A moving light's pose (DESIGN.md's state format): the lantern hangs there.
        LightPose pose = rt_.light_pose(l);
        for (int a = 0; a < 3; ++a)
          pose.position[a] = s["position"].at(static_cast<size_t>(a)).get<float>();
        if (rt_.set_light_pose(l, pose) != Status::kOk)
          throw std::runtime_error("state: light '" + name + "' cannot take that position");
        if (static_cast<int32_t>(l) == lantern_)
          lantern_position_ = {pose.position[0], pose.position[1], pose.position[2]};
      }
    }
  }
  if (state.contains("objects")) {
    for (const auto& [name, s] : state["objects"].items()) {
      const uint32_t o = object_index(rt_, name);
      if (s.contains("visible")) rt_.set_object_visible(o, s["visible"].get<bool>());
    }
  }
}

void InnGame::push_light(uint32_t l) {
  rt_.set_light(l, lights_[l]);
}

bool InnGame::set_light_on(uint32_t light, bool on) {
  if (light >= lights_.size() || lights_[light].on == on) return false;
  lights_[light].on = on;
  push_light(light);
  return true;
}

bool InnGame::take(uint32_t object) {
  if (book_ >= 0 && object == static_cast<uint32_t>(book_) && !book_taken_) {
    book_taken_ = true;
    rt_.set_object_visible(object, false);
    return true;
  }
  for (Item& it : items_) {
    if (it.object == object && !it.carried && !it.is_placed) {
      it.carried = true;
      rt_.set_object_visible(object, false);
      return true;
    }
  }
  return false;
}

bool InnGame::place(uint32_t item) {
  if (item >= items_.size() || !items_[item].carried) return false;
  items_[item].carried = false;
  items_[item].is_placed = true;
  rt_.set_object_visible(items_[item].placed, true);
  return true;
}

bool InnGame::take_lantern() {
  if (lantern_ < 0 || lantern_carried_) return false;
  lantern_carried_ = true;
  return true;
}

bool InnGame::move_lantern(glm::vec3 position) {
  if (!lantern_carried_) return false;
  LightPose pose = rt_.light_pose(static_cast<uint32_t>(lantern_));
  for (int a = 0; a < 3; ++a) pose.position[a] = position[a];
  if (rt_.set_light_pose(static_cast<uint32_t>(lantern_), pose) != Status::kOk) return false;
  lantern_position_ = position;
  return true;
}

glm::vec3 InnGame::lantern_factor() const {
  if (lantern_ < 0) return glm::vec3(0.0f);
  const LightState& s = lights_[static_cast<uint32_t>(lantern_)];
  if (!s.on) return glm::vec3(0.0f);
  return glm::vec3(s.color[0], s.color[1], s.color[2]) * s.intensity;
}

bool InnGame::lantern_landed() const {
  if (lantern_ < 0 || !rt_.ready() || rt_.stats().pane_pending != 0) return false;
  for (uint32_t l = 0; l < rt_.light_count(); ++l)
    if (rt_.state().light_is_pane(l) && !light_landed(l)) return false;
  return true;
}

void InnGame::complete_spell() {
  spell_done_ = true;
  if (spell_light_ < 0) return;
  lights_[static_cast<uint32_t>(spell_light_)] = spell_state_;
  push_light(static_cast<uint32_t>(spell_light_));
}

uint32_t InnGame::placed_count() const {
  uint32_t n = 0;
  for (const Item& it : items_) n += it.is_placed;
  return n;
}

InnGame::Target InnGame::target(glm::vec3 eye, glm::vec3 forward) const {
  Target best;
  float best_score = 1e30f;
  auto consider = [&](Target::Kind kind, uint32_t index, glm::vec3 at, float reach,
                      const std::string& label) {
    const glm::vec3 d = at - eye;
    const float dist = glm::length(d);
    if (dist > reach) return;
    const float facing = dist > 1e-4f ? glm::dot(d / dist, forward) : 1.0f;
    if (facing < kMinFacing) return;
    const float score = dist * (2.0f - facing);
    if (score < best_score) {
      best_score = score;
      best = Target{kind, index, label};
    }
  };
  for (uint32_t l = 0; l < lights_.size(); ++l) {
    if (world_.lights[l].kind == LightKind::kOther) continue;
    if (spell_done_ && static_cast<int32_t>(l) == spell_light_)
      continue;  // the spell's fire stays lit
    consider(Target::kLight, l, world_.lights[l].position, kReach,
             (lights_[l].on ? "snuff the " : "light the ") + pretty(world_.lights[l].name));
  }
  if (lantern_ >= 0 && !lantern_carried_)
    consider(Target::kLantern, static_cast<uint32_t>(lantern_), lantern_position_, kReach,
             "take the lantern");
  if (book_ >= 0 && !book_taken_) {
    consider(Target::kTake, static_cast<uint32_t>(book_),
             world_.objects[static_cast<size_t>(book_)].center, kReach, "take the spell book");
  }
  for (uint32_t i = 0; i < items_.size(); ++i) {
    const Item& it = items_[i];
    if (!it.carried && !it.is_placed) {
      consider(Target::kTake, it.object, world_.objects[it.object].center, kReach,
               "take the " + pretty(it.name));
    }
    if (it.carried) {
      // The spot matters more than the aim: prefer placing when the player stands at the altar.
      const glm::vec3 at = world_.objects[it.placed].center;
      if (glm::distance(at, eye) <= kAltarReach) {
        best = Target{Target::kPlace, i, "place the " + pretty(it.name) + " on the altar"};
        return best;
      }
    }
  }
  return best;
}

std::string InnGame::interact(glm::vec3 eye, glm::vec3 forward) {
  const Target t = target(eye, forward);
  switch (t.kind) {
    case Target::kLight: {
      const bool on = !lights_[t.index].on;
      set_light_on(t.index, on);
      return std::string(on ? "You light the " : "You snuff the ") +
             pretty(world_.lights[t.index].name) + ".";
    }
    case Target::kTake:
      take(t.index);
      return "You take the " + pretty(world_.objects[t.index].name) + ".";
    case Target::kPlace: {
      place(t.index);
      std::string line = "You place the " + pretty(items_[t.index].name) + " on the altar.";
      if (placed_count() == items_.size() && !spell_done_) {
        complete_spell();
        line += " The spell is complete!";
      }
      return line;
    }
    case Target::kLantern:
      take_lantern();
      return "You take the lantern.";
    case Target::kNone:
      break;
  }
  return "";
}

std::string InnGame::objective() const {
  if (spell_done_) return "The spell is cast: the hearth burns violet. (Esc quits)";
  // Until it is carried, the lantern is the first thing to find.
  if (lantern_ >= 0 && !lantern_carried_) return "Take the lantern from its hook (E).";
  if (book_ >= 0 && !book_taken_) {
    return "Find the spell book" +
           (book_room_.empty() ? std::string() : " (" + pretty(book_room_) + ")") +
           ". Light candles and torches to see (E).";
  }
  uint32_t carried = 0;
  std::string missing;
  for (size_t i = 0; i < items_.size(); ++i) {
    carried += items_[i].carried;
    if (!items_[i].carried && !items_[i].is_placed) {
      if (!missing.empty()) missing += ", ";
      missing += pretty(items_[i].name);
      if (!item_rooms_[i].empty()) missing += " (" + pretty(item_rooms_[i]) + ")";
    }
  }
  std::string s = "Place every ingredient on the altar by the " +
                  (altar_room_.empty() ? std::string("main") : pretty(altar_room_)) +
                  " fireplace: " + std::to_string(placed_count()) + "/" +
                  std::to_string(items_.size()) + " placed, " + std::to_string(carried) +
                  " carried.";
  if (!missing.empty()) s += "\nStill to find: " + missing;
  return s;
}

bool InnGame::light_landed(uint32_t l) const {
  if (!rt_.ready()) return false;
  const Planner& p = rt_.planner();
  float want[3], shown[3], color[3];
  p.light_color(l, color);
  for (int c = 0; c < 3; ++c) want[c] = p.light_on(l) ? color[c] * p.light_intensity(l) : 0.0f;
  p.shown_factor(l, shown);
  return want[0] == shown[0] && want[1] == shown[1] && want[2] == shown[2];
}

bool InnGame::object_landed(uint32_t o) const {
  return rt_.ready() && rt_.planner().object_visible(o) == rt_.planner().shown_visible(o);
}

float InnGame::flicker(uint32_t l, double t, float* tint) const {
  float amplitude = 0.1f;
  switch (world_.lights[l].kind) {
    case LightKind::kCandle:
      amplitude = 0.12f;
      break;
    case LightKind::kTorch:
      amplitude = 0.18f;
      break;
    case LightKind::kFire:
      amplitude = 0.25f;
      break;
    case LightKind::kOther:
      amplitude = 0.1f;
      break;
  }
  // A few incommensurate sines per light, phase-shifted by the light's index: smooth, never
  // repeating visibly, and the same for the same time (scripted runs are reproducible).
  const double p = 1.7 * l;
  const double n = 0.5 * std::sin(2.0 * 3.14159265 * 1.3 * t + p) +
                   0.3 * std::sin(2.0 * 3.14159265 * 3.7 * t + 2.1 * p) +
                   0.2 * std::sin(2.0 * 3.14159265 * 7.9 * t + 3.3 * p);
  const float k = static_cast<float>(n) * amplitude;  // in [-amplitude, amplitude]
  // Dimmer moments are redder, as a flame that cools.
  tint[0] = 1.0f;
  tint[1] = 1.0f + 0.5f * k;
  tint[2] = 1.0f + 1.0f * k;
  return 1.0f + k;
}

uint32_t InnGame::animate(double time_s, uint64_t budget) {
  if (!rt_.ready() || rt_.stats().rebuild_active) return 0;
  const Planner& p = rt_.planner();
  uint64_t pending = 0;
  for (uint32_t l = 0; l < lights_.size(); ++l) {
    if (!light_landed(l)) pending += p.light_change_texels(l);
  }
  for (uint32_t o = 0; o < rt_.object_count(); ++o) {
    if (!object_landed(o)) pending += p.object_change_texels(o);
  }
  if (pending >= budget) return 0;
  uint64_t room = budget - pending;
  const uint64_t rebuild = p.rebuild_texels();
  const uint32_t n = static_cast<uint32_t>(lights_.size());
  uint32_t updated = 0;
  int64_t first_skipped = -1;
  for (uint32_t k = 0; k < n; ++k) {
    const uint32_t l = (flicker_cursor_ + k) % n;
    if (!lights_[l].on || world_.lights[l].kind == LightKind::kOther || !light_landed(l)) continue;
    const uint64_t cost = p.light_change_texels(l);
    if (cost > room || cost >= rebuild) {
      if (first_skipped < 0) first_skipped = l;
      continue;
    }
    float tint[3];
    const float f = flicker(l, time_s, tint);
    LightState s = lights_[l];
    s.intensity *= f;
    for (int c = 0; c < 3; ++c) s.color[c] *= tint[c];
    rt_.set_light(l, s);
    room -= cost;
    ++updated;
  }
  // Lights the budget skipped this frame come first next frame.
  flicker_cursor_ = first_skipped >= 0 ? static_cast<uint32_t>(first_skipped)
                                       : (flicker_cursor_ + 1) % std::max(n, 1u);
  return updated;
}

void InnGame::flame_glow(float* out) const {
  for (uint32_t l = 0; l < lights_.size(); ++l) {
    float shown[3] = {0.0f, 0.0f, 0.0f};
    if (rt_.ready()) rt_.planner().shown_factor(l, shown);
    out[l] = max3(shown) / authored_factor_[l];
  }
}

void InnGame::shown_objects(uint8_t* out) const {
  for (uint32_t o = 0; o < rt_.object_count(); ++o) {
    out[o] = rt_.ready() ? rt_.planner().shown_visible(o) : rt_.object_visible(o);
  }
}

}  // namespace lightpatch::inn
