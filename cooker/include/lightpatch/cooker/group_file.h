// A light group's baked maps as a file (a cook job's result, cook_jobs.h): the one definition of
// the format, its writer and its checked reader.
//
// Format version 3, little-endian, no padding between records:
//   header (64 bytes, GroupFileHeader)
//   map_count map records, each a MapRecord (40 bytes) followed by
//     - a bit mask of ceil(n / 8) bytes, n = rect_w * rect_h * channels: bit i (least
//       significant first) set when value i of the rectangle (row-major, channels interleaved)
//       is not +0.0; bits past n are 0;
//     - the `nonzero` values whose bits are set, float32, in the same order.
//     The map is width x height x channels; every value outside the rectangle, or whose bit is
//     clear, is +0.0. The writer stores the smallest rectangle outside which every value's bits
//     are zero: a shadow in a corner costs its corner, unlit and unused texels a bit each, and
//     the maps come back bit for bit.
//     A map's parts follow it as more records of the same owner (not counted in map_count), each
//     with its mask and values: with bit 0 of `parts` set (1), its indirect part (BakedMaps: its
//     bounce light as a block image, the light map / Layout::align, 3 channels), a record with
//     parts = 2; then with bit 2 set (4), its direct part (ShadowMap::direct: the light map's
//     size, 1 channel, 3 for the static group), a record with parts = 8. Version 2 had no
//     direct parts.
//   decision_count decision records, each a DecisionRecord (48 bytes) followed by reason_bytes
//     bytes of UTF-8 (the reason, no terminator).
// The header's crc is the CRC-32 (pack_view.h's) of the whole file read with the crc field as
// zero, and file_size the file's size: a truncated or altered file is refused before it is
// parsed.
// Map roles: 0 the group's own map (B or C_l, exactly one, first), 1 a shadow map S_ol,
// 2 a pair correction, 3 a static shadow.
//
// The reader treats the file as hostile: every size, count and index is checked with 64-bit
// arithmetic against the bytes present and the plan it is read for (map sizes, objects, lights,
// enumerations), every value must be finite, and nothing is allocated before its size is known
// to fit in the file. Limits: maps at most 16384 x 16384, 1 or 3 channels; a reason at most
// 64 KiB.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/bake_plan.h"

namespace lightpatch::cooker {

constexpr char kGroupFileMagic[8] = {'L', 'P', 'G', 'R', 'O', 'U', 'P', '\0'};
constexpr uint32_t kGroupFileVersion = 3;

struct GroupFileHeader {
  char magic[8];            // kGroupFileMagic
  uint32_t version;         // kGroupFileVersion
  uint32_t header_size;     // sizeof(GroupFileHeader)
  uint64_t file_size;       // bytes, header included
  uint8_t job_hash[16];     // the job's content hash (cook_jobs.h JobHash)
  uint32_t group;           // BakePlan::groups index
  uint32_t map_count;       // MapRecord count
  uint32_t decision_count;  // DecisionRecord count
  uint32_t crc;             // CRC-32 of the file with this field zero
  double seconds;           // the group's bake time (GroupBake::seconds)
};
static_assert(sizeof(GroupFileHeader) == 64);

struct MapRecord {
  uint32_t role;           // 0 own map, 1 shadow, 2 pair correction, 3 static shadow
  int32_t light;           // BakedMaps::lights index (shadow, pair correction), else -1
  int32_t object;          // Scene::objects index (shadow, pair's object_a, static shadow), else -1
  int32_t object_b;        // pair correction's object_b, else -1
  uint16_t width, height;  // the map (light-map texels)
  uint16_t rect_x, rect_y;  // the stored rectangle
  uint16_t rect_w, rect_h;
  uint16_t channels;  // 1 or 3
  uint16_t
      parts;  // a map: 0, or 1 (indirect part follows) | 4 (direct part follows); a part: 2 or 8
  uint64_t nonzero;  // values stored after the mask
};
static_assert(sizeof(MapRecord) == 40);

struct DecisionRecord {
  uint8_t kind;    // DecisionKind
  uint8_t stage;   // DecisionStage
  uint8_t taken;   // 0 or 1
  uint8_t forced;  // 0 or 1
  int32_t light;   // as Decision
  int32_t object;
  int32_t object_b;
  double value;  // NaN where none
  double bound;
  double seconds;
  uint32_t reason_bytes;
  uint32_t reserved;  // 0
};
static_assert(sizeof(DecisionRecord) == 48);

// What a result must agree with: the plan it is read for.
struct GroupFileExpect {
  std::array<uint8_t, 16> job_hash{};
  size_t group = 0;
  int width = 0, height = 0;  // the light map
  // The indirect parts' block images (Layout::align > 1: the light map / align), else 0 (a file
  // with an indirect part is refused).
  int indirect_width = 0, indirect_height = 0;
  size_t objects = 0;  // Scene::objects
  size_t lights = 0;   // Scene::lights
  // Most maps the group can have (its own, one per object it may shadow, one per pair of its
  // candidates): bounds what a file can make the reader allocate.
  size_t max_maps = 1;
};

// The file's bytes. `job_hash` names the job the group was baked for.
std::vector<uint8_t> encode_group(const GroupBake& g, const std::array<uint8_t, 16>& job_hash);

// The job hash a result file holds, from its header alone (magic, version, header size, and
// file_size against `size`), or with `check_body` its checksum too. Throws CookError naming what
// is wrong.
std::array<uint8_t, 16> group_file_hash(const uint8_t* data, size_t size, bool check_body);

// The group back, checked against `expect`. Throws CookError naming what is wrong.
GroupBake decode_group(const uint8_t* data, size_t size, const GroupFileExpect& expect);

}  // namespace lightpatch::cooker
