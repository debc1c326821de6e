#include "inn_generator.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>
#include <utility>

#include <glm/gtc/matrix_transform.hpp>

#include "props.h"

namespace lightpatch::inn {

using scenegen::Geometry;
using scenegen::Light;
using scenegen::LightType;
using scenegen::make_box;
using scenegen::make_quad;
using Json = nlohmann::ordered_json;

namespace {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kExteriorThickness = 0.3f;
constexpr const char* kLantern = "lantern";  // the moving light's node

// Walls of a room, by the axis they are perpendicular to and their side.
enum class Wall { kNegX, kPosX, kNegZ, kPosZ };

struct Opening {
  Wall wall;
  float center;  // world x (for ±Z walls) or z (for ±X walls)
  float width;
  float bottom;  // above the room's floor
  float height;
};

struct Room {
  std::string name{};
  glm::vec3 min{0.0f}, max{0.0f};  // interior
  std::vector<Opening> openings{};
  std::vector<glm::vec4> floor_holes{};    // (x0, z0, x1, z1)
  std::vector<glm::vec4> ceiling_holes{};  // (x0, z0, x1, z1)
  int floor_material = kWoodFloor;
  int wall_material = kPlaster;
  bool beams = true;
  Parts parts{};  // static geometry (world coordinates)
  glm::vec3 center() const { return 0.5f * (min + max); }
};

// Unit facing (into the room) of a wall.
glm::vec3 wall_normal(Wall w) {
  switch (w) {
    case Wall::kNegX:
      return {1, 0, 0};
    case Wall::kPosX:
      return {-1, 0, 0};
    case Wall::kNegZ:
      return {0, 0, 1};
    case Wall::kPosZ:
      return {0, 0, -1};
  }
  return {0, 0, 1};
}

float yaw_facing(glm::vec3 dir) {
  return std::atan2(dir.x, dir.z);
}

// A rectangle of size (W, H) in a plane origin + U·u + V·v with rectangular holes
// (u0, v0, u1, v1), split into quads; faces U × V.
void add_panel(Parts& p, int material, glm::vec3 origin, glm::vec3 U, glm::vec3 V, float W, float H,
               const std::vector<glm::vec4>& holes, float cell) {
  std::set<float> us = {0.0f, W};
  std::set<float> vs = {0.0f, H};
  for (const glm::vec4& h : holes) {
    us.insert({std::clamp(h.x, 0.0f, W), std::clamp(h.z, 0.0f, W)});
    vs.insert({std::clamp(h.y, 0.0f, H), std::clamp(h.w, 0.0f, H)});
  }
  const std::vector<float> u(us.begin(), us.end());
  const std::vector<float> v(vs.begin(), vs.end());
  for (std::size_t j = 0; j + 1 < v.size(); ++j) {
    for (std::size_t i = 0; i + 1 < u.size(); ++i) {
      const float cu = 0.5f * (u[i] + u[i + 1]);
      const float cv = 0.5f * (v[j] + v[j + 1]);
      bool in_hole = false;
      for (const glm::vec4& h : holes)
        in_hole = in_hole || (cu > h.x && cu < h.z && cv > h.y && cv < h.w);
      if (in_hole || u[i + 1] - u[i] < 1e-4f || v[j + 1] - v[j] < 1e-4f) continue;
      const int nu = std::max(1, static_cast<int>(std::ceil((u[i + 1] - u[i]) / cell)));
      const int nv = std::max(1, static_cast<int>(std::ceil((v[j + 1] - v[j]) / cell)));
      p.add(material, make_quad(origin + U * u[i] + V * v[j], origin + U * u[i + 1] + V * v[j],
                                origin + U * u[i + 1] + V * v[j + 1],
                                origin + U * u[i] + V * v[j + 1], nu, nv));
    }
  }
}

// The four faces of a box around `axis` (0 = x, 1 = y, 2 = z), facing inward: a tunnel through a
// wall or slab.
void add_tunnel(Parts& p, int material, glm::vec3 min, glm::vec3 max, int axis) {
  const Geometry box = make_box(min, max, scenegen::Facing::kInward, 1);
  Geometry g;
  for (int f = 0; f < 6; ++f) {
    if (f / 2 == axis) continue;  // faces come in pairs +X -X +Y -Y +Z -Z
    Geometry face;
    for (int k = 0; k < 4; ++k) {
      face.positions.push_back(box.positions[static_cast<std::size_t>(4 * f + k)]);
      face.normals.push_back(box.normals[static_cast<std::size_t>(4 * f + k)]);
    }
    for (int k = 0; k < 6; ++k)
      face.indices.push_back(box.indices[static_cast<std::size_t>(6 * f + k)] -
                             4u * static_cast<std::uint32_t>(f));
    g.append(face);
  }
  p.add(material, g);
}

class InnBuilder {
 public:
  explicit InnBuilder(const InnOptions& options)
      : options_(options),
        rng_(0x1A2B3C4Dull ^ (static_cast<std::uint64_t>(options.seed) * 0x9E3779B97F4A7C15ull)) {
    if (options.scale == InnScale::kSmall)
      detail_ = Detail{0, 10};
    else
      detail_ = Detail{1, 16};
  }

  Inn build();

 private:
  void add_materials();
  Room& room(const std::string& name);
  void build_shell(Room& r);
  void add_door(const std::string& a, Wall wa, const std::string& b, float center);
  void add_window(const std::string& name, Wall w, float center, bool curtains);
  void add_stairs(const std::string& upper, const std::string& lower, glm::vec4 hole);
  // Lights.
  void semi_light(const std::string& name, const std::string& room, LightType type, glm::vec3 pos,
                  glm::vec3 dir, glm::vec3 color, float intensity, float radius, bool on,
                  float range);
  void static_light(const std::string& name, LightType type, glm::vec3 pos, glm::vec3 dir,
                    glm::vec3 color, float intensity, float outer = 0.0f);
  void candle(const std::string& name, const std::string& room, glm::vec3 pos, float height,
              bool on);
  void torch(const std::string& name, const std::string& room, glm::vec3 pos_on_wall,
             glm::vec3 facing, bool on);
  // The lantern the player carries (extras.moving: its bounce light comes from the panes, its
  // direct light is the game's), lit on its hook at `hook`; `walk`: the scripted walk with it.
  void lantern(const std::string& room, glm::vec3 hook, std::vector<glm::vec3> walk);
  // The scripted steps: take the lantern, then carry it along the walk (one step a pose).
  void lantern_walk();
  // Objects.
  void object(const std::string& name, const std::string& room, const Parts& parts, glm::vec3 pos,
              float yaw);
  void item(int which, const std::string& room, glm::vec3 pos, float yaw);

  void full_layout();
  void small_layout();
  void dining_props(Room& r, int tables, bool full);
  // Steps with the first item carried beside a candle that is snuffed and lit again, then a
  // light of another room snuffed and lit again (close-ups: the carried item is lit by the light
  // probes).
  void carried_item_close_up(const std::string& item);
  void scenario_step(const std::string& name, const std::string& action, const std::string& node,
                     Json state);

  InnOptions options_;
  Rng rng_;
  Detail detail_;
  scenegen::SceneBuilder scene_;
  std::vector<Room> rooms_;
  Json state_lights_ = Json::object();
  Json state_objects_ = Json::object();
  Json steps_ = Json::array();
  std::map<std::string, std::pair<std::string, glm::vec3>> where_;  // node → (room, position)
  std::vector<std::string> semi_lights_;
  std::vector<glm::vec3> lantern_walk_;  // empty: the layout has no lantern
  std::vector<std::string> items_;
  std::vector<std::string> placed_;
  glm::vec3 altar_{0.0f};  // where the placed items go, in front of the main fireplace
  std::string altar_room_;
  std::string main_fire_;
  InnStats stats_;
};

void InnBuilder::add_materials() {
  struct M {
    const char* name;
    glm::vec3 c;
    float metallic;
    glm::vec3 e;
    float strength;
  };
  const M kMats[kMatCount] = {
      {"plaster", {0.72f, 0.68f, 0.6f}, 0, {0, 0, 0}, 1},
      {"wood_dark", {0.22f, 0.13f, 0.07f}, 0, {0, 0, 0}, 1},
      {"wood_light", {0.48f, 0.33f, 0.19f}, 0, {0, 0, 0}, 1},
      {"wood_floor", {0.34f, 0.22f, 0.12f}, 0, {0, 0, 0}, 1},
      {"stone", {0.42f, 0.41f, 0.38f}, 0, {0, 0, 0}, 1},
      {"brick", {0.5f, 0.25f, 0.17f}, 0, {0, 0, 0}, 1},
      {"cloth_red", {0.62f, 0.07f, 0.05f}, 0, {0, 0, 0}, 1},
      {"cloth_blue", {0.07f, 0.14f, 0.5f}, 0, {0, 0, 0}, 1},
      {"cloth_green", {0.1f, 0.42f, 0.13f}, 0, {0, 0, 0}, 1},
      {"cloth_cream", {0.82f, 0.77f, 0.62f}, 0, {0, 0, 0}, 1},
      {"ceramic", {0.86f, 0.85f, 0.8f}, 0, {0, 0, 0}, 1},
      {"metal", {0.56f, 0.56f, 0.55f}, 0.8f, {0, 0, 0}, 1},
      {"wax", {0.9f, 0.86f, 0.72f}, 0, {0, 0, 0}, 1},
      {"flame", {1.0f, 0.8f, 0.4f}, 0, {1.0f, 0.6f, 0.2f}, 4.0f},
      {"ember", {0.1f, 0.05f, 0.03f}, 0, {1.0f, 0.25f, 0.05f}, 1},
      {"water", {0.18f, 0.3f, 0.35f}, 0, {0, 0, 0}, 1},
      {"glass", {0.35f, 0.55f, 0.75f}, 0, {0, 0, 0}, 1},
      {"book_red", {0.45f, 0.08f, 0.06f}, 0, {0, 0, 0}, 1},
      {"book_green", {0.08f, 0.3f, 0.12f}, 0, {0, 0, 0}, 1},
      {"book_blue", {0.08f, 0.12f, 0.38f}, 0, {0, 0, 0}, 1},
      {"book_brown", {0.36f, 0.22f, 0.1f}, 0, {0, 0, 0}, 1},
      {"book_purple", {0.35f, 0.08f, 0.45f}, 0, {0, 0, 0}, 1},
      {"herb", {0.25f, 0.5f, 0.12f}, 0, {0, 0, 0}, 1},
      {"dragon_scale", {0.7f, 0.12f, 0.08f}, 0.3f, {0, 0, 0}, 1},
  };
  for (int i = 0; i < kMatCount; ++i) {
    scenegen::Material m;
    m.name = kMats[i].name;
    // Small seeded variation of the albedo keeps seeds distinguishable without changing the look.
    const float jitter = rng_.uniform(0.95f, 1.05f);
    m.base_color = glm::vec4(glm::clamp(kMats[i].c * jitter, 0.0f, 1.0f), 1.0f);
    m.metallic = kMats[i].metallic;
    m.roughness = 0.8f;
    m.emissive = kMats[i].e;
    m.emissive_strength = kMats[i].strength;
    scene_.add_material(m);
  }
}

Room& InnBuilder::room(const std::string& name) {
  for (Room& r : rooms_) {
    if (r.name == name) return r;
  }
  throw std::logic_error("inn: no room " + name);
}

void InnBuilder::build_shell(Room& r) {
  const glm::vec3 s = r.max - r.min;
  const float cell = detail_.bevel_segments > 0 ? 1.0f : 4.0f;
  auto holes_for = [&](Wall w, float origin_u, float sign) {
    std::vector<glm::vec4> holes;
    for (const Opening& o : r.openings) {
      if (o.wall != w) continue;
      const float u = sign * (o.center - origin_u);
      holes.emplace_back(u - o.width / 2, o.bottom, u + o.width / 2, o.bottom + o.height);
    }
    return holes;
  };
  const glm::vec3 Y(0, 1, 0);
  // Each wall: origin, U (so that U × Y faces into the room).
  add_panel(r.parts, r.wall_material, {r.min.x, r.min.y, r.max.z}, {0, 0, -1}, Y, s.z, s.y,
            holes_for(Wall::kNegX, r.max.z, -1), cell);
  add_panel(r.parts, r.wall_material, {r.max.x, r.min.y, r.min.z}, {0, 0, 1}, Y, s.z, s.y,
            holes_for(Wall::kPosX, r.min.z, 1), cell);
  add_panel(r.parts, r.wall_material, {r.min.x, r.min.y, r.min.z}, {1, 0, 0}, Y, s.x, s.y,
            holes_for(Wall::kNegZ, r.min.x, 1), cell);
  add_panel(r.parts, r.wall_material, {r.max.x, r.min.y, r.max.z}, {-1, 0, 0}, Y, s.x, s.y,
            holes_for(Wall::kPosZ, r.max.x, -1), cell);
  // Floor: U = +Z, V = +X faces +Y; ceiling: U = +X, V = +Z faces −Y.
  std::vector<glm::vec4> fh, ch;
  for (const glm::vec4& h : r.floor_holes)
    fh.emplace_back(h.y - r.min.z, h.x - r.min.x, h.w - r.min.z, h.z - r.min.x);
  for (const glm::vec4& h : r.ceiling_holes)
    ch.emplace_back(h.x - r.min.x, h.y - r.min.z, h.z - r.min.x, h.w - r.min.z);
  add_panel(r.parts, r.floor_material, r.min, {0, 0, 1}, {1, 0, 0}, s.z, s.x, fh, cell);
  add_panel(r.parts, r.wall_material, {r.min.x, r.max.y, r.min.z}, {1, 0, 0}, {0, 0, 1}, s.x, s.z,
            ch, cell);
  // Skirting boards and ceiling beams (full scale).
  if (detail_.bevel_segments > 0 && r.beams) {
    for (float x = r.min.x + 1.2f; x < r.max.x - 0.6f; x += 1.6f) {
      r.parts.add(kWoodDark, rbox(detail_, {x - 0.1f, r.max.y - 0.25f, r.min.z},
                                  {x + 0.1f, r.max.y + 0.01f, r.max.z}, 0.02f));
    }
  }
}

void InnBuilder::add_door(const std::string& a, Wall wa, const std::string& b, float center) {
  Room& ra = room(a);
  Room& rb = room(b);
  const Wall wb = wa == Wall::kPosX   ? Wall::kNegX
                  : wa == Wall::kNegX ? Wall::kPosX
                  : wa == Wall::kPosZ ? Wall::kNegZ
                                      : Wall::kPosZ;
  const float w = 1.0f, h = 2.1f;
  ra.openings.push_back({wa, center, w, 0.0f, h});
  rb.openings.push_back({wb, center, w, 0.0f, h});
  glm::vec3 lo, hi;
  int axis;
  if (wa == Wall::kPosX || wa == Wall::kNegX) {
    const float x0 = wa == Wall::kPosX ? ra.max.x : rb.max.x;
    const float x1 = wa == Wall::kPosX ? rb.min.x : ra.min.x;
    lo = {x0, ra.min.y, center - w / 2};
    hi = {x1, ra.min.y + h, center + w / 2};
    axis = 0;
  } else {
    const float z0 = wa == Wall::kPosZ ? ra.max.z : rb.max.z;
    const float z1 = wa == Wall::kPosZ ? rb.min.z : ra.min.z;
    lo = {center - w / 2, ra.min.y, z0};
    hi = {center + w / 2, ra.min.y + h, z1};
    axis = 2;
  }
  add_tunnel(ra.parts, kWoodDark, lo, hi, axis);
  // The door leaf, open against the wall in room a.
  const glm::vec3 n = wall_normal(wa);
  const glm::vec3 along = glm::vec3(n.z, 0, -n.x);  // along the wall
  const glm::vec3 hinge =
      (axis == 0 ? glm::vec3(wa == Wall::kPosX ? ra.max.x : ra.min.x, ra.min.y, center)
                 : glm::vec3(center, ra.min.y, wa == Wall::kPosZ ? ra.max.z : ra.min.z)) +
      along * (w / 2 + 0.02f);
  const glm::mat4 m = place(hinge, yaw_facing(along));
  ra.parts.add(kWoodLight,
               rbox(detail_, {-0.03f, 0.01f, 0.0f}, {0.03f, h - 0.02f, w - 0.04f}, 0.01f), m);
  ra.parts.add(kMetal, scenegen::make_sphere(0.03f, 8, 5),
               m * glm::translate(glm::mat4(1.0f), {0.06f, 1.0f, w - 0.15f}));
}

void InnBuilder::add_window(const std::string& name, Wall w, float center, bool curtains) {
  Room& r = room(name);
  const float width = 1.2f, bottom = 0.9f, height = 1.3f;
  r.openings.push_back({w, center, width, bottom, height});
  const glm::vec3 n = wall_normal(w);
  glm::vec3 lo, hi;
  int axis;
  float plane;
  if (w == Wall::kNegX || w == Wall::kPosX) {
    plane = w == Wall::kNegX ? r.min.x : r.max.x;
    const float outer = plane - n.x * kExteriorThickness;
    lo = {std::min(plane, outer), r.min.y + bottom, center - width / 2};
    hi = {std::max(plane, outer), r.min.y + bottom + height, center + width / 2};
    axis = 0;
  } else {
    plane = w == Wall::kNegZ ? r.min.z : r.max.z;
    const float outer = plane - n.z * kExteriorThickness;
    lo = {center - width / 2, r.min.y + bottom, std::min(plane, outer)};
    hi = {center + width / 2, r.min.y + bottom + height, std::max(plane, outer)};
    axis = 2;
  }
  add_tunnel(r.parts, kPlaster, lo, hi, axis);
  // Window bars in the middle of the reveal: one vertical, one horizontal.
  const glm::vec3 mid = 0.5f * (lo + hi);
  const glm::vec3 across = axis == 0 ? glm::vec3(0, 0, 1) : glm::vec3(1, 0, 0);
  const glm::vec3 through = axis == 0 ? glm::vec3(1, 0, 0) : glm::vec3(0, 0, 1);
  const float bar = 0.03f;
  r.parts.add(kWoodDark,
              make_box(mid - across * bar - through * bar - glm::vec3(0, height / 2, 0),
                       mid + across * bar + through * bar + glm::vec3(0, height / 2, 0)));
  r.parts.add(kWoodDark,
              make_box(mid - across * (width / 2) - through * bar - glm::vec3(0, bar, 0),
                       mid + across * (width / 2) + through * bar + glm::vec3(0, bar, 0)));
  // Sill.
  const glm::vec3 sill_center = glm::vec3(mid.x, r.min.y + bottom, mid.z) + n * 0.0f;
  const glm::vec3 ext = across * (width / 2 + 0.1f) + glm::vec3(0, 0.04f, 0) + glm::abs(n) * 0.12f;
  r.parts.add(
      kWoodDark,
      rbox(detail_, sill_center - glm::vec3(ext.x, 0.04f, ext.z) + n * 0.12f - glm::vec3(0, 0, 0),
           sill_center + glm::vec3(ext.x, 0.0f, ext.z) + n * 0.12f, 0.01f));
  if (curtains) {
    const int cloth = rng_.below(2) == 0 ? kClothRed : kClothGreen;
    for (int side : {-1, 1}) {
      const glm::vec3 pos = glm::vec3(mid.x, r.min.y, mid.z) + n * 0.03f +
                            across * (static_cast<float>(side) * (width / 2 + 0.3f));
      // Curtain local +Z = into the room; local +X = across.
      const glm::mat4 m = place(pos, yaw_facing(n));
      add_curtain(r.parts, detail_, m, 0.55f, 0.5f, bottom + height + 0.25f, cloth);
    }
  }
}

void InnBuilder::add_stairs(const std::string& upper, const std::string& lower, glm::vec4 hole) {
  Room& up = room(upper);
  Room& low = room(lower);
  up.floor_holes.push_back(hole);
  low.ceiling_holes.push_back(hole);
  add_tunnel(up.parts, kStone, {hole.x, low.max.y, hole.y}, {hole.z, up.min.y, hole.w}, 1);
  // Steps descend along +Z from the upper floor to the lower one.
  const float drop = up.min.y - low.min.y;
  const int steps = 14;
  const float rise = drop / static_cast<float>(steps);
  const float run = (hole.w - hole.y) / static_cast<float>(steps);
  for (int i = 0; i + 1 < steps; ++i) {
    const float top = up.min.y - rise * static_cast<float>(i + 1);
    low.parts.add(kWoodDark,
                  rbox(detail_, {hole.x, low.min.y, hole.y + run * static_cast<float>(i)},
                       {hole.z, top, hole.y + run * static_cast<float>(i + 1)}, 0.01f));
  }
  // A railing along the open side of the hole in the upper room.
  const Geometry post = scenegen::make_cylinder(0.03f, 0.95f, 8);
  for (float z = hole.y; z <= hole.w + 1e-3f; z += (hole.w - hole.y) / 4.0f) {
    up.parts.add(kWoodDark, post, glm::translate(glm::mat4(1.0f), {hole.z + 0.05f, up.min.y, z}));
  }
  up.parts.add(kWoodDark, rbox(detail_, {hole.z + 0.01f, up.min.y + 0.95f, hole.y - 0.03f},
                               {hole.z + 0.09f, up.min.y + 1.0f, hole.w + 0.03f}, 0.01f));
}

void InnBuilder::semi_light(const std::string& name, const std::string& room_name, LightType type,
                            glm::vec3 pos, glm::vec3 dir, glm::vec3 color, float intensity,
                            float radius, bool on, float range) {
  Light l;
  l.type = type;
  l.color = color;
  l.intensity = intensity;
  l.range = range;
  if (type == LightType::kSpot) {
    l.inner_cone_angle = 0.6f;
    l.outer_cone_angle = 1.3f;
  }
  scene_.add_light_node(name, l, pos, dir, true, radius);
  semi_lights_.push_back(name);
  where_[name] = {room_name, pos};
  if (!on) state_lights_[name] = Json{{"on", false}};
  ++stats_.semi_dynamic_lights;
}

void InnBuilder::static_light(const std::string& name, LightType type, glm::vec3 pos, glm::vec3 dir,
                              glm::vec3 color, float intensity, float outer) {
  Light l;
  l.type = type;
  l.color = color;
  l.intensity = intensity;
  if (type == LightType::kSpot) {
    l.inner_cone_angle = 0.5f * outer;
    l.outer_cone_angle = outer;
  }
  scene_.add_light_node(name, l, pos, dir, false, type == LightType::kDirectional ? 0.0f : 0.05f);
  ++stats_.static_lights;
}

void InnBuilder::candle(const std::string& name, const std::string& room_name, glm::vec3 pos,
                        float height, bool on) {
  Room& r = room(room_name);
  const glm::vec3 flame = add_candle(r.parts, detail_, place(pos, 0.0f), height) + pos;
  semi_light(name, room_name, LightType::kPoint, flame, {0, -1, 0}, {1.0f, 0.72f, 0.4f}, 1.5f,
             0.015f, on, 8.0f);
}

void InnBuilder::torch(const std::string& name, const std::string& room_name, glm::vec3 pos_on_wall,
                       glm::vec3 facing, bool on) {
  Room& r = room(room_name);
  const glm::mat4 m = place(pos_on_wall, yaw_facing(facing));
  const glm::vec3 flame = glm::vec3(m * glm::vec4(add_torch(r.parts, detail_, m), 1.0f));
  semi_light(name, room_name, LightType::kPoint, flame, {0, -1, 0}, {1.0f, 0.6f, 0.3f}, 6.0f, 0.05f,
             on, 12.0f);
}

void InnBuilder::lantern(const std::string& room_name, glm::vec3 hook,
                         std::vector<glm::vec3> walk) {
  if (!options_.lantern) return;
  Light l;
  l.type = LightType::kPoint;
  l.color = {1.0f, 0.78f, 0.5f};
  l.intensity = 3.0f;
  l.range = 10.0f;
  const int node = scene_.add_light_node(kLantern, l, hook, {0, -1, 0}, true, 0.03f);
  scene_.node(node).moving = true;
  where_[kLantern] = {room_name, hook};
  lantern_walk_ = std::move(walk);
  ++stats_.moving_lights;
}

void InnBuilder::lantern_walk() {
  if (lantern_walk_.empty()) return;
  scenario_step("take_lantern", "carry", kLantern, Json::object());
  for (size_t i = 0; i < lantern_walk_.size(); ++i) {
    const glm::vec3 p = lantern_walk_[i];
    scenario_step("lantern_walk_" + std::to_string(i), "move", kLantern,
                  Json{{"lights", {{kLantern, {{"position", {p.x, p.y, p.z}}}}}}});
    // Look at the lantern from behind and above, along the walk.
    Json& st = steps_.back();
    const glm::vec3 from = i > 0 ? lantern_walk_[i - 1] : where_.at(kLantern).second;
    // Carried at a walk, 1.4 m/s, one pose a frame at 30 frames/s.
    st["frames"] = std::max(1, int(std::lround(glm::length(p - from) / 1.4f * 30.0f)));
    glm::vec3 back = from - p;
    back.y = 0.0f;
    back = glm::length(back) > 1e-3f ? glm::normalize(back) : glm::vec3(-1, 0, 0);
    const glm::vec3 cam = p + back * 1.2f + glm::vec3(0.0f, 0.45f, 0.0f);
    st["camera"] = {cam.x, cam.y, cam.z};
    st["focus"] = {p.x, p.y - 0.3f, p.z};
    st["close_up"] = true;
  }
}

void InnBuilder::object(const std::string& name, const std::string& room_name, const Parts& parts,
                        glm::vec3 pos, float yaw) {
  Parts local;
  local.append(parts, glm::rotate(glm::mat4(1.0f), yaw, glm::vec3(0, 1, 0)));
  const int mesh = scene_.add_mesh(name, local.primitives());
  scenegen::Node n;
  n.name = name;
  n.translation = pos;
  n.mesh = mesh;
  n.semi_dynamic = true;
  scene_.add_node(n);
  where_[name] = {room_name, pos};
  ++stats_.semi_dynamic_objects;
}

void InnBuilder::item(int which, const std::string& room_name, glm::vec3 pos, float yaw) {
  const Parts parts = make_item(detail_, which);
  const std::string name = item_name(which);
  object(name, room_name, parts, pos, yaw);
  // Its baked copy at its place on the altar, hidden until the player puts it there.
  const int slot = static_cast<int>(placed_.size());
  const glm::vec3 placed =
      altar_ + glm::vec3(0.0f, 0.0f, (static_cast<float>(slot) - 2.5f) * 0.45f);
  object("placed_" + name, altar_room_, parts, placed, 0.0f);
  state_objects_["placed_" + name] = Json{{"visible", false}};
  items_.push_back(name);
  placed_.push_back("placed_" + name);
  ++stats_.items;
}

void InnBuilder::dining_props(Room& r, int tables, bool full) {
  // Tables with chairs and place settings in a grid.
  const int cols = tables >= 2 ? 2 : 1;
  const int rows = (tables + cols - 1) / cols;
  const float sx = (r.max.x - r.min.x) / static_cast<float>(cols + 1);
  const float sz = (r.max.z - r.min.z) / static_cast<float>(rows + 1);
  int t = 0;
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols && t < tables; ++col, ++t) {
      const glm::vec3 pos(r.min.x + sx * static_cast<float>(col + 1) + 0.4f, r.min.y,
                          r.min.z + sz * static_cast<float>(row + 1));
      add_table(r.parts, detail_, place(pos, 0.0f), 1.6f, 0.9f, 0.76f);
      for (int side : {-1, 1}) {
        for (int k : {-1, 1}) {
          const glm::vec3 cp =
              pos + glm::vec3(0.4f * static_cast<float>(k), 0, 0.62f * static_cast<float>(side));
          add_chair(r.parts, detail_, place(cp, side > 0 ? kPi : 0.0f));
          add_place_setting(r.parts, detail_,
                            place(pos + glm::vec3(0.4f * static_cast<float>(k), 0.76f,
                                                  0.25f * static_cast<float>(side)),
                                  side > 0 ? 0.0f : kPi));
        }
      }
      add_bowl(r.parts, detail_, place(pos + glm::vec3(-0.25f, 0.76f, 0.0f), 0.0f));
      if (full)
        add_carpet(r.parts, detail_, place(pos, 0.0f), 2.6f, 1.9f, t % 2 ? kClothRed : kClothBlue);
    }
  }
}

void InnBuilder::scenario_step(const std::string& name, const std::string& action,
                               const std::string& node, Json state) {
  Json s;
  s["name"] = name;
  s["action"] = action;
  if (!node.empty()) {
    s["node"] = node;
    const auto it = where_.find(node);
    if (it != where_.end()) {
      const Room& r = room(it->second.first);
      s["room"] = r.name;
      const glm::vec3 f = it->second.second;
      s["focus"] = {f.x, f.y, f.z};
      // A camera at eye height, between the room's centre and the focus.
      const glm::vec3 c = r.center();
      const glm::vec3 cam = glm::vec3(0.5f * (c.x + f.x), r.min.y + 1.6f, 0.5f * (c.z + f.z));
      s["camera"] = {cam.x, cam.y, cam.z};
    }
  }
  s["state"] = std::move(state);
  steps_.push_back(std::move(s));
}

void InnBuilder::carried_item_close_up(const std::string& item) {
  // The candle nearest the item in its room, and the candle of another room farthest from it (a
  // small light that reaches no probe there; a fire shines through the door).
  const auto& [item_room, item_pos] = where_.at(item);
  std::string candle, far;
  float near_d = INFINITY, far_d = -1.0f;
  for (const std::string& l : semi_lights_) {
    const auto& [room_name, pos] = where_.at(l);
    const float d = glm::length(pos - item_pos);
    if (room_name == item_room && l.rfind("candle", 0) == 0 && d < near_d) {
      near_d = d;
      candle = l;
    }
  }
  if (candle.empty()) return;
  const glm::vec3 flame = where_.at(candle).second;
  for (const std::string& l : semi_lights_) {
    const auto& [room_name, pos] = where_.at(l);
    const float d = glm::length(pos - flame);
    if (room_name != item_room && l.rfind("candle", 0) == 0 && d > far_d) {
      far_d = d;
      far = l;
    }
  }
  // The camera a little above and in front of the flame (towards the room's centre), looking at
  // it, so that the carried item, held at the lower right of the view, is about 0.3 m from it.
  const Room& r = room(item_room);
  glm::vec3 toward = r.center() - flame;
  toward.y = 0.0f;
  toward = glm::length(toward) > 1e-3f ? glm::normalize(toward) : glm::vec3(1, 0, 0);
  const glm::vec3 cam = flame + toward * 0.62f + glm::vec3(0.0f, 0.4f, 0.0f);
  auto close_up = [&](const std::string& name, const std::string& light, bool on,
                      const char* held_item) {
    scenario_step(name, "light", light, Json{{"lights", {{light, {{"on", on}}}}}});
    Json& st = steps_.back();
    st["camera"] = {cam.x, cam.y, cam.z};
    st["focus"] = {flame.x, flame.y, flame.z};
    st["close_up"] = true;
    // What the step shows of the carried item's probe light (the inn's tests check it).
    st["held_item"] = held_item;
  };
  close_up("snuff_" + candle + "_by_" + item, candle, false, "near_light_off");
  close_up("light_" + candle + "_by_" + item, candle, true, "near_light_on");
  if (far.empty()) return;
  close_up("snuff_" + far + "_far_from_" + item, far, false, "other_room_light");
  close_up("light_" + far + "_far_from_" + item, far, true, "other_room_light");
}

void InnBuilder::small_layout() {
  rooms_.push_back({.name = "dining", .min = {0, 0, 0}, .max = {6, 3, 5}});
  rooms_.push_back({.name = "living_main", .min = {6.25f, 0, 0}, .max = {11, 3, 5}});
  add_door("dining", Wall::kPosX, "living_main", 3.8f);
  add_window("dining", Wall::kNegZ, 3.0f, false);
  Room& dining = room("dining");
  Room& living = room("living_main");
  dining_props(dining, 1, false);
  // Fireplace on the living room's +X wall, altar in front of it.
  const glm::mat4 fm = place({11.0f, 0, 2.5f}, -kPi / 2);
  const Fireplace f = add_fireplace(living.parts, detail_, fm, 2.0f, 3.0f);
  const glm::vec3 fire = glm::vec3(fm * glm::vec4(f.fire, 1));
  main_fire_ = "fire_main";
  semi_light(main_fire_, "living_main", LightType::kSpot, fire, {-1, -0.15f, 0},
             {1.0f, 0.55f, 0.25f}, 20.0f, 0.25f, false, 14.0f);
  static_light("ember_main", LightType::kPoint, glm::vec3(fm * glm::vec4(f.ember, 1)), {0, -1, 0},
               {1.0f, 0.35f, 0.1f}, 0.6f);
  add_carpet(living.parts, detail_, place({8.6f, 0, 2.5f}, 0.0f), 2.0f, 1.5f, kClothRed);
  living.parts.add(kStone, rbox(detail_, {9.2f, 0.0f, 1.1f}, {9.8f, 0.35f, 3.9f}, 0.02f));
  altar_ = {9.5f, 0.35f, 2.5f};
  altar_room_ = "living_main";
  candle("candle_dining_0", "dining", {3.65f, 0.76f, 2.5f}, 0.12f, false);
  torch("torch_dining_0", "dining", {0.0f, 1.9f, 2.5f}, {1, 0, 0}, false);
  candle("candle_mantel_0", "living_main", glm::vec3(fm * glm::vec4(0.6f, f.mantel_top, 0.62f, 1)),
         0.15f, false);
  static_light("moon", LightType::kDirectional, {3, 6, -4}, {0.25f, -0.55f, 1.0f},
               {0.55f, 0.65f, 1.0f}, 2.0f);
  // Spell book on a small shelf, two items.
  glm::vec3 slot;
  const glm::mat4 sm = place({1.5f, 0, 5.0f}, kPi);
  add_bookshelf(dining.parts, detail_, rng_, sm, 1.0f, 1.2f, 3, &slot);
  object("spell_book", "dining", make_spell_book(detail_), glm::vec3(sm * glm::vec4(slot, 1)), kPi);
  item(0, "dining", {3.5f, 0.76f, 2.5f}, kPi / 2);
  item(1, "living_main", {7.0f, 0.0f, 4.5f}, 0.0f);
  lantern("dining", {5.6f, 1.8f, 1.0f},
          {{4.6f, 1.3f, 1.6f},
           {5.3f, 1.3f, 3.6f},
           {6.1f, 1.3f, 3.8f},
           {7.3f, 1.3f, 3.4f},
           {8.6f, 1.3f, 2.5f}});
}

void InnBuilder::full_layout() {
  rooms_.push_back({.name = "dining", .min = {0, 0, 0}, .max = {10, 3, 8}});
  rooms_.push_back({.name = "living_main", .min = {10.25f, 0, 0}, .max = {17, 3, 8}});
  rooms_.push_back({.name = "corridor", .min = {0, 0, 8.25f}, .max = {17, 3, 10}});
  rooms_.push_back({.name = "bedroom_1", .min = {0, 0, 10.25f}, .max = {5.5f, 3, 15}});
  rooms_.push_back({.name = "bedroom_2", .min = {5.75f, 0, 10.25f}, .max = {11, 3, 15}});
  rooms_.push_back({.name = "living_small", .min = {11.25f, 0, 10.25f}, .max = {17, 3, 15}});
  rooms_.push_back(
      {.name = "bath", .min = {17.25f, 0, 8.25f}, .max = {22, 3, 15}, .floor_material = kStone});
  rooms_.push_back({.name = "cellar",
                    .min = {0, -2.8f, 0},
                    .max = {6, -0.3f, 6},
                    .floor_material = kStone,
                    .wall_material = kStone,
                    .beams = false});

  add_door("dining", Wall::kPosX, "living_main", 6.6f);
  add_door("dining", Wall::kPosZ, "corridor", 5.0f);
  add_door("living_main", Wall::kPosZ, "corridor", 12.6f);
  add_door("corridor", Wall::kPosZ, "bedroom_1", 2.75f);
  add_door("corridor", Wall::kPosZ, "bedroom_2", 8.4f);
  add_door("corridor", Wall::kPosZ, "living_small", 14.6f);
  add_door("corridor", Wall::kPosX, "bath", 9.125f);
  add_window("dining", Wall::kNegZ, 3.0f, true);
  add_window("dining", Wall::kNegZ, 7.0f, true);
  add_window("living_main", Wall::kNegZ, 13.4f, true);
  add_window("bedroom_1", Wall::kPosZ, 2.75f, true);
  add_window("bedroom_2", Wall::kPosZ, 8.4f, true);
  add_window("bath", Wall::kPosX, 11.6f, false);
  add_stairs("dining", "cellar", {0.25f, 1.0f, 1.25f, 5.0f});

  // Static lights: moonlight through the windows, embers in the hearths.
  static_light("moon", LightType::kDirectional, {8, 8, -6}, {0.25f, -0.55f, 1.0f},
               {0.55f, 0.65f, 1.0f}, 2.0f);
  static_light("moon_window_bedroom_1", LightType::kSpot, {2.75f, 3.2f, 16.5f}, {0, -0.6f, -1},
               {0.55f, 0.65f, 1.0f}, 3.0f, 0.5f);
  static_light("moon_window_bedroom_2", LightType::kSpot, {8.4f, 3.2f, 16.5f}, {0, -0.6f, -1},
               {0.55f, 0.65f, 1.0f}, 3.0f, 0.5f);
  static_light("moon_window_bath", LightType::kSpot, {23.5f, 3.2f, 11.6f}, {-1, -0.6f, 0},
               {0.55f, 0.65f, 1.0f}, 3.0f, 0.5f);

  // Dining room: four tables, cupboards, torches, candles.
  Room& dining = room("dining");
  dining_props(dining, 4, true);
  Rng& rng = rng_;
  add_cupboard(dining.parts, detail_, rng, place({2.2f, 0, 8.0f}, kPi), 1.8f, 2.1f);
  add_cupboard(dining.parts, detail_, rng, place({8.0f, 0, 8.0f}, kPi), 1.8f, 2.1f);
  add_cupboard(dining.parts, detail_, rng, place({10.0f, 0, 2.5f}, -kPi / 2), 1.6f, 2.1f);
  add_barrel(dining.parts, detail_, place({9.5f, 0, 0.5f}, 0.0f));
  add_barrel(dining.parts, detail_, place({9.5f, 0, 1.1f}, 0.4f));
  torch("torch_dining_0", "dining", {5.0f, 1.9f, 0.0f}, {0, 0, 1}, false);
  torch("torch_dining_1", "dining", {0.0f, 1.9f, 6.6f}, {1, 0, 0}, false);
  candle("candle_dining_0", "dining", {3.98f, 0.76f, 2.667f}, 0.12f, false);
  candle("candle_dining_1", "dining", {7.32f, 0.76f, 5.333f}, 0.12f, false);

  // Main living room: the fireplace with the altar for the placed items.
  Room& living = room("living_main");
  const glm::mat4 fm = place({17.0f, 0, 4.0f}, -kPi / 2);
  const Fireplace f = add_fireplace(living.parts, detail_, fm, 2.2f, 3.0f);
  main_fire_ = "fire_main";
  semi_light(main_fire_, "living_main", LightType::kSpot, glm::vec3(fm * glm::vec4(f.fire, 1)),
             {-1, -0.15f, 0}, {1.0f, 0.55f, 0.25f}, 25.0f, 0.3f, false, 16.0f);
  static_light("ember_main", LightType::kPoint, glm::vec3(fm * glm::vec4(f.ember, 1)), {0, -1, 0},
               {1.0f, 0.35f, 0.1f}, 0.8f);
  candle("candle_mantel_0", "living_main", glm::vec3(fm * glm::vec4(-0.8f, f.mantel_top, 0.62f, 1)),
         0.15f, false);
  candle("candle_mantel_1", "living_main", glm::vec3(fm * glm::vec4(0.8f, f.mantel_top, 0.62f, 1)),
         0.15f, false);
  living.parts.add(kStone, rbox(detail_, {15.0f, 0.0f, 2.4f}, {15.7f, 0.4f, 5.6f}, 0.03f));
  altar_ = {15.35f, 0.4f, 4.0f};
  altar_room_ = "living_main";
  add_carpet(living.parts, detail_, place({13.3f, 0, 4.0f}, kPi / 2), 3.0f, 2.0f, kClothRed);
  add_armchair(living.parts, detail_, place({13.0f, 0, 2.6f}, kPi / 2 - 0.4f), kClothGreen);
  add_armchair(living.parts, detail_, place({13.0f, 0, 5.4f}, kPi / 2 + 0.4f), kClothRed);
  add_table(living.parts, detail_, place({12.2f, 0, 4.0f}, kPi / 2), 0.9f, 0.6f, 0.5f);
  add_bookshelf(living.parts, detail_, rng, place({15.4f, 0, 8.0f}, kPi), 2.0f, 2.2f, 5, nullptr);
  add_bookshelf(living.parts, detail_, rng, place({10.25f, 0, 2.2f}, kPi / 2), 1.8f, 2.2f, 5,
                nullptr);

  // Corridor: torches (on at the start: the only lit semi-dynamic lights), runner, crates.
  Room& corridor = room("corridor");
  torch("torch_corridor_0", "corridor", {3.0f, 1.9f, 8.25f}, {0, 0, 1}, true);
  torch("torch_corridor_1", "corridor", {10.0f, 1.9f, 8.25f}, {0, 0, 1}, true);
  add_carpet(corridor.parts, detail_, place({8.5f, 0, 9.125f}, kPi / 2), 1.0f, 14.0f, kClothBlue);
  add_crate(corridor.parts, detail_, place({16.5f, 0, 9.6f}, 0.2f), 0.5f);
  add_crate(corridor.parts, detail_, place({16.4f, 0.5f, 9.6f}, -0.1f), 0.4f);
  add_barrel(corridor.parts, detail_, place({0.4f, 0, 9.6f}, 0.0f));
  add_bookshelf(corridor.parts, detail_, rng, place({5.6f, 0, 10.0f}, kPi), 1.8f, 2.2f, 5, nullptr);

  // Bedrooms.
  for (int b = 0; b < 2; ++b) {
    const std::string name = b == 0 ? "bedroom_1" : "bedroom_2";
    Room& r = room(name);
    const bool left = b == 0;
    const float wall_x = left ? r.min.x : r.max.x;
    const float inward = left ? 1.0f : -1.0f;
    add_bed(r.parts, detail_, place({wall_x, 0, 13.0f}, left ? kPi / 2 : -kPi / 2),
            b == 0 ? kClothRed : kClothBlue);
    add_table(r.parts, detail_, place({wall_x + inward * 0.35f, 0, 11.4f}, 0.0f), 0.5f, 0.5f, 0.6f);
    candle("candle_" + name + "_bedside", name, {wall_x + inward * 0.35f, 0.6f, 11.4f}, 0.1f,
           false);
    const float tx = left ? 3.9f : 7.4f;
    add_table(r.parts, detail_, place({tx, 0, 14.1f}, 0.0f), 1.2f, 0.7f, 0.76f);
    add_chair(r.parts, detail_, place({tx, 0, 13.45f}, 0.0f));
    candle("candle_" + name + "_table", name, {tx + 0.4f, 0.76f, 14.2f}, 0.14f, false);
    glm::vec3 slot;
    const float shelf_x = left ? r.max.x : r.min.x;
    const glm::mat4 sm = place({shelf_x, 0, 12.4f}, left ? -kPi / 2 : kPi / 2);
    add_bookshelf(r.parts, detail_, rng, sm, 1.8f, 2.2f, 5, b == 0 ? &slot : nullptr);
    if (b == 0)
      object("spell_book", name, make_spell_book(detail_), glm::vec3(sm * glm::vec4(slot, 1)),
             -kPi / 2);
    add_barrel(r.parts, detail_, place({left ? 4.9f : 10.4f, 0, 10.85f}, 0.0f));
    add_barrel(r.parts, detail_, place({left ? 4.3f : 9.8f, 0, 10.8f}, 1.0f));
    add_crate(r.parts, detail_, place({left ? 4.9f : 10.4f, 0.8f, 10.85f}, 0.3f), 0.3f);
    add_crate(r.parts, detail_, place({left ? 0.5f : 6.3f, 0, 14.5f}, 0.1f), 0.35f);
    add_crate(r.parts, detail_, place({left ? 0.95f : 6.75f, 0, 14.55f}, -0.2f), 0.25f);
    add_carpet(r.parts, detail_, place({left ? 2.4f : 8.4f, 0, 12.8f}, 0.0f), 1.6f, 2.2f,
               b == 0 ? kClothGreen : kClothRed);
  }

  // Small living room: second fireplace, armchairs, bookshelf.
  Room& ls = room("living_small");
  const glm::mat4 fm2 = place({14.1f, 0, 15.0f}, kPi);
  const Fireplace f2 = add_fireplace(ls.parts, detail_, fm2, 2.0f, 3.0f);
  semi_light("fire_small", "living_small", LightType::kSpot, glm::vec3(fm2 * glm::vec4(f2.fire, 1)),
             {0, -0.15f, -1}, {1.0f, 0.55f, 0.25f}, 20.0f, 0.25f, false, 14.0f);
  static_light("ember_small", LightType::kPoint, glm::vec3(fm2 * glm::vec4(f2.ember, 1)),
               {0, -1, 0}, {1.0f, 0.35f, 0.1f}, 0.6f);
  add_armchair(ls.parts, detail_, place({13.2f, 0, 12.6f}, 0.3f), kClothBlue);
  add_armchair(ls.parts, detail_, place({15.0f, 0, 12.6f}, -0.3f), kClothGreen);
  add_table(ls.parts, detail_, place({14.1f, 0, 11.4f}, 0.0f), 1.0f, 0.6f, 0.6f);
  candle("candle_living_small", "living_small", {14.4f, 0.6f, 11.4f}, 0.12f, false);
  add_bookshelf(ls.parts, detail_, rng, place({17.0f, 0, 12.6f}, -kPi / 2), 1.8f, 2.2f, 5, nullptr);
  add_carpet(ls.parts, detail_, place({14.1f, 0, 12.8f}, 0.0f), 2.4f, 2.0f, kClothBlue);

  // Bathing room.
  Room& bath = room("bath");
  add_bathtub(bath.parts, detail_, place({19.6f, 0, 13.8f}, 0.0f));
  add_bucket(bath.parts, detail_, place({18.0f, 0, 14.4f}, 0.0f));
  add_bucket(bath.parts, detail_, place({21.4f, 0, 9.0f}, 0.0f));
  add_stool(bath.parts, detail_, place({20.2f, 0, 11.0f}, 0.0f));
  add_stool(bath.parts, detail_, place({18.2f, 0, 12.2f}, 0.0f));
  add_towel_rack(bath.parts, detail_, place({21.9f, 0, 13.8f}, -kPi / 2));
  add_carpet(bath.parts, detail_, place({19.6f, 0, 12.6f}, 0.0f), 1.2f, 0.7f, kClothCream);
  candle("candle_bath", "bath", {18.2f, 0.46f, 12.2f}, 0.12f, false);

  // Cellar: barrels, crates, wine racks, a torch.
  Room& cellar = room("cellar");
  for (int i = 0; i < 5; ++i)
    add_barrel(
        cellar.parts, detail_,
        place({5.6f, -2.8f, 0.5f + 0.6f * static_cast<float>(i)}, 0.3f * static_cast<float>(i)));
  for (int i = 0; i < 3; ++i)
    add_barrel(
        cellar.parts, detail_,
        place({3.0f + 0.6f * static_cast<float>(i), -2.8f, 0.45f}, 0.5f * static_cast<float>(i)));
  add_wine_rack(cellar.parts, detail_, rng, place({3.6f, -2.8f, 6.0f}, kPi), 2.0f, 1.8f);
  add_wine_rack(cellar.parts, detail_, rng, place({5.3f, -2.8f, 6.0f}, kPi), 1.2f, 1.8f);
  add_crate(cellar.parts, detail_, place({3.0f, -2.8f, 3.0f}, 0.2f), 0.6f);
  add_crate(cellar.parts, detail_, place({3.8f, -2.8f, 3.2f}, -0.3f), 0.5f);
  torch("torch_cellar", "cellar", {6.0f, -1.0f, 3.6f}, {-1, 0, 0}, false);

  // The items, spread across the rooms.
  item(0, "dining", {3.83f, 0.76f, 5.333f}, kPi / 2);
  item(1, "bedroom_2", {7.0f, 0.76f, 14.1f}, 0.0f);
  item(2, "bedroom_1", {3.6f, 0.76f, 14.0f}, 0.7f);
  item(3, "cellar", {3.0f, -2.2f, 3.0f}, 0.0f);
  item(4, "bath", {20.2f, 0.46f, 11.0f}, 0.0f);
  item(5, "living_small", {13.85f, 0.6f, 11.35f}, 0.4f);
  lantern("dining", {9.6f, 1.8f, 3.0f},
          {{8.4f, 1.3f, 4.4f},
           {9.4f, 1.3f, 6.4f},
           {10.1f, 1.3f, 6.6f},
           {11.6f, 1.3f, 6.0f},
           {13.4f, 1.3f, 4.6f}});
}

Inn InnBuilder::build() {
  add_materials();
  if (options_.scale == InnScale::kSmall)
    small_layout();
  else
    full_layout();
  for (Room& r : rooms_) build_shell(r);
  for (Room& r : rooms_) {
    // The flames are their own node that casts no shadows: a light sits inside its flame, which
    // must neither block nor swallow it.
    Parts flames;
    auto f = r.parts.by_material.find(kFlame);
    if (f != r.parts.by_material.end()) {
      flames.by_material.insert(*f);
      r.parts.by_material.erase(f);
    }
    const int mesh = scene_.add_mesh("room_" + r.name, r.parts.primitives());
    scenegen::Node n;
    n.name = "room_" + r.name;
    n.mesh = mesh;
    scene_.add_node(n);
    if (!flames.by_material.empty()) {
      scenegen::Node fn;
      fn.name = "flames_" + r.name;
      fn.mesh = scene_.add_mesh(fn.name, flames.primitives());
      fn.cast_shadows = false;
      scene_.add_node(fn);
    }
  }

  // The scripted scenario: light the lights one by one, take the book, collect and place the
  // items, the spell completes (the main fire flares up violet).
  scenario_step("dark_inn", "start", "", Json::object());
  lantern_walk();
  for (const std::string& l : semi_lights_) {
    if (state_lights_.contains(l))
      scenario_step("light_" + l, "light", l, Json{{"lights", {{l, {{"on", true}}}}}});
  }
  scenario_step("take_spell_book", "take", "spell_book",
                Json{{"objects", {{"spell_book", {{"visible", false}}}}}});
  for (std::size_t i = 0; i < items_.size(); ++i) {
    scenario_step("take_" + items_[i], "take", items_[i],
                  Json{{"objects", {{items_[i], {{"visible", false}}}}}});
    if (i == 0) carried_item_close_up(items_[i]);
    scenario_step("place_" + items_[i], "place", placed_[i],
                  Json{{"objects", {{placed_[i], {{"visible", true}}}}}});
  }
  scenario_step(
      "spell_done", "spell_done", main_fire_,
      Json{{"lights",
            {{main_fire_, {{"on", true}, {"color", {0.7, 0.3, 1.0}}, {"intensity", 60.0}}}}}});

  Inn inn{std::move(scene_), Json::object(), Json::object(), stats_};
  inn.state["lights"] = state_lights_;
  inn.state["objects"] = state_objects_;
  inn.scenario["scale"] = options_.scale == InnScale::kSmall ? "small" : "full";
  inn.scenario["seed"] = options_.seed;
  inn.scenario["semi_dynamic_lights"] = semi_lights_;
  if (!lantern_walk_.empty()) inn.scenario["lantern"] = kLantern;
  inn.scenario["items"] = items_;
  inn.scenario["placed_items"] = placed_;
  inn.scenario["steps"] = steps_;
  inn.stats.triangles = inn.scene.triangle_count();
  return inn;
}

std::string sidecar(const std::string& scene_path, const char* suffix) {
  std::filesystem::path p(scene_path);
  return (p.parent_path() / (p.stem().string() + suffix)).string();
}

void write_text(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    f << text;
    f.close();
    if (!f) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw std::runtime_error("cannot write " + path);
    }
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace

Inn generate_inn(const InnOptions& options) {
  return InnBuilder(options).build();
}

std::string state_path_for(const std::string& scene_path) {
  return sidecar(scene_path, ".state.json");
}
std::string scenario_path_for(const std::string& scene_path) {
  return sidecar(scene_path, ".scenario.json");
}

void write_inn(const Inn& inn, const std::string& path, bool draco) {
  scenegen::WriteOptions options;
  options.draco = draco;
  inn.scene.write(path, options);
  Json scenario = inn.scenario;
  scenario["scene"] = std::filesystem::path(path).filename().string();
  scenario["initial_state"] = std::filesystem::path(state_path_for(path)).filename().string();
  write_text(state_path_for(path), inn.state.dump(1) + "\n");
  write_text(scenario_path_for(path), scenario.dump(1) + "\n");
}

}  // namespace lightpatch::inn
