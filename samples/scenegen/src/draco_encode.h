// Draco encoding of one primitive for KHR_draco_mesh_compression (private to scenegen).
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "lightpatch/scenegen/geometry.h"

namespace lightpatch::scenegen {

struct DracoSettings {
  int position_bits = 14;
  int normal_bits = 10;
  int texcoord_bits = 12;
  int speed = 5;
};

struct DracoPrimitive {
  std::vector<std::uint8_t> bytes;
  std::map<std::string, int> attribute_ids;  // glTF semantic → Draco attribute unique id
  std::size_t point_count = 0;               // vertices after decoding
  std::size_t face_count = 0;                // triangles after decoding
};

// Encodes `g` (checked) with Edgebreaker; throws std::runtime_error when Draco fails.
DracoPrimitive encode_draco(const Geometry& g, const DracoSettings& settings);

}  // namespace lightpatch::scenegen
