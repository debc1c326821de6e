// Traced gather rays as a file: a cook's gather job writes the operator (indirect/gather.h) once,
// and every light-group job of the same scene, layout and options loads it instead of tracing
// it again (job_dir.h).
//
// Format version 3 (2 had no per-texel coarse texels, `fine`; 1 no near hits), little-endian:
//   header (64 bytes, GatherFileHeader): magic, version, header size, file size, the job's hash,
//     the crc (CRC-32 of the whole file read with the crc field as zero), the counts the file was
//     traced for (texels, objects, coarse texels, rays per coarse texel)
//   the operator's scalars (GatherScalars), then its arrays in a fixed order, each a u64 element
//     count followed by the elements (u8, u32, f32 or 3 x f32); the largest, the static hit of
//     every ray, is bit-packed: a u8 bit width w, then each hit as w bits (least significant
//     first), kNoTexel stored as the coarse-texel count. Nested lists are an offsets array
//     (count + 1 entries) and a values array.
// The reader checks sizes against the bytes present before allocating, and every index against
// what it indexes (texels, coarse texels, blocks, tiles, objects, rays), so that a file that
// passes is safe for the solver to follow.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "indirect/gather.h"

namespace lightpatch::cooker {

struct GatherFileHeader {
  char magic[8];  // "LPGATHER"
  uint32_t version;
  uint32_t header_size;
  uint64_t file_size;
  uint8_t job_hash[16];
  uint32_t crc;
  uint32_t texels;   // TexelSet size the operator was traced on
  uint32_t objects;  // Scene::objects
  uint32_t coarse;   // coarse texels
  uint32_t rays;     // rays per coarse texel
  uint32_t reserved;
};
static_assert(sizeof(GatherFileHeader) == 64);

struct GatherFileExpect {
  std::array<uint8_t, 16> job_hash{};
  size_t texels = 0;
  size_t objects = 0;
  int rays = 0;   // the preset's rays per coarse texel
  int level = 0;  // the preset's indirect level
};

std::vector<uint8_t> encode_gather(const GatherOperator& op, const std::array<uint8_t, 16>& hash);
// Throws CookError naming what is wrong.
GatherOperator decode_gather(const uint8_t* data, size_t size, const GatherFileExpect& expect);
// The job hash the file holds, from its header (and with `check_body` its checksum). Throws.
std::array<uint8_t, 16> gather_file_hash(const uint8_t* data, size_t size, bool check_body);

}  // namespace lightpatch::cooker
