#include "lightpatch/cooker/group_file.h"

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <set>

#include "lightpatch/cooker/bake_plan.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/pack_view.h"

namespace lightpatch::cooker {

static_assert(std::endian::native == std::endian::little, "the format is little-endian");

namespace {

constexpr int kMaxSide = 16384;
constexpr uint32_t kMaxReason = 64 * 1024;
enum Role : uint32_t { kOwn = 0, kShadow = 1, kPair = 2, kStaticShadow = 3 };
// MapRecord::parts
enum Part : uint16_t {
  kNoPart = 0,
  kHasIndirect = 1,
  kIsIndirect = 2,
  kHasDirect = 4,
  kIsDirect = 8
};

template <typename T>
void put(std::vector<uint8_t>& out, const T& v) {
  const size_t at = out.size();
  out.resize(at + sizeof v);
  std::memcpy(out.data() + at, &v, sizeof v);
}

// The smallest rectangle outside which every value's bits are zero (empty: w = h = 0).
void zero_free_rect(const FloatImage& m, int& x0, int& y0, int& x1, int& y1) {
  x0 = m.width, y0 = m.height, x1 = 0, y1 = 0;
  const size_t c = size_t(m.channels);
  for (int y = 0; y < m.height; ++y) {
    const float* row = m.data.data() + size_t(y) * size_t(m.width) * c;
    for (int x = 0; x < m.width; ++x) {
      for (size_t k = 0; k < c; ++k) {
        if (std::bit_cast<uint32_t>(row[size_t(x) * c + k]) == 0) continue;
        x0 = std::min(x0, x), y0 = std::min(y0, y);
        x1 = std::max(x1, x + 1), y1 = std::max(y1, y + 1);
      }
    }
  }
  if (x1 <= x0 || y1 <= y0) x0 = y0 = x1 = y1 = 0;
}

// One image as a record, its mask and its values; `part` is MapRecord::parts.
void put_image(std::vector<uint8_t>& out, uint32_t role, int light, int object, int object_b,
               const FloatImage& m, uint16_t part) {
  if (m.width <= 0 || m.height <= 0 || m.width > kMaxSide || m.height > kMaxSide ||
      (m.channels != 1 && m.channels != 3) ||
      m.data.size() != size_t(m.width) * size_t(m.height) * size_t(m.channels)) {
    throw CookError("group file: cannot store a map of " + std::to_string(m.width) + "x" +
                    std::to_string(m.height) + "x" + std::to_string(m.channels));
  }
  int x0, y0, x1, y1;
  zero_free_rect(m, x0, y0, x1, y1);
  MapRecord r{};
  r.role = role;
  r.light = light;
  r.object = object;
  r.object_b = object_b;
  r.width = uint16_t(m.width);
  r.height = uint16_t(m.height);
  r.rect_x = uint16_t(x0);
  r.rect_y = uint16_t(y0);
  r.rect_w = uint16_t(x1 - x0);
  r.rect_h = uint16_t(y1 - y0);
  r.channels = uint16_t(m.channels);
  r.parts = part;
  const size_t c = size_t(m.channels), row = size_t(x1 - x0) * c;
  const size_t n = row * size_t(y1 - y0);
  std::vector<uint8_t> mask((n + 7) / 8, 0);
  std::vector<float> values;
  size_t i = 0;
  for (int y = y0; y < y1; ++y) {
    const float* src = m.data.data() + (size_t(y) * size_t(m.width) + size_t(x0)) * c;
    for (size_t k = 0; k < row; ++k, ++i) {
      if (std::bit_cast<uint32_t>(src[k]) == 0) continue;
      mask[i / 8] |= uint8_t(1u << (i % 8));
      values.push_back(src[k]);
    }
  }
  r.nonzero = values.size();
  put(out, r);
  out.insert(out.end(), mask.begin(), mask.end());
  const size_t at = out.size();
  out.resize(at + values.size() * sizeof(float));
  if (!values.empty()) std::memcpy(out.data() + at, values.data(), values.size() * sizeof(float));
}

// A map and, when it has them, its indirect part (the block image, BakedMaps) and its direct part
// (ShadowMap::direct) after it.
void put_map(std::vector<uint8_t>& out, uint32_t role, int light, int object, int object_b,
             const FloatImage& m, const FloatImage& indirect, const FloatImage& direct) {
  const bool has_indirect = !indirect.data.empty(), has_direct = !direct.data.empty();
  put_image(out, role, light, object, object_b, m,
            uint16_t((has_indirect ? kHasIndirect : 0) | (has_direct ? kHasDirect : 0)));
  if (has_indirect) put_image(out, role, light, object, object_b, indirect, kIsIndirect);
  if (has_direct) put_image(out, role, light, object, object_b, direct, kIsDirect);
}

// A cursor over untrusted bytes: every read is bounds-checked first.
class Reader {
 public:
  Reader(const uint8_t* data, size_t size, size_t at) : data_(data), size_(size), at_(at) {}
  template <typename T>
  T take(const char* what) {
    T v;
    std::memcpy(&v, need(sizeof v, what), sizeof v);
    return v;
  }
  const uint8_t* need(uint64_t n, const char* what) {
    if (n > size_ - at_) throw CookError(std::string("group file: truncated ") + what);
    const uint8_t* p = data_ + at_;
    at_ += size_t(n);
    return p;
  }
  size_t left() const { return size_ - at_; }

 private:
  const uint8_t* data_;
  size_t size_, at_;
};

// CRC-32 of a whole file whose header's crc field reads as zero.
uint32_t file_crc(const uint8_t* data, size_t size) {
  constexpr size_t at = offsetof(GroupFileHeader, crc);
  const uint8_t zero[4] = {0, 0, 0, 0};
  uint32_t c = crc32(data, at);
  c = crc32(zero, sizeof zero, c);
  return crc32(data + at + 4, size - at - 4, c);
}

GroupFileHeader checked_header(const uint8_t* data, size_t size, bool check_body) {
  if (size < sizeof(GroupFileHeader))
    throw CookError("group file: " + std::to_string(size) + " bytes, shorter than its header");
  GroupFileHeader h;
  std::memcpy(&h, data, sizeof h);
  if (std::memcmp(h.magic, kGroupFileMagic, sizeof h.magic) != 0)
    throw CookError("group file: not a lightpatch group result (bad magic)");
  if (h.version != kGroupFileVersion)
    throw CookError("group file: format version " + std::to_string(h.version) + ", expected " +
                    std::to_string(kGroupFileVersion));
  if (h.header_size != sizeof h) throw CookError("group file: bad header size");
  if (h.file_size != size)
    throw CookError("group file: header says " + std::to_string(h.file_size) + " bytes, file has " +
                    std::to_string(size) + " (truncated or extended)");
  if (check_body && file_crc(data, size) != h.crc)
    throw CookError("group file: checksum mismatch (corrupted)");
  return h;
}

}  // namespace

std::vector<uint8_t> encode_group(const GroupBake& g, const std::array<uint8_t, 16>& job_hash) {
  std::vector<uint8_t> out(sizeof(GroupFileHeader), 0);
  uint32_t maps = 0;
  const bool is_static = g.group == 0;
  put_map(out, kOwn, -1, -1, -1, g.map, g.indirect, g.direct);
  ++maps;
  for (const ShadowMap& s : g.shadows)
    put_map(out, kShadow, s.light, s.object, -1, s.map, s.indirect, s.direct), ++maps;
  for (const PairCorrectionMap& p : g.pair_corrections)
    put_map(out, kPair, p.light, p.object_a, p.object_b, p.map, p.indirect, p.direct), ++maps;
  for (const StaticShadowMap& s : g.static_shadows)
    put_map(out, kStaticShadow, -1, s.object, -1, s.map, s.indirect, s.direct), ++maps;
  if (is_static && (!g.shadows.empty() || !g.pair_corrections.empty()))
    throw CookError("group file: the static group has light shadows");
  for (const Decision& d : g.decisions) {
    if (d.reason.size() > kMaxReason) throw CookError("group file: decision reason too long");
    DecisionRecord r{};
    r.kind = uint8_t(d.kind);
    r.stage = uint8_t(d.stage);
    r.taken = d.taken ? 1 : 0;
    r.forced = d.forced ? 1 : 0;
    r.light = d.light;
    r.object = d.object;
    r.object_b = d.object_b;
    r.value = d.value;
    r.bound = d.bound;
    r.seconds = d.seconds;
    r.reason_bytes = uint32_t(d.reason.size());
    put(out, r);
    out.insert(out.end(), d.reason.begin(), d.reason.end());
  }
  GroupFileHeader h{};
  std::memcpy(h.magic, kGroupFileMagic, sizeof h.magic);
  h.version = kGroupFileVersion;
  h.header_size = sizeof h;
  h.file_size = out.size();
  std::memcpy(h.job_hash, job_hash.data(), sizeof h.job_hash);
  h.group = uint32_t(g.group);
  h.map_count = maps;
  h.decision_count = uint32_t(g.decisions.size());
  h.seconds = g.seconds;
  std::memcpy(out.data(), &h, sizeof h);
  h.crc = file_crc(out.data(), out.size());
  std::memcpy(out.data(), &h, sizeof h);
  return out;
}

std::array<uint8_t, 16> group_file_hash(const uint8_t* data, size_t size, bool check_body) {
  const GroupFileHeader h = checked_header(data, size, check_body);
  std::array<uint8_t, 16> hash;
  std::memcpy(hash.data(), h.job_hash, hash.size());
  return hash;
}

GroupBake decode_group(const uint8_t* data, size_t size, const GroupFileExpect& e) {
  const GroupFileHeader h = checked_header(data, size, true);
  if (std::memcmp(h.job_hash, e.job_hash.data(), sizeof h.job_hash) != 0)
    throw CookError("group file: baked for another job (hash differs)");
  if (h.group != e.group)
    throw CookError("group file: holds group " + std::to_string(h.group) + ", expected " +
                    std::to_string(e.group));
  if (!std::isfinite(h.seconds) || h.seconds < 0.0) throw CookError("group file: bad seconds");
  const bool is_static = e.group == 0;
  Reader in(data, size, sizeof h);
  // Each record takes at least its own bytes: counts beyond what is left are refused before
  // anything is reserved.
  if (uint64_t(h.map_count) * sizeof(MapRecord) > in.left() || h.map_count < 1 ||
      h.map_count > e.max_maps)
    throw CookError("group file: bad map count " + std::to_string(h.map_count));
  if (uint64_t(h.decision_count) * sizeof(DecisionRecord) > in.left())
    throw CookError("group file: bad decision count " + std::to_string(h.decision_count));
  GroupBake g;
  g.group = e.group;
  g.seconds = h.seconds;
  auto object_ok = [&](int32_t o) { return o >= 0 && uint64_t(o) < e.objects; };
  uint32_t last_role = kOwn;
  std::set<std::array<int64_t, 3>> owners;
  // The image of record r (its mask and values, which follow it), `what` naming it in errors.
  auto read_image = [&](const MapRecord& r, const std::string& what) {
    if ((r.channels != 1 && r.channels != 3) || uint32_t(r.rect_x) + r.rect_w > r.width ||
        uint32_t(r.rect_y) + r.rect_h > r.height)
      throw CookError("group file: " + what + " has a bad channel count or rect");
    const uint64_t row = uint64_t(r.rect_w) * r.channels, n = row * r.rect_h;
    if (r.nonzero > n) throw CookError("group file: " + what + " has a bad count");
    const uint8_t* mask = in.need((n + 7) / 8, "map mask");
    const uint8_t* values = in.need(r.nonzero * sizeof(float), "map values");
    uint64_t set = 0;
    for (uint64_t b = 0; b < (n + 7) / 8; ++b) set += uint64_t(std::popcount(mask[b]));
    if (set != r.nonzero || (n % 8 != 0 && (mask[n / 8] >> (n % 8)) != 0))
      throw CookError("group file: " + what + " mask disagrees with its count");
    FloatImage m(r.width, r.height, r.channels);
    uint64_t k = 0, v = 0;
    for (uint32_t y = 0; y < r.rect_h; ++y) {
      float* dst = m.data.data() + (size_t(r.rect_y + y) * r.width + r.rect_x) * r.channels;
      for (uint64_t x = 0; x < row; ++x, ++k) {
        if (!((mask[k / 8] >> (k % 8)) & 1u)) continue;
        float f;
        std::memcpy(&f, values + v * sizeof(float), sizeof f);
        ++v;
        if (!std::isfinite(f) || std::bit_cast<uint32_t>(f) == 0)
          throw CookError("group file: " + what + " has a non-finite value");
        dst[x] = f;
      }
    }
    return m;
  };
  for (uint32_t i = 0; i < h.map_count; ++i) {
    const std::string what = "map " + std::to_string(i);
    const MapRecord r = in.take<MapRecord>("map record");
    if (r.width != e.width || r.height != e.height)
      throw CookError("group file: " + what + " is " + std::to_string(r.width) + "x" +
                      std::to_string(r.height) + ", the light map " + std::to_string(e.width) +
                      "x" + std::to_string(e.height));
    // An indirect part only where the layout has blocks.
    if ((r.parts & ~uint16_t(kHasIndirect | kHasDirect)) != 0)
      throw CookError("group file: " + what + " has bad part flags");
    if ((r.parts & kHasIndirect) && !(e.indirect_width > 0))
      throw CookError("group file: " + what + " has a bad indirect flag");
    // Roles in order (own map, shadows, pairs, static shadows), each owner once: the map count
    // stays within what the plan allows.
    if ((i == 0) != (r.role == kOwn) || r.role < last_role)
      throw CookError("group file: " + what + " out of order");
    last_role = r.role;
    if (r.role != kOwn && !owners.insert({r.role, r.object, r.object_b}).second)
      throw CookError("group file: " + what + " repeats an owner");
    bool ok = false;
    switch (r.role) {
      case kOwn:
        ok = r.light == -1 && r.object == -1 && r.object_b == -1 &&
             (is_static ? r.channels == 3 : true);
        break;
      case kShadow:
        ok = !is_static && r.light == int(e.group) - 1 && object_ok(r.object) && r.object_b == -1;
        break;
      case kPair:
        ok = !is_static && r.light == int(e.group) - 1 && object_ok(r.object) &&
             object_ok(r.object_b) && r.object < r.object_b;
        break;
      case kStaticShadow:
        ok = is_static && r.light == -1 && object_ok(r.object) && r.object_b == -1;
        break;
      default:
        break;
    }
    if (!ok) throw CookError("group file: " + what + " has a bad role or owner");
    FloatImage m = read_image(r, what);
    auto same_owner = [&](const MapRecord& p) {
      return p.role == r.role && p.light == r.light && p.object == r.object &&
             p.object_b == r.object_b;
    };
    FloatImage part, direct;
    if (r.parts & kHasIndirect) {
      const MapRecord p = in.take<MapRecord>("map record");
      if (p.parts != kIsIndirect || !same_owner(p) || p.channels != 3 ||
          p.width != e.indirect_width || p.height != e.indirect_height)
        throw CookError("group file: " + what + "'s indirect part does not match it or the layout");
      part = read_image(p, what + "'s indirect part");
    }
    if (r.parts & kHasDirect) {
      const MapRecord p = in.take<MapRecord>("map record");
      if (p.parts != kIsDirect || !same_owner(p) || p.channels != (is_static ? 3 : 1) ||
          p.width != r.width || p.height != r.height)
        throw CookError("group file: " + what + "'s direct part does not match it");
      direct = read_image(p, what + "'s direct part");
    }
    switch (r.role) {
      case kOwn:
        g.map = std::move(m);
        g.indirect = std::move(part);
        g.direct = std::move(direct);
        break;
      case kShadow:
        g.shadows.push_back({r.light, r.object, std::move(m), std::move(part), std::move(direct)});
        break;
      case kPair:
        g.pair_corrections.push_back(
            {r.light, r.object, r.object_b, std::move(m), std::move(part), std::move(direct)});
        break;
      default:
        g.static_shadows.push_back({r.object, std::move(m), std::move(part), std::move(direct)});
        break;
    }
  }
  auto index_ok = [](int32_t v, uint64_t n) { return v == -1 || (v >= 0 && uint64_t(v) < n); };
  for (uint32_t i = 0; i < h.decision_count; ++i) {
    const DecisionRecord r = in.take<DecisionRecord>("decision record");
    if (r.kind > uint8_t(DecisionKind::kTripleOverlap) ||
        r.stage > uint8_t(DecisionStage::kBounce) || r.taken > 1 || r.forced > 1 ||
        r.reserved != 0 || !index_ok(r.light, e.lights) || !index_ok(r.object, e.objects) ||
        !index_ok(r.object_b, e.objects) || r.reason_bytes > kMaxReason)
      throw CookError("group file: decision " + std::to_string(i) + " is malformed");
    const uint8_t* text = in.need(r.reason_bytes, "decision reason");
    Decision d;
    d.kind = DecisionKind(r.kind);
    d.stage = DecisionStage(r.stage);
    d.taken = r.taken != 0;
    d.forced = r.forced != 0;
    d.light = r.light;
    d.object = r.object;
    d.object_b = r.object_b;
    d.value = r.value;
    d.bound = r.bound;
    d.seconds = r.seconds;
    d.reason.assign(reinterpret_cast<const char*>(text), r.reason_bytes);
    g.decisions.push_back(std::move(d));
  }
  if (in.left() != 0)
    throw CookError("group file: " + std::to_string(in.left()) + " bytes after the last record");
  return g;
}

}  // namespace lightpatch::cooker
