// LightMeter: measures what the light map holds on the surfaces around a light (the table under a
// candle, the wall and floor around a torch), so a scripted run can show that lighting a light
// brightens the spot in front of it. Texels are found once per light by casting rays from the
// light down and around onto the static geometry; measuring reads those texels back from the
// runtime's current light map, plus its indirect map magnified there where the pack has one (a
// stall: for scripted runs and tests, not for frames).
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "lightpatch/runtime.h"

namespace lightpatch::inn {

struct World;

class LightMeter {
 public:
  LightMeter() = default;
  ~LightMeter();
  LightMeter(const LightMeter&) = delete;
  LightMeter& operator=(const LightMeter&) = delete;

  // Creates the read-back framebuffer (current context).
  void init();

  // Light-map texels (x, y from the top-left) of the surfaces that rays from `position` hit
  // between `min_distance` and `max_distance` metres away, front faces only.
  static std::vector<glm::ivec2> texels_around(const World& world, glm::vec3 position,
                                               uint32_t map_width, uint32_t map_height,
                                               float min_distance, float max_distance);

  // Mean luminance (irradiance units) of `texels` in the runtime's light map; -1 if empty or
  // the map cannot be read.
  float measure(const Runtime& runtime, const std::vector<glm::ivec2>& texels);

  // Rec. 709 luminance of linear RGB.
  static float luminance(const float rgb[3]);

 private:
  uint32_t framebuffer_ = 0;
  std::vector<float> whole_map_;  // only when the light map is not readable through a framebuffer
  std::vector<float> indirect_;   // the indirect map read back (packs with one)
};

}  // namespace lightpatch::inn
