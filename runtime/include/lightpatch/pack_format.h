// lightpatch pack format, version 7: the one definition shared by the cooker's writer and the
// runtime's reader.
//
// A pack is one little-endian file, usable straight from a read-only memory mapping:
//
//   Header (64 bytes) | SectionEntry[section_count] | sections...
//
// Every section starts at a multiple of kSectionAlignment from the start of the file; atlas pixel
// data is therefore aligned for glTexImage2D/glTexSubImage2D with GL_UNPACK_ALIGNMENT 4. All
// offsets are byte offsets from the start of the file; there are no pointers. Records are fixed
// size, with sizes and field offsets pinned by static_assert below. Reserved fields are zero.
//
// Sections (each at most once; "required" ones must be present):
//   kLights      (required) LightRecord[light_count]
//   kObjects     (required) ObjectRecord[object_count]        semi-dynamic objects
//   kGroups      (required) GroupRecord[group_count]          contiguous patch ranges per owner
//   kPatches     (required) PatchRecord[patch_count]          sorted by group
//   kAtlases     (required) AtlasRecord[atlas_count]
//   kAtlasData   (required) RGBA8 pixels of every atlas, each atlas aligned to kSectionAlignment
//   kStrings     (required) UTF-8 names, not NUL-terminated, referenced by offset/length
//   kMeshes      (optional) MeshRecord[mesh_count]            light-map UVs of the baked meshes
//   kMeshData    (optional) MeshVertex[] and uint32 indices referenced by MeshRecord
//   kProbes      (optional) ProbeRecord[probe_count]           light probes (see below)
//   kProbeGrid   (optional, with kProbes) ProbeGridRecord, then uint32 probe index per grid point
//   kProbeSets   (with kProbes) ProbeSetRecord[]               contiguous entry ranges per owner
//   kProbeEntries (with kProbes) ProbeEntry[]                  sorted by set
//   kMovingLights (optional) MovingLightRecord[]               one per light flagged moving
//   kPanes       (with kMovingLights) PaneRecord[]             one per light of type kLightPane
//
// Table checksum: CRC-32 (IEEE 802.3, reflected, poly 0xEDB88320) over the bytes of the section
// index and of every section except kAtlasData and kMeshData, in index order, with the header's
// table_checksum field itself excluded (the header is not covered).
//
// Decoding a patch texel: byte q in [0,255] of the patch's channel(s):
//   x = q / 255
//   v = scale * x           (kEncodingLinear)
//   v = scale * x * x       (kEncodingSquare: sqrt-encoded darks keep precision)
//   value = kFlagNegative ? -v : v
// A 3-channel patch adds its three values to the map's R, G, B; a 1-channel patch adds its value
// to all three (grey) or to the one channel its flags name (patch_destination()). Each value
// added to map channel c is first multiplied by the patch's tint, PatchRecord::tint[c] / 255
// (255 for all three: no tint), so that a 1-channel patch can carry light of one colour
// (bounce light tinted by an albedo) that would otherwise take three channels. A 2-channel patch
// (channels `channel` and `channel` + 1) carries light of two colours: it adds
// v0 * tint[c] / 255 + v1 * tint_b[c] / 255 to map channel c (two lights' colours, or one
// light's direct light and its bounce off a coloured wall, in one quad).
// Values are irradiance in the lights' units (W/m^2-like "lux" for intensity 1 of the owning
// light for contribution/shadow/correction patches; absolute for base patches).
//
// Two target maps. Bounce light is smooth, so a pack may store it at a reduced resolution: the
// indirect map, lightmap_width / indirect_scale x lightmap_height / indirect_scale texels
// (Header::indirect_scale 2, 4 or 8; 0: the pack has none). A patch draws into the light map
// (PatchRecord::target kTargetLightMap, rectangles in light-map texels) or into the indirect map
// (kTargetIndirectMap, rectangles in indirect-map texels). What a game lights a surface with, at
// light-map UV (u, v), is
//   light(u, v) = L(u, v) + I(u, v)
// where L is the light map sampled at its texel (or bilinearly, as the game likes) and I is the
// indirect map sampled bilinearly with its texel centres at ((i + 0.5) / W_i, (j + 0.5) / H_i),
// clamped to its edge texels: at the centre of light-map texel (x, y), I is interpolated at
// indirect-texel coordinates ((x + 0.5) / s - 0.5, (y + 0.5) / s - 0.5). The cooker lays charts
// out on s x s blocks with a ring of blocks of their own, so that interpolation never mixes two
// charts; the light map holds what the indirect map cannot (direct light, sharp bounce detail).
// The bilinear filter still blends across a crease or a contact inside a chart (a wall and the
// floor it is unwrapped with), so the light map may be negative there: it holds the map less the
// magnified indirect map. Neither map is clamped on its own; a game lights with max(L + I, 0).
//
// Light probes: points in the free space of the scene where moving things (a character, a carried
// object) take their light. Each probe holds, per owner exactly as the map's groups do (base,
// a light's contribution, a light's shadow of an object, an object's static shadow), the
// irradiance that owner brings to the probe as order-2 spherical harmonics (9 coefficients per
// channel), so a probe follows the state by the same sum as the light map:
//   E(n) = sum_sets sign(kind) * factor * sum_k sh[k] * Y_k(n),   lit with max(E(n), 0)
// (group_rules.h: the sign, the factor f_l or 1, when the state draws a set). Pair corrections
// have no probe sets. Y_k is the real SH basis in the order Y00, Y1-1, Y10, Y11, Y2-2, Y2-1, Y20,
// Y21, Y22 of the unit direction n = (x, y, z) in world space (glTF: +Y up):
//   0.282095; 0.488603 y, 0.488603 z, 0.488603 x; 1.092548 xy, 1.092548 yz,
//   0.315392 (3z^2 - 1), 1.092548 xz, 0.546274 (x^2 - y^2)
// and the coefficients already include the cosine lobe's convolution, so E(n) is the irradiance
// of a surface facing n (same units as the patches). Probes on a regular grid (kProbeGrid) are
// blended trilinearly, leaving out a corner the query point cannot reach along the axes within
// the probe's reach (a wall between them).
//
// Moving lights (docs/moving_lights.md; precomputed radiance maps, Szecsi & Szirmay-Kalos): a
// light whose LightRecord has kLightFlagMoving may be moved by the game. Its direct light is the
// game's (a dynamic light); the pack holds its bounce light as a sum over panes. A pane is a
// patch of static surface (clustered texels, close and alike in orientation); its light is a
// pseudo-light of type kLightPane in the light table, with one contribution group holding the
// bounce light everywhere when the pane's texels receive irradiance 1 (grey). The runtime sets
// each pane's factor to the irradiance the moving lights give it,
//   f_pane = sum over moving lights m (on) of colour_m * intensity_m * w(m, pane)
//   w(m, pane) = V(m, pane) * (1/M) * sum_i E(m, x_i, n_i)
// over the pane's M entry points (x_i, n_i), with E the KHR_lights_punctual irradiance of a unit
// light at the light's pose (spot cone and range window as the cooker's direct light) with the
// squared distance floored at the pane's radius squared, and V the pane's visibility of the
// light's position (PaneRecord: a hemispherical depth map from the pane's eye, filtered). The
// pane lights' authored colour is that factor for the moving lights' authored poses and
// states (intensity 1), so the authored state of every light is consistent. Pane lights have no
// name and no shadow or pair-correction group; a pane's probe set is a contribution set too (the
// light its members at irradiance 1 and its map reflect towards the probe: at a probe even the
// members' first bounce is indirect light). Moving lights have no group and no probe set.
//
// Anchors (docs/moving_lights.md, "Anchors"): instead of panes, a pack may hold the moving lights'
// bounce light on a lattice of light positions in the scene's free space. An anchor is a
// PaneRecord with point_count 0 (a pack's pane records are all panes or all anchors); its group
// holds the bounce light of a unit moving light (colour (1,1,1), intensity 1, the moving lights'
// shared range and radius) standing at the anchor. The runtime blends the anchors around each
// moving light, trilinearly over the lattice, leaving out an anchor that does not see the light:
//   f_anchor = sum over moving lights m (on) of colour_m * intensity_m * w(m, anchor)
//   w(m, a) = T(p_m - a) * V(a, p_m) / sum over anchors b of T(p_m - b) * V(b, p_m)
// with T(d) = prod over axes of max(0, 1 - |d_i| / spacing) (the lattice's tent, spacing the
// anchors' shared PaneRecord::radius) and V the anchor's filtered visibility of p_m (its
// spherical depth map); w is 0 where the sum is 0 (no anchor around sees the light).
#pragma once

#include <cstddef>
#include <cstdint>

namespace lightpatch::pack {

constexpr uint32_t kMagic = 0x314B504Cu;  // "LPK1" read as little-endian bytes 'L','P','K','1'
// Version 2: MeshRecord grew to 64 bytes with flags and each mesh instance's light-map scale and
// offset (kMeshFlagTexcoord1). Version 3: atlas sides are multiples of kAtlasAlign, no longer
// powers of two (a version 2 reader would call such a pack corrupt), and patches touch in the
// atlas (no gutter); a 1-channel patch may draw into one map channel (kFlagDestinationMask).
// Version 4: light probes (sections 10-13). Version 5: moving lights and their panes (sections
// 14-15, LightRecord::flags, kLightPane); later in version 5, magnified patches (PatchFlags
// kFlagLevelMask), which a reader built before them refuses as unknown patch flags. Version 6:
// PatchRecord grew to 28 bytes with a per-patch tint. Version 7: 2-channel patches with a second
// tint (PatchRecord::tint_b; records of 32 bytes); later in version 7, anchors (PaneRecord with
// point_count 0), which a reader built before them refuses as panes without entry points. A
// reader accepts its own version only (a
// pack of another version is refused with a message to cook it again).
constexpr uint32_t kVersion = 7;
constexpr uint32_t kSectionAlignment = 256;
constexpr uint16_t kNone16 = 0xFFFFu;  // "no light" / "no object" in 16-bit owner fields
constexpr uint32_t kMaxAtlasSize = 16384;
constexpr uint32_t kAtlasAlign = 4;  // atlas sides are multiples of this (4x4 compression blocks)
constexpr uint32_t kMaxLightmapSize = 16384;

enum SectionType : uint32_t {
  kSectionLights = 1,
  kSectionObjects = 2,
  kSectionGroups = 3,
  kSectionPatches = 4,
  kSectionAtlases = 5,
  kSectionAtlasData = 6,
  kSectionStrings = 7,
  kSectionMeshes = 8,
  kSectionMeshData = 9,
  kSectionProbes = 10,
  kSectionProbeGrid = 11,
  kSectionProbeSets = 12,
  kSectionProbeEntries = 13,
  kSectionMovingLights = 14,
  kSectionPanes = 15,
};
constexpr uint32_t kSectionTypeMax = 15;

struct Header {
  uint32_t magic;            // kMagic
  uint32_t version;          // kVersion
  uint64_t file_size;        // total bytes; must equal the mapped size
  uint32_t section_count;    // entries in the section index that follows the header
  uint32_t table_checksum;   // CRC-32, see above
  uint32_t lightmap_width;   // texels of the recomposed light map
  uint32_t lightmap_height;  // texels
  uint32_t light_count;
  uint32_t object_count;
  uint32_t group_count;
  uint32_t patch_count;
  uint32_t atlas_count;
  uint32_t mesh_count;
  uint32_t flags;  // reserved, 0
  // Light-map texels per indirect-map texel along each axis: 2, 4 or 8, dividing lightmap_width
  // and lightmap_height; 0: no indirect map (every patch targets the light map).
  uint32_t indirect_scale;
};
static_assert(sizeof(Header) == 64);
static_assert(offsetof(Header, file_size) == 8);
static_assert(offsetof(Header, section_count) == 16);
static_assert(offsetof(Header, table_checksum) == 20);
static_assert(offsetof(Header, lightmap_width) == 24);
static_assert(offsetof(Header, light_count) == 32);
static_assert(offsetof(Header, patch_count) == 44);
static_assert(offsetof(Header, mesh_count) == 52);
static_assert(offsetof(Header, indirect_scale) == 60);

struct SectionEntry {
  uint32_t type;      // SectionType
  uint32_t reserved;  // 0
  uint64_t offset;    // from file start, multiple of kSectionAlignment
  uint64_t length;    // bytes; a multiple of the record size for record sections
};
static_assert(sizeof(SectionEntry) == 24);
static_assert(offsetof(SectionEntry, offset) == 8);
static_assert(offsetof(SectionEntry, length) == 16);

// kLightPane: a moving lights' pane (see "Moving lights" above), not a light of the scene.
enum LightType : uint32_t {
  kLightPoint = 0,
  kLightSpot = 1,
  kLightDirectional = 2,
  kLightPane = 3
};

enum LightFlags : uint32_t {
  // The light moves (point or spot only): it has no group; its bounce light is the panes'.
  kLightFlagMoving = 1u << 0,
};

// A semi-dynamic light. Its contribution patches were baked for colour (1,1,1) and intensity 1
// (candela for point/spot, lux for directional). A pane (kLightPane) has name_length 0, no
// flags, and its factor is set by the runtime from the moving lights (colour: the authored one).
struct LightRecord {
  uint32_t name_offset;  // into kStrings (0 for a pane)
  uint32_t name_length;  // bytes, > 0 (0 for a pane)
  float color[3];        // authored linear RGB, finite, >= 0
  float intensity;       // authored intensity, finite, >= 0 (1 for a pane)
  uint32_t type;         // LightType
  uint32_t flags;        // LightFlags; unknown bits are zero
};
static_assert(sizeof(LightRecord) == 32);
static_assert(offsetof(LightRecord, color) == 8);
static_assert(offsetof(LightRecord, intensity) == 20);
static_assert(offsetof(LightRecord, type) == 24);
static_assert(offsetof(LightRecord, flags) == 28);

// A semi-dynamic object (a glTF mesh node marked semiDynamic).
struct ObjectRecord {
  uint32_t name_offset;  // into kStrings
  uint32_t name_length;  // bytes, > 0
  uint32_t reserved[2];  // 0
};
static_assert(sizeof(ObjectRecord) == 16);

enum GroupKind : uint16_t {
  kGroupBase = 0,            // light = object_a = object_b = kNone16; added once
  kGroupContribution = 1,    // light; added with factor f_l = on * color * intensity
  kGroupShadow = 2,          // light, object_a; subtracted with f_l while object_a is visible
  kGroupPairCorrection = 3,  // light, object_a < object_b; added with f_l while both visible
  // What object_a changes in the static lights' light (B with the object present minus B): its
  // shadow and blocked bounce, the bounce it adds. light = object_b = kNone16; subtracted with
  // factor 1 while object_a is visible (paper §3.2.1: objects cast shadows under static light).
  kGroupStaticShadow = 4,
};
constexpr uint16_t kGroupKindMax = kGroupStaticShadow;

// Groups whose decoded values are subtracted from the map.
constexpr bool group_subtracts(uint16_t kind) {
  return kind == kGroupShadow || kind == kGroupStaticShadow;
}

// A contiguous range of patches with one owner. Groups are sorted by (kind, light, object_a,
// object_b); at most one group per owner; every patch belongs to exactly one group.
struct GroupRecord {
  uint16_t kind;         // GroupKind
  uint16_t light;        // light index or kNone16
  uint16_t object_a;     // object index or kNone16
  uint16_t object_b;     // object index or kNone16
  uint32_t first_patch;  // index into kPatches
  uint32_t patch_count;  // >= 1
};
static_assert(sizeof(GroupRecord) == 16);
static_assert(offsetof(GroupRecord, first_patch) == 8);

enum PatchEncoding : uint8_t { kEncodingLinear = 0, kEncodingSquare = 1 };
// The map a patch draws into (see "Two target maps" above).
enum PatchTarget : uint8_t { kTargetLightMap = 0, kTargetIndirectMap = 1 };
enum PatchFlags : uint8_t {
  kFlagNegative = 1u << 0,  // decoded values are subtracted from (added with sign -1 to) the map
  // Bits 1-2, 1-channel patches only: 0 (grey) adds the value to the map's R, G and B; 1, 2 or 3
  // adds it to R, G or B only (one channel of a tinted patch stored apart, so that it can fill an
  // atlas's alpha plane, which 3-channel patches leave to 1-channel ones).
  kFlagDestinationMask = 3u << 1,
  // Bits 3-4: the patch's level L (0..3, "Magnified patches" below). 0: the atlas rectangle
  // holds the patch texel for texel.
  kFlagLevelMask = 3u << 3,
};
constexpr unsigned kFlagDestinationShift = 1;
constexpr unsigned kFlagLevelShift = 3;
constexpr unsigned kMaxPatchLevel = 3;

// The one map channel a patch draws into (0, 1 or 2), or -1 for all three.
constexpr int patch_destination(uint8_t flags) {
  return int((flags & kFlagDestinationMask) >> kFlagDestinationShift) - 1;
}

// Magnified patches. A patch of level L > 0 is stored at 1/2^L of its target map's resolution
// per axis (smooth light, such as bounce light or a moving light's pane, costs 4^L times fewer
// atlas texels):
// PatchRecord::width and height stay its destination rectangle in target-map texels, and its
// atlas rectangle at (atlas_x, atlas_y) is ceil(width / 2^L) x ceil(height / 2^L) texels. The
// value at destination texel (x, y) of the patch (0 <= x < width, 0 <= y < height) is the
// bilinear interpolation of the patch's decoded, signed atlas values at atlas-rectangle texel
// coordinates
//   s = ((x + 0.5) / 2^L - 0.5, (y + 0.5) / 2^L - 0.5),
// i = floor(s), f = s - i, reading texels i and i + 1 per axis clamped to the rectangle
// [0, ceil(width / 2^L) - 1] x [0, ceil(height / 2^L) - 1]: a patch reads only its own texels,
// never its atlas neighbours'. Decoding (scale, square) comes before interpolation.
constexpr uint32_t patch_level(uint8_t flags) {
  return (uint32_t(flags) & kFlagLevelMask) >> kFlagLevelShift;
}
// The atlas rectangle's side for a destination side of `side` texels at level `level`.
constexpr uint32_t patch_atlas_side(uint32_t side, uint32_t level) {
  return (side + (1u << level) - 1u) >> level;
}

// One light patch: a rectangle of an atlas copied (decoded, scaled) to a rectangle of its target
// map (the light map, or the indirect map). Rectangles are in texels of that map with the origin
// at the top-left of the image (row 0 is the first row of the atlas data, and glTF v = 0). A
// group's patches that target the light map come first, then those that target the indirect map.
struct PatchRecord {
  uint16_t atlas_x, atlas_y;  // top-left texel in the atlas
  uint16_t width, height;     // destination texels, >= 1 (atlas texels: patch_atlas_side)
  uint16_t dest_x, dest_y;    // top-left texel in the target map
  uint8_t atlas;              // atlas index
  uint8_t channel;            // first atlas channel (0=R .. 3=A)
  // 1 (grey, or one map channel: PatchFlags), 2 (two tints, channel..+1, channel <= 2) or 3 (RGB
  // from channel..+2)
  uint8_t channel_count;
  uint8_t encoding;  // PatchEncoding
  float scale;       // finite, > 0
  uint8_t flags;     // PatchFlags
  uint8_t target;    // PatchTarget
  uint16_t group;    // index of the owning GroupRecord (redundant, validated)
  // Per map channel R, G, B: the value added to channel c is multiplied by tint[c] / 255
  // ("Decoding a patch texel"). 255, 255, 255 for a patch without a tint.
  uint8_t tint[3];
  // A 2-channel patch's second value's tint, as `tint` for its first; 0, 0, 0 for other patches.
  uint8_t tint_b[3];
  uint16_t reserved;  // 0
};
static_assert(sizeof(PatchRecord) == 32);
static_assert(offsetof(PatchRecord, dest_x) == 8);
static_assert(offsetof(PatchRecord, atlas) == 12);
static_assert(offsetof(PatchRecord, scale) == 16);
static_assert(offsetof(PatchRecord, flags) == 20);
static_assert(offsetof(PatchRecord, group) == 22);
static_assert(offsetof(PatchRecord, tint) == 24);
static_assert(offsetof(PatchRecord, tint_b) == 27);
static_assert(offsetof(PatchRecord, reserved) == 30);

// Whether a patch carries a tint (a factor other than 1 on some map channel).
constexpr bool patch_has_tint(const PatchRecord& p) {
  return p.channel_count == 2 || p.tint[0] != 255 || p.tint[1] != 255 || p.tint[2] != 255;
}

// An atlas: any size whose sides are multiples of kAtlasAlign (GLES 3.0 textures need not be
// powers of two; the runtime reads them with texelFetch only). Patches may touch: a texel belongs
// to at most one patch per channel, and a reader reads a patch's own rectangle only, so texels no
// patch covers (zero as the cooker writes them) never reach a map.
struct AtlasRecord {
  uint32_t width;        // texels, a multiple of kAtlasAlign in kAtlasAlign..kMaxAtlasSize
  uint32_t height;       // texels, a multiple of kAtlasAlign in kAtlasAlign..kMaxAtlasSize
  uint64_t data_offset;  // from file start, inside kAtlasData, multiple of kSectionAlignment
                         // width*height*4 bytes of RGBA8, rows top to bottom, tightly packed
};
static_assert(sizeof(AtlasRecord) == 16);

// MeshRecord::flags.
enum MeshFlags : uint16_t {
  // The instance's light-map UVs are its glTF TEXCOORD_1 placed by lightmap_scale_offset:
  // uv = TEXCOORD_1 * (scale_offset[0], scale_offset[1]) + (scale_offset[2], scale_offset[3])
  // (Unity's lightmapScaleOffset, in glTF's convention: v = 0 at the top row). A game can keep its
  // glTF loader's TEXCOORD_1 and apply this per instance; the vertices below give the same UVs.
  kMeshFlagTexcoord1 = 1u << 0,
};

// Light-map UVs of one baked glTF mesh primitive instance (one node's primitive), so a game can
// draw the scene with the layout the cooker chose (unwrapped or TEXCOORD_1). Vertices refer to
// the glTF primitive's vertices; chart cuts of an unwrap duplicate them.
struct MeshRecord {
  uint32_t name_offset;    // glTF node name, into kStrings
  uint32_t name_length;    // bytes
  uint32_t node_index;     // glTF node index
  uint32_t primitive;      // primitive index within the node's mesh
  uint64_t vertex_offset;  // from file start, inside kMeshData: MeshVertex[vertex_count]
  uint64_t index_offset;   // from file start, inside kMeshData: uint32_t[index_count]
  uint32_t vertex_count;
  uint32_t index_count;  // multiple of 3; every index < vertex_count
  uint16_t object;       // semi-dynamic object index or kNone16
  uint16_t flags;        // MeshFlags; unknown bits are zero
  uint32_t reserved1;
  // With kMeshFlagTexcoord1: scale (x, y) and offset (z, w), finite; otherwise all zero.
  float lightmap_scale_offset[4];
};
static_assert(sizeof(MeshRecord) == 64);
static_assert(offsetof(MeshRecord, vertex_offset) == 16);
static_assert(offsetof(MeshRecord, vertex_count) == 32);
static_assert(offsetof(MeshRecord, object) == 40);
static_assert(offsetof(MeshRecord, flags) == 42);
static_assert(offsetof(MeshRecord, lightmap_scale_offset) == 48);

struct MeshVertex {
  uint32_t source_vertex;  // index into the source primitive's vertex attributes
  float u, v;              // light-map UV in [0,1], glTF convention (v = 0 at the top row)
};
static_assert(sizeof(MeshVertex) == 12);

constexpr uint32_t kNone32 = 0xFFFFFFFFu;  // "no probe" in a grid cell
constexpr uint32_t kProbeShCount = 9;      // SH coefficients per channel (order 2)
constexpr uint32_t kMaxProbes = 1u << 20;
constexpr uint32_t kMaxProbeGridPoints = 1u << 22;

// One light probe. Grid probes have no name (name_length 0); probes placed by the scene (a node
// with extras "lightProbe": true) carry their node's name and may also sit on the grid.
struct ProbeRecord {
  float position[3];  // world space, metres, finite
  // Free distance from the probe along +X, -X, +Y, -Y, +Z, -Z to the nearest static surface,
  // capped at the grid spacing (metres, finite, >= 0): a grid query leaves the probe out when the
  // point is farther from it than this along an axis.
  float reach[6];
  uint32_t name_offset;  // into kStrings (0 when unnamed)
  uint32_t name_length;  // bytes; 0 for an unnamed probe
  uint32_t reserved;     // 0
};
static_assert(sizeof(ProbeRecord) == 48);
static_assert(offsetof(ProbeRecord, reach) == 12);
static_assert(offsetof(ProbeRecord, name_offset) == 36);

// The probe grid: point (i, j, k) lies at origin + spacing * (i, j, k), i < size[0] fastest. The
// section holds this record and then size[0] * size[1] * size[2] uint32 probe indices (kNone32
// where no probe is: inside geometry, or where nothing moves). A point between grid points blends
// the 8 corners of its cell; outside the grid it takes the nearest cell.
struct ProbeGridRecord {
  float origin[3];    // world space, metres, finite
  float spacing;      // metres, finite, > 0
  uint32_t size[3];   // grid points per axis, each >= 1, product <= kMaxProbeGridPoints
  uint32_t reserved;  // 0
};
static_assert(sizeof(ProbeGridRecord) == 32);
static_assert(offsetof(ProbeGridRecord, size) == 16);

// A contiguous range of probe entries with one owner, keyed like GroupRecord (kind base,
// contribution, shadow or static shadow; never pair correction). Sorted by (kind, light,
// object_a, object_b); at most one set per owner; every entry belongs to exactly one set.
struct ProbeSetRecord {
  uint16_t kind;         // GroupKind, not kGroupPairCorrection
  uint16_t light;        // light index or kNone16, as GroupRecord
  uint16_t object_a;     // object index or kNone16, as GroupRecord
  uint16_t object_b;     // kNone16
  uint32_t first_entry;  // index into kProbeEntries
  uint32_t entry_count;  // >= 1
};
static_assert(sizeof(ProbeSetRecord) == 16);
static_assert(offsetof(ProbeSetRecord, first_entry) == 8);

// What one set brings to one probe: irradiance SH coefficients sh[k * 3 + c] for basis function
// k (order above) and channel c (R, G, B), finite, in the set's units (for intensity 1 of the
// owning light, colour (1,1,1), like contribution patches; absolute for base and static shadow).
// Within a set, entries are sorted by probe, each probe at most once.
struct ProbeEntry {
  uint32_t probe;  // index into kProbes
  float sh[kProbeShCount * 3];
};
static_assert(sizeof(ProbeEntry) == 112);
static_assert(offsetof(ProbeEntry, sh) == 4);

// A moving light's authored pose and shape (the light's own LightRecord has kLightFlagMoving and
// type kLightPoint or kLightSpot). Sorted by light, each moving light exactly once.
struct MovingLightRecord {
  uint32_t light;      // index into kLights
  float position[3];   // authored, world space, metres, finite
  float direction[3];  // authored unit vector the light shines along (spots), finite
  float range;         // metres, finite, >= 0; 0 = infinite (KHR_lights_punctual)
  float inner_cone;    // radians, finite, 0 <= inner <= outer (spots)
  float outer_cone;    // radians, finite, 0 < outer <= pi/2 (spots)
  float radius;        // metres, finite, >= 0 (its sphere; the weights treat it as a point)
  uint32_t reserved;   // 0
};
static_assert(sizeof(MovingLightRecord) == 48);
static_assert(offsetof(MovingLightRecord, range) == 28);
static_assert(offsetof(MovingLightRecord, radius) == 40);

constexpr uint32_t kMaxPanePoints = 8;
constexpr uint32_t kPaneDepthSize = 16;  // the depth map is kPaneDepthSize^2 texels
constexpr uint32_t kMaxPanes = 4096;

struct PanePoint {
  float position[3];  // world space, metres, finite
  float normal[3];    // unit, finite
};
static_assert(sizeof(PanePoint) == 24);

// One pane of the moving lights. Its visibility of a light at L: with d = L - eye, if
// dot(d, normal) <= 0 it is 0; otherwise d in the pane's frame (t, b, normal), t and b from
// orthonormal_basis() below, maps to the hemi-octahedral square
//   (p, q) = (d.t, d.b) / (|d.t| + |d.b| + d.n),  (s, r) = (p + q, p - q) in [-1, 1]^2
//   texel coordinates (u, v) = ((s + 1) / 2 * N - 0.5, (r + 1) / 2 * N - 0.5),  N = kPaneDepthSize
// and V is the bilinear blend (weights of the 4 texels around (u, v), clamped to the map's edge)
// of [|d| <= depth_i] where depth_i = depth[y * N + x] / 65535 * depth_range: the distance from
// the eye to the first static surface along texel (x, y)'s centre direction (65535: none within
// depth_range, visible at any distance). Sorted by light, each pane light exactly once.
//
// An anchor (point_count 0; see "Anchors" above) is a light position: eye is where it stands,
// normal is (0, 0, 1), radius is the lattice spacing (the same for every anchor of a pack), the
// points are zero, and the depth map covers the whole sphere, octahedrally in world axes: with
// (x, y, z) = d / (|d.x| + |d.y| + |d.z|),
//   (s, r) = (x, y) where z >= 0, else ((1 - |y|) sign(x), (1 - |x|) sign(y))  (sign(0) = 1)
// and (u, v), V and depth_i as for a pane (the bilinear weights clamped at the map's edges).
struct PaneRecord {
  uint32_t light;        // index into kLights (a kLightPane)
  float eye[3];          // world space, metres, finite: where the depth map looks from
  float normal[3];       // unit, finite: the pane's orientation (the hemisphere's axis)
  float radius;          // metres, finite, > 0: the pane's extent (floors squared distances)
  float depth_range;     // metres, finite, > 0
  uint32_t point_count;  // entry points, 1..kMaxPanePoints (unused ones are zero); 0: an anchor
  PanePoint points[kMaxPanePoints];
  uint16_t depth[kPaneDepthSize * kPaneDepthSize];
};
static_assert(sizeof(PaneRecord) == 744);
static_assert(offsetof(PaneRecord, points) == 40);
static_assert(offsetof(PaneRecord, depth) == 232);

// The pane frame's tangents from its unit normal n (Duff et al. 2017, "Building an orthonormal
// basis, revisited"): the cooker's depth maps and the runtime's lookups use this one function.
inline void orthonormal_basis(const float n[3], float t[3], float b[3]) {
  const float sign = n[2] >= 0.0f ? 1.0f : -1.0f;
  const float a = -1.0f / (sign + n[2]);
  const float c = n[0] * n[1] * a;
  t[0] = 1.0f + sign * n[0] * n[0] * a;
  t[1] = sign * c;
  t[2] = -sign * n[0];
  b[0] = c;
  b[1] = sign + n[1] * n[1] * a;
  b[2] = -n[1];
}

}  // namespace lightpatch::pack
