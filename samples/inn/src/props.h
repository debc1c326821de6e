// Props for the inn: furniture and small objects built from scenegen shapes, in local
// coordinates (origin on the floor, local +Z is the prop's front) and placed with a matrix.
#pragma once

#include <cstdint>
#include <map>
#include <vector>

#include <glm/glm.hpp>

#include "lightpatch/scenegen/scene_builder.h"

namespace lightpatch::inn {

// Materials of the inn (index into the scene's materials, in this order).
enum Mat : int {
  kPlaster,
  kWoodDark,
  kWoodLight,
  kWoodFloor,
  kStone,
  kBrick,
  kClothRed,
  kClothBlue,
  kClothGreen,
  kClothCream,
  kCeramic,
  kMetal,
  kWax,
  kFlame,
  kEmber,
  kWater,
  kGlass,
  kBookRed,
  kBookGreen,
  kBookBlue,
  kBookBrown,
  kBookPurple,
  kHerb,
  kScale,
  kMatCount
};

// A small deterministic generator (splitmix64): the same seed gives the same inn everywhere.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next();
  float uniform(float lo, float hi);  // [lo, hi)
  int below(int n);                   // [0, n)

 private:
  std::uint64_t state_;
};

// Geometry grouped by material; one glTF primitive per material.
struct Parts {
  std::map<int, scenegen::Geometry> by_material;
  void add(int material, const scenegen::Geometry& g, const glm::mat4& m);
  void add(int material, const scenegen::Geometry& g) { add(material, g, glm::mat4(1.0f)); }
  void append(const Parts& other, const glm::mat4& m);
  std::size_t triangle_count() const;
  std::vector<scenegen::Primitive> primitives() const;
};

// Tessellation level: full-scale props use rounded boxes and more segments; the small inn uses
// plain boxes.
struct Detail {
  int bevel_segments = 1;  // 0: plain boxes
  int round_segments = 16;
};

glm::mat4 place(glm::vec3 position, float yaw);  // translate · rotateY(yaw)

scenegen::Geometry rbox(const Detail& d, glm::vec3 min, glm::vec3 max, float bevel);

// Each adds to `p` in local coordinates transformed by `m`.
void add_table(Parts& p, const Detail& d, const glm::mat4& m, float w, float depth, float h);
void add_chair(Parts& p, const Detail& d, const glm::mat4& m);
void add_place_setting(Parts& p, const Detail& d, const glm::mat4& m);  // plate, cup, cutlery
void add_bowl(Parts& p, const Detail& d, const glm::mat4& m);
// A candle in a dish; returns the flame's local position.
glm::vec3 add_candle(Parts& p, const Detail& d, const glm::mat4& m, float height);
// A wall torch; local z = 0 is the wall; returns the flame's local position.
glm::vec3 add_torch(Parts& p, const Detail& d, const glm::mat4& m);
// Bookshelf against a wall (local z = 0 is the wall); when `slot` is non-null, leaves a gap for a
// book on the middle shelf and returns the gap's local floor-of-shelf centre in *slot.
void add_bookshelf(Parts& p, const Detail& d, Rng& rng, const glm::mat4& m, float w, float h,
                   int shelves, glm::vec3* slot);
void add_bed(Parts& p, const Detail& d, const glm::mat4& m, int blanket_material);
void add_barrel(Parts& p, const Detail& d, const glm::mat4& m);
void add_crate(Parts& p, const Detail& d, const glm::mat4& m, float size);
void add_cupboard(Parts& p, const Detail& d, Rng& rng, const glm::mat4& m, float w, float h);
void add_armchair(Parts& p, const Detail& d, const glm::mat4& m, int cloth_material);
void add_carpet(Parts& p, const Detail& d, const glm::mat4& m, float w, float depth, int material);
// Wavy curtain hanging in the local XY plane facing +Z, `w` wide from y0 to y1.
void add_curtain(Parts& p, const Detail& d, const glm::mat4& m, float w, float y0, float y1,
                 int material);
struct Fireplace {
  glm::vec3 fire;      // local position of the flames
  glm::vec3 ember;     // local position of the embers
  float mantel_top;    // local y of the mantel shelf's top
  float mantel_front;  // local z of the mantel's front edge
};
// Fireplace against a wall (local z = 0 is the wall), `w` wide, chimney breast up to `ceiling`.
Fireplace add_fireplace(Parts& p, const Detail& d, const glm::mat4& m, float w, float ceiling);
void add_bathtub(Parts& p, const Detail& d, const glm::mat4& m);
void add_bucket(Parts& p, const Detail& d, const glm::mat4& m);
void add_stool(Parts& p, const Detail& d, const glm::mat4& m);
void add_towel_rack(Parts& p, const Detail& d, const glm::mat4& m);
void add_wine_rack(Parts& p, const Detail& d, Rng& rng, const glm::mat4& m, float w, float h);

// The spell's items, in local coordinates (base on the floor of the item).
Parts make_spell_book(const Detail& d);
Parts make_item(const Detail& d, int which);  // 0 .. kItemCount-1
constexpr int kItemCount = 6;
const char* item_name(int which);

}  // namespace lightpatch::inn
