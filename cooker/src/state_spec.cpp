#include "lightpatch/cooker/state_spec.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <string>

#include "json_depth.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/io.h"
#include "lightpatch/cooker/printable.h"

namespace lightpatch::cooker {

namespace {

using nlohmann::json;

std::string type_name(const json& j) {
  return j.type_name();
}

// A value as messages show it: its JSON, cut (a value can be as long as the file).
std::string shown(const json& j) {
  return printable(j.dump(-1, ' ', false, json::error_handler_t::replace));
}

float finite_non_negative(const json& j, const std::string& where) {
  if (!j.is_number()) throw CookError(where + " must be a number, got " + type_name(j));
  const double v = j.get<double>();
  if (!std::isfinite(v) || v < 0.0 || v > 3.0e38) {
    throw CookError(where + " must be a finite non-negative number, got " + shown(j));
  }
  return static_cast<float>(v);
}

// A world-space vector: 3 finite numbers within the importer's world (+-1e6 m).
void parse_vec3(const json& j, const std::string& at, float out[3]) {
  if (!j.is_array() || j.size() != 3) {
    throw CookError(at + " must be an array of 3 numbers, got " + shown(j));
  }
  for (int c = 0; c < 3; ++c) {
    const json& v = j[size_t(c)];
    if (!v.is_number()) {
      throw CookError(at + "[" + std::to_string(c) + "] must be a number, got " + type_name(v));
    }
    const double d = v.get<double>();
    if (!std::isfinite(d) || std::fabs(d) > 1.0e6) {
      throw CookError(at + "[" + std::to_string(c) + "] must be finite, within +-1e6, got " +
                      shown(v));
    }
    out[c] = static_cast<float>(d);
  }
}

LightOverride parse_light(const json& j, const std::string& where) {
  if (!j.is_object()) throw CookError(where + " must be an object, got " + type_name(j));
  LightOverride o;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& key = it.key();
    const std::string at = where + "." + printable(key);
    if (key == "on") {
      if (!it->is_boolean()) throw CookError(at + " must be true or false, got " + shown(*it));
      o.has_on = true;
      o.on = it->get<bool>();
    } else if (key == "color") {
      if (!it->is_array() || it->size() != 3) {
        throw CookError(at + " must be an array of 3 numbers, got " + shown(*it));
      }
      for (int c = 0; c < 3; ++c) {
        o.color[c] = finite_non_negative((*it)[c], at + "[" + std::to_string(c) + "]");
      }
      o.has_color = true;
    } else if (key == "intensity") {
      o.intensity = finite_non_negative(*it, at);
      o.has_intensity = true;
    } else if (key == "position") {
      parse_vec3(*it, at, o.position);
      o.has_position = true;
    } else if (key == "direction") {
      parse_vec3(*it, at, o.direction);
      const double len = std::sqrt(double(o.direction[0]) * o.direction[0] +
                                   double(o.direction[1]) * o.direction[1] +
                                   double(o.direction[2]) * o.direction[2]);
      if (!(len > 1e-6)) throw CookError(at + " must not be a zero vector");
      for (float& c : o.direction) c = static_cast<float>(c / len);
      o.has_direction = true;
    } else {
      throw CookError(at + ": unknown key (expected on, color, intensity, position, direction)");
    }
  }
  return o;
}

}  // namespace

StateSpec parse_state_json(const std::string& text, const std::string& what) {
  if (json_deeper_than(text.data(), text.size(), kMaxJsonDepth)) {
    throw CookError(what + ": invalid state: JSON nested deeper than " +
                    std::to_string(kMaxJsonDepth) + " levels");
  }
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {
    // parse_error, and out_of_range for a number beyond a double (1e400).
    throw CookError(what + ": invalid JSON: " + printable(e.what(), 200));
  }
  if (!root.is_object())
    throw CookError(what + ": a state must be a JSON object, got " + type_name(root));
  StateSpec spec;
  for (auto it = root.begin(); it != root.end(); ++it) {
    const std::string& key = it.key();
    if (key == "lights") {
      if (!it->is_object())
        throw CookError(what + ": \"lights\" must be an object, got " + type_name(*it));
      for (auto l = it->begin(); l != it->end(); ++l) {
        spec.lights[l.key()] = parse_light(*l, what + ": lights." + printable(l.key()));
      }
    } else if (key == "objects") {
      if (!it->is_object())
        throw CookError(what + ": \"objects\" must be an object, got " + type_name(*it));
      for (auto o = it->begin(); o != it->end(); ++o) {
        const std::string at = what + ": objects." + printable(o.key());
        if (!o->is_object()) throw CookError(at + " must be an object, got " + type_name(*o));
        bool visible = true;
        for (auto f = o->begin(); f != o->end(); ++f) {
          if (f.key() != "visible")
            throw CookError(at + "." + printable(f.key()) + ": unknown key (expected visible)");
          if (!f->is_boolean())
            throw CookError(at + ".visible must be true or false, got " + shown(*f));
          visible = f->get<bool>();
        }
        spec.objects[o.key()] = visible;
      }
    } else {
      throw CookError(what + ": unknown key \"" + printable(key) + "\" (expected lights, objects)");
    }
  }
  return spec;
}

StateSpec load_state_file(const std::string& path) {
  const std::vector<uint8_t> bytes = read_file(path);
  return parse_state_json(std::string(bytes.begin(), bytes.end()), path);
}

std::vector<StateSpec> load_states_jsonl(const std::string& path) {
  const std::vector<uint8_t> bytes = read_file(path);
  return parse_states_jsonl(std::string(bytes.begin(), bytes.end()), path);
}

std::vector<StateSpec> parse_states_jsonl(const std::string& text, const std::string& path) {
  std::vector<StateSpec> out;
  size_t start = 0;
  int line = 0;
  while (start <= text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    ++line;
    const std::string row = text.substr(start, end - start);
    if (row.find_first_not_of(" \t\r") != std::string::npos) {
      out.push_back(parse_state_json(row, path + ":" + std::to_string(line)));
    }
    start = end + 1;
  }
  if (out.empty()) throw CookError(path + ": no states (one JSON object per line expected)");
  return out;
}

ResolvedState resolve_state(const Scene& scene, const StateSpec& state) {
  ResolvedState r;
  r.radiant.resize(scene.lights.size());
  r.position.resize(scene.lights.size());
  r.direction.resize(scene.lights.size());
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    r.radiant[i] = scene.lights[i].color * scene.lights[i].intensity;
    r.position[i] = scene.lights[i].position;
    r.direction[i] = scene.lights[i].direction;
  }
  std::vector<std::string> unknown;
  for (const auto& [name, o] : state.lights) {
    size_t i = 0;
    while (i < scene.lights.size() && scene.lights[i].name != name) ++i;
    if (i == scene.lights.size()) {
      unknown.push_back("light '" + name + "'");
      continue;
    }
    const Light& l = scene.lights[i];
    if (!l.semi_dynamic) {
      throw CookError("state changes light '" + name +
                      "', which is static (only semi-dynamic lights can change)");
    }
    if ((o.has_position || o.has_direction) && !l.moving) {
      throw CookError("state moves light '" + name +
                      "', which is not marked moving (extras \"moving\": true)");
    }
    if (o.has_position) r.position[i] = glm::vec3(o.position[0], o.position[1], o.position[2]);
    if (o.has_direction) {
      r.direction[i] = glm::vec3(o.direction[0], o.direction[1], o.direction[2]);
    }
    const glm::vec3 color = o.has_color ? glm::vec3(o.color[0], o.color[1], o.color[2]) : l.color;
    const float intensity = o.has_intensity ? o.intensity : l.intensity;
    r.radiant[i] = (o.has_on && !o.on) ? glm::vec3(0.0f) : color * intensity;
  }
  r.visible.assign(scene.objects.size(), 1);
  for (const auto& [name, vis] : state.objects) {
    size_t i = 0;
    while (i < scene.objects.size() && scene.objects[i].name != name) ++i;
    if (i == scene.objects.size()) {
      unknown.push_back("object '" + name + "'");
      continue;
    }
    r.visible[i] = vis ? 1 : 0;
  }
  if (!unknown.empty()) {
    std::string list;
    for (const std::string& u : unknown) list += (list.empty() ? "" : ", ") + u;
    throw CookError(
        "the state names what the scene does not have (or has not marked "
        "semiDynamic): " +
        list);
  }
  return r;
}

}  // namespace lightpatch::cooker
