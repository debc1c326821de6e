#include "farm/gather_file.h"

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <string>

#include "lightpatch/cooker/error.h"
#include "lightpatch/pack_view.h"

namespace lightpatch::cooker {

static_assert(std::endian::native == std::endian::little, "the format is little-endian");
// Every field of the operator is written below: a field added to gather.h must be added here
// (and the version bumped), or a loaded operator would lack it.
// (Sizes on 64-bit libstdc++: 3 ints and 13 vectors; the grid and 22 more fields.)
static_assert(sizeof(CoarseGrid) == 328, "CoarseGrid changed: update gather_file.cpp");
static_assert(sizeof(GatherOperator) == 720, "GatherOperator changed: update gather_file.cpp");

namespace {

constexpr char kMagic[8] = {'L', 'P', 'G', 'A', 'T', 'H', 'E', 'R'};
constexpr uint32_t kVersion = 4;

struct GatherScalars {
  int32_t level, width, height, rays, tiles_x, tiles_y;
  int32_t level_rays[GatherOperator::kLevels];
  float mean_albedo;
  uint64_t buried_texels, rays_traced;
};
static_assert(GatherOperator::kLevels == 3 && sizeof(GatherScalars) == 56);

class Writer {
 public:
  std::vector<uint8_t> out;
  void raw(const void* p, size_t n) {
    const size_t at = out.size();
    out.resize(at + n);
    if (n) std::memcpy(out.data() + at, p, n);
  }
  template <typename T>
  void array(const std::vector<T>& v) {
    const uint64_t n = v.size();
    raw(&n, sizeof n);
    raw(v.data(), v.size() * sizeof(T));
  }
  void nested(const std::vector<std::vector<uint32_t>>& v) {
    std::vector<uint32_t> offsets{0}, values;
    for (const std::vector<uint32_t>& e : v) {
      values.insert(values.end(), e.begin(), e.end());
      offsets.push_back(uint32_t(values.size()));
    }
    array(offsets);
    array(values);
  }
  // Values in [0, limit] as bit_width(limit) bits each; kNoTexel as `limit`.
  void packed(const std::vector<uint32_t>& v, uint32_t limit) {
    const uint64_t n = v.size();
    raw(&n, sizeof n);
    const uint8_t w = uint8_t(std::max(1, int(std::bit_width(limit))));
    raw(&w, 1);
    // Least significant bit first, a value's bits after the previous value's (w <= 32, so the
    // accumulator never holds more than 39 bits).
    std::vector<uint8_t> bits((n * w + 7) / 8, 0);
    uint64_t acc = 0;
    int held = 0;
    size_t o = 0;
    for (uint32_t x : v) {
      acc |= uint64_t(x == kNoTexel ? limit : x) << held;
      for (held += w; held >= 8; held -= 8, acc >>= 8) bits[o++] = uint8_t(acc);
    }
    if (held > 0) bits[o] = uint8_t(acc);
    raw(bits.data(), bits.size());
  }
};

class Reader {
 public:
  Reader(const uint8_t* data, size_t size, size_t at) : data_(data), size_(size), at_(at) {}
  const uint8_t* need(uint64_t n, const char* what) {
    if (n > size_ - at_) throw CookError(std::string("gather file: truncated ") + what);
    const uint8_t* p = data_ + at_;
    at_ += size_t(n);
    return p;
  }
  template <typename T>
  std::vector<T> array(const char* what, uint64_t expect = ~uint64_t(0)) {
    uint64_t n;
    std::memcpy(&n, need(sizeof n, what), sizeof n);
    if (n > (size_ - at_) / sizeof(T))
      throw CookError(std::string("gather file: truncated ") + what);
    if (expect != ~uint64_t(0) && n != expect)
      throw CookError(std::string("gather file: ") + what + " has " + std::to_string(n) +
                      " entries, expected " + std::to_string(expect));
    std::vector<T> v(n);
    if (n) std::memcpy(v.data(), need(n * sizeof(T), what), n * sizeof(T));
    return v;
  }
  std::vector<std::vector<uint32_t>> nested(const char* what, uint64_t count, uint32_t bound) {
    const std::vector<uint32_t> offsets = array<uint32_t>(what, count + 1);
    const std::vector<uint32_t> values = array<uint32_t>(what);
    if (offsets[0] != 0 || offsets.back() != values.size())
      throw CookError(std::string("gather file: bad offsets of ") + what);
    std::vector<std::vector<uint32_t>> out(count);
    for (uint64_t i = 0; i < count; ++i) {
      if (offsets[i + 1] < offsets[i])
        throw CookError(std::string("gather file: bad offsets of ") + what);
      out[i].assign(values.begin() + offsets[i], values.begin() + offsets[i + 1]);
      for (uint32_t x : out[i])
        if (x >= bound) throw CookError(std::string("gather file: index out of range in ") + what);
    }
    return out;
  }
  std::vector<uint32_t> packed(const char* what, uint64_t expect, uint32_t limit) {
    uint64_t n;
    std::memcpy(&n, need(sizeof n, what), sizeof n);
    uint8_t w;
    std::memcpy(&w, need(1, what), 1);
    if (n != expect || w != std::max(1, int(std::bit_width(limit))))
      throw CookError(std::string("gather file: bad size of ") + what);
    const uint8_t* bits = need((n * w + 7) / 8, what);
    // As Writer::packed: reads exactly the (n * w + 7) / 8 bytes.
    std::vector<uint32_t> v(n);
    const uint64_t mask = (uint64_t(1) << w) - 1;
    uint64_t acc = 0;
    int held = 0;
    size_t at = 0;
    for (uint64_t i = 0; i < n; ++i) {
      for (; held < w; held += 8) acc |= uint64_t(bits[at++]) << held;
      const uint32_t x = uint32_t(acc & mask);
      acc >>= w;
      held -= w;
      if (x > limit) throw CookError(std::string("gather file: index out of range in ") + what);
      v[i] = x == limit ? kNoTexel : x;
    }
    return v;
  }
  size_t left() const { return size_ - at_; }

 private:
  const uint8_t* data_;
  size_t size_, at_;
};

uint32_t file_crc(const uint8_t* data, size_t size) {
  constexpr size_t at = offsetof(GatherFileHeader, crc);
  const uint8_t zero[4] = {0, 0, 0, 0};
  uint32_t c = crc32(data, at);
  c = crc32(zero, sizeof zero, c);
  return crc32(data + at + 4, size - at - 4, c);
}

// Every entry < bound, or kNoTexel where `none` allows it.
void check_indices(const std::vector<uint32_t>& v, uint64_t bound, bool none, const char* what) {
  for (uint32_t x : v)
    if (!(x < bound || (none && x == kNoTexel)))
      throw CookError(std::string("gather file: index out of range in ") + what);
}

void check_offsets(const std::vector<uint32_t>& v, uint64_t total, const char* what) {
  if (v.empty() || v[0] != 0 || v.back() != total)
    throw CookError(std::string("gather file: bad offsets of ") + what);
  for (size_t i = 1; i < v.size(); ++i)
    if (v[i] < v[i - 1]) throw CookError(std::string("gather file: bad offsets of ") + what);
}

void check_finite(const std::vector<float>& v, const char* what) {
  for (float x : v)
    if (!std::isfinite(x) || x < 0.0f)
      throw CookError(std::string("gather file: bad value in ") + what);
}

void check_finite(const std::vector<glm::vec3>& v, const char* what) {
  for (const glm::vec3& x : v)
    if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z))
      throw CookError(std::string("gather file: bad value in ") + what);
}

}  // namespace

std::vector<uint8_t> encode_gather(const GatherOperator& op, const std::array<uint8_t, 16>& hash) {
  const CoarseGrid& g = op.grid;
  Writer w;
  w.out.resize(sizeof(GatherFileHeader), 0);
  GatherScalars s{};
  s.level = g.level;
  s.width = g.width;
  s.height = g.height;
  s.rays = op.rays;
  for (int l = 0; l < GatherOperator::kLevels; ++l) s.level_rays[l] = op.level_rays[l];
  s.tiles_x = op.tiles_x;
  s.tiles_y = op.tiles_y;
  s.mean_albedo = op.mean_albedo;
  s.buried_texels = op.buried_texels;
  s.rays_traced = op.rays_traced;
  w.raw(&s, sizeof s);
  w.array(g.coarse_of);
  w.array(g.member_offset);
  w.array(g.members);
  w.array(g.block_of);
  w.array(g.block_offset);
  w.array(g.block_coarse);
  w.array(g.chart);
  w.array(g.position);
  w.array(g.normal);
  w.array(g.albedo);
  w.array(g.links);
  w.array(g.fine);
  w.array(g.alive);
  w.packed(op.hit, uint32_t(g.size()));
  for (const std::vector<float>& weight : op.weight) w.array(weight);
  w.array(op.crossing_offset);
  w.array(op.crossings);
  w.array(op.crossing_hits);
  w.nested(op.coarse_crossing);
  w.array(op.near_offset);
  w.array(op.near);
  w.array(op.tile_of);
  w.nested(op.tile_coarse);
  w.nested(op.sources);
  w.array(op.buried);
  GatherFileHeader h{};
  std::memcpy(h.magic, kMagic, sizeof kMagic);
  h.version = kVersion;
  h.header_size = sizeof h;
  h.file_size = w.out.size();
  std::memcpy(h.job_hash, hash.data(), sizeof h.job_hash);
  h.texels = uint32_t(g.coarse_of.size());
  h.objects = uint32_t(op.coarse_crossing.size());
  h.coarse = uint32_t(g.size());
  h.rays = uint32_t(op.rays);
  std::memcpy(w.out.data(), &h, sizeof h);
  h.crc = file_crc(w.out.data(), w.out.size());
  std::memcpy(w.out.data(), &h, sizeof h);
  return std::move(w.out);
}

namespace {

GatherFileHeader checked_header(const uint8_t* data, size_t size, bool check_body) {
  if (size < sizeof(GatherFileHeader)) throw CookError("gather file: shorter than its header");
  GatherFileHeader h;
  std::memcpy(&h, data, sizeof h);
  if (std::memcmp(h.magic, kMagic, sizeof kMagic) != 0 || h.header_size != sizeof h)
    throw CookError("gather file: not a lightpatch gather file");
  if (h.version != kVersion)
    throw CookError("gather file: format version " + std::to_string(h.version) + ", expected " +
                    std::to_string(kVersion));
  if (h.file_size != size) throw CookError("gather file: truncated or extended");
  if (check_body && file_crc(data, size) != h.crc)
    throw CookError("gather file: checksum mismatch (corrupted)");
  return h;
}

}  // namespace

std::array<uint8_t, 16> gather_file_hash(const uint8_t* data, size_t size, bool check_body) {
  const GatherFileHeader h = checked_header(data, size, check_body);
  std::array<uint8_t, 16> hash;
  std::memcpy(hash.data(), h.job_hash, hash.size());
  return hash;
}

GatherOperator decode_gather(const uint8_t* data, size_t size, const GatherFileExpect& e) {
  const GatherFileHeader h = checked_header(data, size, true);
  if (std::memcmp(h.job_hash, e.job_hash.data(), sizeof h.job_hash) != 0)
    throw CookError("gather file: traced for another scene or options (hash differs)");
  if (h.texels != e.texels || h.objects != e.objects || h.rays != uint32_t(e.rays))
    throw CookError("gather file: traced for other texels, objects or rays");

  Reader in(data, size, sizeof h);
  GatherScalars s;
  std::memcpy(&s, in.need(sizeof s, "scalars"), sizeof s);
  if (s.level != e.level || s.rays != e.rays || s.width <= 0 || s.height <= 0 || s.tiles_x <= 0 ||
      s.tiles_y <= 0 || !std::isfinite(s.mean_albedo))
    throw CookError("gather file: bad scalars");
  for (int l = 0; l < GatherOperator::kLevels; ++l)
    if (s.level_rays[l] < 0 || s.level_rays[l] > s.rays)
      throw CookError("gather file: bad rays of a bounce level");
  GatherOperator op;
  CoarseGrid& g = op.grid;
  g.level = s.level;
  g.width = s.width;
  g.height = s.height;
  op.rays = s.rays;
  for (int l = 0; l < GatherOperator::kLevels; ++l) op.level_rays[l] = s.level_rays[l];
  op.tiles_x = s.tiles_x;
  op.tiles_y = s.tiles_y;
  op.mean_albedo = s.mean_albedo;
  op.buried_texels = s.buried_texels;
  op.rays_traced = s.rays_traced;
  const uint64_t nc = h.coarse, blocks = uint64_t(s.width) * uint64_t(s.height);
  const uint64_t tiles = uint64_t(s.tiles_x) * uint64_t(s.tiles_y);
  g.coarse_of = in.array<uint32_t>("coarse_of", e.texels);
  g.member_offset = in.array<uint32_t>("member_offset", nc + 1);
  g.members = in.array<uint32_t>("members");
  g.block_of = in.array<uint32_t>("block_of", nc);
  g.block_offset = in.array<uint32_t>("block_offset", blocks + 1);
  g.block_coarse = in.array<uint32_t>("block_coarse");
  g.chart = in.array<uint32_t>("chart", nc);
  g.position = in.array<glm::vec3>("position", nc);
  g.normal = in.array<glm::vec3>("normal", nc);
  g.albedo = in.array<glm::vec3>("albedo", nc);
  g.links = in.array<uint32_t>("links", nc * CoarseGrid::kLinks);
  g.fine = in.array<uint8_t>("fine", nc);
  g.alive = in.array<uint8_t>("alive", nc);
  check_indices(g.coarse_of, nc, true, "coarse_of");
  check_offsets(g.member_offset, g.members.size(), "member_offset");
  check_indices(g.members, e.texels, false, "members");
  check_indices(g.block_of, blocks, false, "block_of");
  check_offsets(g.block_offset, g.block_coarse.size(), "block_offset");
  check_indices(g.block_coarse, nc, false, "block_coarse");
  check_indices(g.links, nc, true, "links");
  check_finite(g.position, "position");
  check_finite(g.normal, "normal");
  check_finite(g.albedo, "albedo");
  for (uint8_t a : g.alive)
    if (a > 1) throw CookError("gather file: bad value in alive");
  for (uint8_t f : g.fine)
    if (f > 1) throw CookError("gather file: bad value in fine");

  op.hit = in.packed("hit", nc * uint64_t(s.rays), uint32_t(nc));
  for (std::vector<float>& weight : op.weight) {
    weight = in.array<float>("weight", nc);
    check_finite(weight, "weight");
  }
  op.crossing_offset = in.array<uint32_t>("crossing_offset", nc + 1);
  op.crossings = in.array<Crossing>("crossings");
  op.crossing_hits = in.array<CrossingHit>("crossing_hits");
  check_offsets(op.crossing_offset, op.crossings.size(), "crossing_offset");
  for (const Crossing& c : op.crossings) {
    if (c.ray >= uint32_t(s.rays) || uint64_t(c.first) + c.count > op.crossing_hits.size())
      throw CookError("gather file: index out of range in crossings");
  }
  for (const CrossingHit& c : op.crossing_hits) {
    if (c.object < 0 || uint64_t(c.object) >= e.objects || !(c.coarse < nc || c.coarse == kNoTexel))
      throw CookError("gather file: index out of range in crossing_hits");
  }
  op.coarse_crossing = in.nested("coarse_crossing", e.objects, uint32_t(nc));
  op.near_offset = in.array<uint32_t>("near_offset", nc + 1);
  op.near = in.array<NearHit>("near");
  check_offsets(op.near_offset, op.near.size(), "near_offset");
  for (const NearHit& n : op.near) {
    if (n.ray >= uint32_t(s.rays) || n.fine >= e.texels || n.count == 0 ||
        n.count > uint32_t(s.rays) || !std::isfinite(n.point.x) || !std::isfinite(n.point.y) ||
        !std::isfinite(n.point.z))
      throw CookError("gather file: bad near hit");
  }
  op.tile_of = in.array<uint32_t>("tile_of", nc);
  check_indices(op.tile_of, tiles, false, "tile_of");
  op.tile_coarse = in.nested("tile_coarse", tiles, uint32_t(nc));
  op.sources = in.nested("sources", tiles, uint32_t(tiles));
  op.buried = in.array<uint8_t>("buried", e.texels);
  for (uint8_t b : op.buried)
    if (b > 1) throw CookError("gather file: bad value in buried");
  if (in.left() != 0) throw CookError("gather file: bytes after the last array");
  return op;
}

}  // namespace lightpatch::cooker
