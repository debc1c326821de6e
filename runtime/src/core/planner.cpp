#include "lightpatch/planner.h"

#include <cassert>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "lightpatch/group_rules.h"
#include "lightpatch/patch_accumulate.h"

namespace lightpatch {
namespace {

constexpr uint64_t kNotPending = ~0ull;
constexpr uint32_t kNoLight = ~0u;
// A light below 1/256 of its peak since the last rebuild counts as 1/256 of it (planner.h).
constexpr float kDimFloor = 1.0f / 256.0f;

float max3(const float v[3]) {
  float m = std::fabs(v[0]);
  if (std::fabs(v[1]) > m) m = std::fabs(v[1]);
  if (std::fabs(v[2]) > m) m = std::fabs(v[2]);
  return m;
}

bool nonzero(const float v[3]) {
  return v[0] != 0.0f || v[1] != 0.0f || v[2] != 0.0f;
}

bool same(const float a[3], const float b[3]) {
  return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

// Carves typed arrays out of one block (sized in a first pass with base == nullptr).
struct Carver {
  uint8_t* base;
  size_t used = 0;
  template <typename T>
  T* take(size_t count) {
    used = (used + alignof(T) - 1) / alignof(T) * alignof(T);
    T* p = base ? reinterpret_cast<T*>(base + used) : nullptr;
    used += sizeof(T) * count;
    return p;
  }
};

// Max over the maps of the sum of |values| of `count` groups from `groups` (the scratch map set
// is left zeroed). One bound for both targets: the larger of the two maps' maxima.
float groups_bound(const PackView& pack, const uint32_t* groups, uint32_t count, float* scratch) {
  const float one[3] = {1.0f, 1.0f, 1.0f};
  for (uint32_t i = 0; i < count; ++i) {
    const pack::GroupRecord& g = pack.group(groups[i]);
    add_patches(pack, g.first_patch, g.patch_count, one, scratch, /*absolute=*/true);
  }
  float m = 0.0f;
  for (uint32_t i = 0; i < count; ++i) {
    const pack::GroupRecord& g = pack.group(groups[i]);
    for (uint32_t p = g.first_patch; p < g.first_patch + g.patch_count; ++p) {
      const pack::PatchRecord& pr = pack.patch(p);
      const uint32_t w = pack.map_width(pr.target);
      float* map = scratch + pack.map_offset(pr.target) * 3;
      for (uint32_t y = pr.dest_y; y < uint32_t(pr.dest_y + pr.height); ++y) {
        float* row = map + (size_t(y) * w + pr.dest_x) * 3;
        for (uint32_t k = 0; k < uint32_t(pr.width) * 3; ++k) {
          if (row[k] > m) m = row[k];
          row[k] = 0.0f;
        }
      }
    }
  }
  return m;
}

}  // namespace

Planner::~Planner() {
  std::free(block_);
}

Status Planner::init(const PackView& pack, const PlannerLimits& limits, Error* error) {
  std::free(block_);
  block_ = nullptr;
  ready_ = rebuilding_ = rebuild_cleared_ = false;
  rebuild_group_ = rebuild_patch_ = 0;
  rebuild_left_ = 0;
  base_bound_ = 0.0f;
  marked_count_ = 0;
  frame_ = 0;
  stats_ = FrameStats();
  if (!pack.valid()) return set_error(error, Status::kInvalidArgument, "planner: pack not open");
  pack_ = &pack;
  limits_ = limits;
  light_count_ = pack.light_count();
  object_count_ = pack.object_count();
  group_count_ = pack.group_count();
  const uint32_t patch_count = pack.patch_count();
  const uint32_t nl = light_count_, no = object_count_, ng = group_count_;

  uint32_t light_refs = 0, object_refs = 0;
  for (uint32_t g = 0; g < ng; ++g) {
    const pack::GroupRecord& gr = pack.group(g);
    if (group_has_light(gr.kind)) ++light_refs;
    for (uint32_t k = 0; k < 2; ++k) {
      const uint32_t o = k ? gr.object_b : gr.object_a;
      object_refs += o < no && group_names_object(gr, o);
    }
  }

  for (int pass = 0; pass < 2; ++pass) {
    Carver c{static_cast<uint8_t*>(block_)};
    group_texels_ = c.take<uint64_t>(ng);
    patch_prefix_ = c.take<uint64_t>(size_t(patch_count) + 1);
    indirect_prefix_ = c.take<uint64_t>(size_t(patch_count) + 1);
    group_split_ = c.take<uint32_t>(ng);
    light_since_ = c.take<uint64_t>(nl);
    object_since_ = c.take<uint64_t>(no);
    marked_frame_ = c.take<uint64_t>(ng);
    light_bound_ = c.take<float>(nl);
    light_first_ = c.take<uint32_t>(size_t(nl) + 1);
    light_groups_ = c.take<uint32_t>(light_refs);
    object_first_ = c.take<uint32_t>(size_t(no) + 1);
    object_groups_ = c.take<uint32_t>(object_refs);
    marked_ = c.take<uint32_t>(ng);
    color_ = c.take<Factor>(nl);
    shown_ = c.take<Factor>(nl);
    build_ = c.take<Factor>(nl);
    drift_weight_ = c.take<Factor>(nl);
    drift_peak_ = c.take<Factor>(nl);
    drift_saved_ = c.take<Factor>(2 * size_t(nl));
    intensity_ = c.take<float>(nl);
    on_ = c.take<uint8_t>(nl);
    want_visible_ = c.take<uint8_t>(no);
    shown_visible_ = c.take<uint8_t>(no);
    build_visible_ = c.take<uint8_t>(no);
    if (pass == 0) {
      block_ = std::calloc(1, c.used + 16);
      if (!block_) return set_error(error, Status::kOutOfMemory, "planner: out of memory");
    }
  }

  clear_texels_ = pack.map_texels();
  indirect_clear_texels_ = uint64_t(pack.indirect_width()) * pack.indirect_height();
  patch_prefix_[0] = indirect_prefix_[0] = 0;
  for (uint32_t p = 0; p < patch_count; ++p) {
    const pack::PatchRecord& pr = pack.patch(p);
    const uint64_t area = uint64_t(pr.width) * pr.height;
    patch_prefix_[p + 1] = patch_prefix_[p] + area;
    indirect_prefix_[p + 1] =
        indirect_prefix_[p] + (pr.target == pack::kTargetIndirectMap ? area : 0);
  }
  // Counting sort of the references (groups are sorted by kind, then light: each light's groups
  // come out contribution first).
  for (uint32_t g = 0; g < ng; ++g) {
    const pack::GroupRecord& gr = pack.group(g);
    group_texels_[g] =
        patch_prefix_[gr.first_patch + gr.patch_count] - patch_prefix_[gr.first_patch];
    // A group's light-map patches come first (validated), then its indirect-map ones.
    uint32_t split = gr.first_patch;
    while (split < gr.first_patch + gr.patch_count &&
           pack.patch(split).target == pack::kTargetLightMap) {
      ++split;
    }
    group_split_[g] = split;
    marked_frame_[g] = kNotPending;
    if (group_has_light(gr.kind)) ++light_first_[gr.light + 1];
    for (uint32_t k = 0; k < 2; ++k) {
      const uint32_t o = k ? gr.object_b : gr.object_a;
      if (o < no && group_names_object(gr, o)) ++object_first_[o + 1];
    }
  }
  for (uint32_t l = 0; l < nl; ++l) light_first_[l + 1] += light_first_[l];
  for (uint32_t o = 0; o < no; ++o) object_first_[o + 1] += object_first_[o];
  // Fill using the since arrays as cursors (reset below).
  for (uint32_t l = 0; l < nl; ++l) light_since_[l] = light_first_[l];
  for (uint32_t o = 0; o < no; ++o) object_since_[o] = object_first_[o];
  for (uint32_t g = 0; g < ng; ++g) {
    const pack::GroupRecord& gr = pack.group(g);
    if (group_has_light(gr.kind)) light_groups_[light_since_[gr.light]++] = g;
    for (uint32_t k = 0; k < 2; ++k) {
      const uint32_t o = k ? gr.object_b : gr.object_a;
      if (o < no && group_names_object(gr, o)) object_groups_[object_since_[o]++] = g;
    }
  }

  // Magnitude bounds: B (base and static shadows) and each light's A_l, max over texels.
  float* scratch = static_cast<float*>(std::calloc(size_t(clear_texels_) * 3, sizeof(float)));
  uint32_t* fixed = static_cast<uint32_t*>(std::malloc(sizeof(uint32_t) * (ng + 1)));
  if (!scratch || !fixed) {
    std::free(scratch);
    std::free(fixed);
    return set_error(error, Status::kOutOfMemory, "planner: out of memory");
  }
  uint32_t fixed_count = 0;
  for (uint32_t g = 0; g < ng; ++g) {
    if (!group_has_light(pack.group(g).kind)) fixed[fixed_count++] = g;
  }
  base_bound_ = groups_bound(pack, fixed, fixed_count, scratch);
  for (uint32_t l = 0; l < nl; ++l) {
    light_bound_[l] = groups_bound(pack, light_groups_ + light_first_[l],
                                   light_first_[l + 1] - light_first_[l], scratch);
  }
  std::free(scratch);
  std::free(fixed);

  for (uint32_t l = 0; l < nl; ++l) {
    const pack::LightRecord& lr = pack.light(l);
    on_[l] = 1;
    std::memcpy(color_[l].rgb, lr.color, sizeof(float) * 3);
    intensity_[l] = lr.intensity;
    light_since_[l] = 1;  // the initial build is a change made before the first frame
  }
  for (uint32_t o = 0; o < no; ++o) {
    want_visible_[o] = 1;
    object_since_[o] = 1;
  }
  return Status::kOk;
}

void Planner::light_color(uint32_t light, float out[3]) const {
  std::memcpy(out, color_[light].rgb, sizeof(float) * 3);
}

void Planner::shown_factor(uint32_t light, float out[3]) const {
  std::memcpy(out, shown_[light].rgb, sizeof(float) * 3);
}

void Planner::want_factor(uint32_t l, float out[3]) const {
  for (int c = 0; c < 3; ++c) out[c] = on_[l] ? color_[l].rgb[c] * intensity_[l] : 0.0f;
}

float Planner::map_bound(const Factor* factors) const {
  float m = base_bound_;
  for (uint32_t l = 0; l < light_count_; ++l) m += max3(factors[l].rgb) * light_bound_[l];
  return m;
}

float Planner::wanted_map_bound() const {
  float m = base_bound_;
  for (uint32_t l = 0; l < light_count_; ++l) {
    float f[3];
    want_factor(l, f);
    m += max3(f) * light_bound_[l];
  }
  return m;
}

bool Planner::lit(const Factor* factors, uint32_t light) const {
  return nonzero(factors[light].rgb);
}

Status Planner::set_light(uint32_t light, bool on, const float color[3], float intensity) {
  assert(light < light_count_ && "set_light: light index out of range");
  if (light >= light_count_) return Status::kInvalidArgument;
  for (int c = 0; c < 3; ++c) {
    if (!std::isfinite(color[c]) || color[c] < 0.0f) return Status::kInvalidArgument;
  }
  if (!std::isfinite(intensity) || intensity < 0.0f) return Status::kInvalidArgument;
  const uint8_t old_on = on_[light];
  const Factor old_color = color_[light];
  const float old_intensity = intensity_[light];
  on_[light] = on ? 1 : 0;
  std::memcpy(color_[light].rgb, color, sizeof(float) * 3);
  intensity_[light] = intensity;
  const float bound = wanted_map_bound();
  if (!(bound <= value_limit_)) {  // also catches colour * intensity overflowing to infinity
    on_[light] = old_on;
    color_[light] = old_color;
    intensity_[light] = old_intensity;
    return Status::kOutOfRange;
  }
  if (light_since_[light] == kNotPending) light_since_[light] = frame_ + 1;
  return Status::kOk;
}

Status Planner::set_object_visible(uint32_t object, bool visible) {
  assert(object < object_count_ && "set_object_visible: object index out of range");
  if (object >= object_count_) return Status::kInvalidArgument;
  want_visible_[object] = visible ? 1 : 0;
  if (object_since_[object] == kNotPending) object_since_[object] = frame_ + 1;
  return Status::kOk;
}

uint64_t Planner::rebuild_texels() const {
  uint64_t total = 2 * clear_texels_;  // the clear and the whole-map present
  for (uint32_t g = 0; g < group_count_; ++g) {
    const bool active = group_active(
        pack_->group(g),
        [&](uint32_t l) {
          float f[3];
          want_factor(l, f);
          return nonzero(f);
        },
        [&](uint32_t o) { return want_visible_[o] != 0; });
    if (active) total += group_texels_[g];
  }
  return total;
}

TargetTexels Planner::group_cost(uint32_t g) const {
  const pack::GroupRecord& gr = pack_->group(g);
  TargetTexels t;
  t.indirect_map =
      indirect_prefix_[gr.first_patch + gr.patch_count] - indirect_prefix_[gr.first_patch];
  t.light_map = group_texels_[g] - t.indirect_map;
  return t;
}

TargetTexels Planner::light_change_cost(uint32_t l) const {
  TargetTexels total;
  for (uint32_t i = light_first_[l]; i < light_first_[l + 1]; ++i) {
    const uint32_t g = light_groups_[i];
    if (light_change_touches(pack_->group(g), l,
                             [&](uint32_t o) { return shown_visible_[o] != 0; })) {
      const TargetTexels t = group_cost(g);  // drawn, then presented
      total.light_map += 2 * t.light_map;
      total.indirect_map += 2 * t.indirect_map;
    }
  }
  return total;
}

TargetTexels Planner::object_change_cost(uint32_t o) const {
  TargetTexels total;
  for (uint32_t i = object_first_[o]; i < object_first_[o + 1]; ++i) {
    const uint32_t g = object_groups_[i];
    if (object_change_touches(
            pack_->group(g), o, [&](uint32_t l) { return lit(shown_, l); },
            [&](uint32_t x) { return shown_visible_[x] != 0; })) {
      const TargetTexels t = group_cost(g);
      total.light_map += 2 * t.light_map;
      total.indirect_map += 2 * t.indirect_map;
    }
  }
  return total;
}

void Planner::count_texels(uint32_t first, uint32_t end) {
  stats_.texels += patch_prefix_[end] - patch_prefix_[first];
  stats_.indirect_texels += indirect_prefix_[end] - indirect_prefix_[first];
  ++stats_.draws;
}

void Planner::emit(DrawSink& sink, uint32_t group, uint32_t first, uint32_t end,
                   const float factor[3]) {
  const uint32_t split = group_split_[group];
  if (first < split) {
    const uint32_t e = end < split ? end : split;
    sink.draw(group, first, e - first, factor);
    count_texels(first, e);
  }
  if (end > split) {
    const uint32_t b = first > split ? first : split;
    sink.draw(group, b, end - b, factor);
    count_texels(b, end);
  }
}

void Planner::mark_for_present(uint32_t group) {
  if (marked_frame_[group] == frame_) return;
  marked_frame_[group] = frame_;
  marked_[marked_count_++] = group;
  marked_texels_ += group_texels_[group];
}

void Planner::present_marked(DrawSink& sink) {
  for (uint32_t i = 0; i < marked_count_; ++i) {
    const pack::GroupRecord& gr = pack_->group(marked_[i]);
    const uint32_t split = group_split_[marked_[i]], end = gr.first_patch + gr.patch_count;
    if (split > gr.first_patch) {
      sink.present(gr.first_patch, split - gr.first_patch);
      count_texels(gr.first_patch, split);
    }
    if (end > split) {
      sink.present(split, end - split);
      count_texels(split, end);
    }
  }
  marked_count_ = 0;
  marked_texels_ = 0;
}

void Planner::reset_drift() {
  drift_draws_ = 0.0f;
  for (uint32_t l = 0; l < light_count_; ++l) {
    drift_weight_[l] = Factor{{0.0f, 0.0f, 0.0f}};
    drift_peak_[l] = shown_[l];
  }
}

void Planner::count_draws(uint32_t draws, uint32_t light, const float from[3], const float to[3]) {
  if (draws == 0) return;
  const float d = float(draws);
  drift_draws_ += d;
  for (uint32_t l = 0; l < light_count_; ++l) {
    for (int c = 0; c < 3; ++c) {
      float f = std::fabs(shown_[l].rgb[c]);
      if (l == light) f = std::fmax(std::fabs(from[c]), std::fabs(to[c]));
      drift_weight_[l].rgb[c] += d * f;
      drift_peak_[l].rgb[c] = std::fmax(drift_peak_[l].rgb[c], f);
    }
  }
}

float Planner::drift() const {
  // Relative to M = |B| + sum_l f_l A_l, the error u (D |B| + sum_l w_l A_l) is at most
  // u max(D, max_l w_l / f_l): a ratio of sums is at most the largest ratio of its terms.
  float ratio = drift_draws_;
  for (uint32_t l = 0; l < light_count_; ++l) {
    for (int c = 0; c < 3; ++c) {
      const float w = drift_weight_[l].rgb[c];
      if (w == 0.0f) continue;
      const float f = std::fmax(std::fabs(shown_[l].rgb[c]), kDimFloor * drift_peak_[l].rgb[c]);
      ratio = std::fmax(ratio, w / f);
    }
  }
  return precision_.unit_roundoff * ratio;
}

void Planner::invalidate() {
  ready_ = false;
  rebuilding_ = false;
}

void Planner::request_rebuild() {
  if (!rebuilding_) start_rebuild();
}

void Planner::start_rebuild() {
  for (uint32_t l = 0; l < light_count_; ++l) want_factor(l, build_[l].rgb);
  std::memcpy(build_visible_, want_visible_, object_count_);
  rebuilding_ = true;
  rebuild_cleared_ = false;
  rebuild_group_ = 0;
  rebuild_patch_ = 0;
  rebuild_left_ = 2 * clear_texels_;
  for (uint32_t g = 0; g < group_count_; ++g) {
    const bool active = group_active(
        pack_->group(g), [&](uint32_t l) { return lit(build_, l); },
        [&](uint32_t o) { return build_visible_[o] != 0; });
    if (active) rebuild_left_ += group_texels_[g];
  }
}

// Runs rebuild steps within the budget; true when the rebuild was presented.
bool Planner::run_rebuild(uint64_t budget, DrawSink& sink) {
  auto room = [&] { return budget - stats_.texels; };
  // A step of the map's size (the clear, the present): false when it waits for the next frame.
  auto whole_map_step = [&]() {
    if (clear_texels_ <= room()) return true;
    if (stats_.texels != 0 || clear_texels_ <= budget) return false;
    stats_.oversize_steps = 1;  // alone in its frame
    return true;
  };
  if (!rebuild_cleared_) {
    if (!whole_map_step()) return false;
    sink.clear();
    stats_.texels += clear_texels_;
    stats_.indirect_texels += indirect_clear_texels_;
    rebuild_left_ -= clear_texels_;
    rebuild_cleared_ = true;
    if (stats_.oversize_steps) return false;
  }
  const float one[3] = {1.0f, 1.0f, 1.0f};
  for (; rebuild_group_ < group_count_; ++rebuild_group_, rebuild_patch_ = 0) {
    const pack::GroupRecord& gr = pack_->group(rebuild_group_);
    if (!group_active(
            gr, [&](uint32_t l) { return lit(build_, l); },
            [&](uint32_t o) { return build_visible_[o] != 0; })) {
      continue;
    }
    const float* f = group_has_light(gr.kind) ? build_[gr.light].rgb : one;
    const uint32_t first = gr.first_patch + rebuild_patch_;
    const uint32_t end = gr.first_patch + gr.patch_count;
    if (first == end) continue;  // finished by an earlier partial step
    const uint64_t whole = patch_prefix_[end] - patch_prefix_[first];
    if (whole <= room()) {
      emit(sink, rebuild_group_, first, end, f);
      rebuild_left_ -= whole;
      continue;
    }
    // Split the group: as many whole patches as fit.
    uint32_t k = first;
    while (k < end && patch_prefix_[k + 1] - patch_prefix_[first] <= room()) ++k;
    if (k == first) {
      if (stats_.texels != 0 || patch_prefix_[first + 1] - patch_prefix_[first] <= budget) {
        return false;
      }
      k = first + 1;  // one patch larger than the whole budget: alone in its frame
      stats_.oversize_steps = 1;
    }
    const uint64_t texels = patch_prefix_[k] - patch_prefix_[first];
    emit(sink, rebuild_group_, first, k, f);
    rebuild_left_ -= texels;
    rebuild_patch_ = k - gr.first_patch;
    return false;
  }
  if (!whole_map_step()) return false;
  sink.present_all();
  stats_.texels += clear_texels_;
  stats_.indirect_texels += indirect_clear_texels_;
  ++stats_.draws;
  rebuild_left_ -= clear_texels_;
  std::memcpy(shown_, build_, sizeof(Factor) * light_count_);
  std::memcpy(shown_visible_, build_visible_, object_count_);
  rebuilding_ = false;
  ready_ = true;
  reset_drift();
  stats_.presented = true;
  return true;
}

bool Planner::apply_light_change(uint32_t l, uint64_t budget, DrawSink& sink, bool* started) {
  const uint64_t cost = light_change_texels(l);
  if (cost > budget || cost >= rebuild_texels()) {
    start_rebuild();
    *started = true;
    return false;
  }
  if (cost > budget - stats_.texels - marked_texels_) return false;  // next frame
  float want[3], d[3];
  const Factor old = shown_[l];
  want_factor(l, want);
  for (int c = 0; c < 3; ++c) d[c] = want[c] - old.rgb[c];
  auto visible = [&](uint32_t o) { return shown_visible_[o] != 0; };
  uint32_t draws = 0;
  for (uint32_t i = light_first_[l]; i < light_first_[l + 1]; ++i) {
    draws += light_change_touches(pack_->group(light_groups_[i]), l, visible);
  }
  // Would the change take the drift bound past the tolerance? Then rebuild instead.
  std::memcpy(drift_saved_, drift_weight_, sizeof(Factor) * light_count_);
  std::memcpy(drift_saved_ + light_count_, drift_peak_, sizeof(Factor) * light_count_);
  const float saved_draws = drift_draws_;
  std::memcpy(shown_[l].rgb, want, sizeof want);
  count_draws(draws, l, old.rgb, want);
  if (drift() > limits_.drift_tolerance) {
    shown_[l] = old;
    std::memcpy(drift_weight_, drift_saved_, sizeof(Factor) * light_count_);
    std::memcpy(drift_peak_, drift_saved_ + light_count_, sizeof(Factor) * light_count_);
    drift_draws_ = saved_draws;
    start_rebuild();
    *started = true;
    return false;
  }
  for (uint32_t i = light_first_[l]; i < light_first_[l + 1]; ++i) {
    const uint32_t g = light_groups_[i];
    const pack::GroupRecord& gr = pack_->group(g);
    if (!light_change_touches(gr, l, visible)) continue;
    emit(sink, g, gr.first_patch, gr.first_patch + gr.patch_count, d);
    mark_for_present(g);
  }
  return true;
}

bool Planner::apply_object_change(uint32_t o, uint64_t budget, DrawSink& sink, bool* started) {
  const uint64_t cost = object_change_texels(o);
  if (cost > budget || cost >= rebuild_texels()) {
    start_rebuild();
    *started = true;
    return false;
  }
  if (cost > budget - stats_.texels - marked_texels_) return false;
  auto lit_now = [&](uint32_t l) { return lit(shown_, l); };
  auto visible = [&](uint32_t x) { return shown_visible_[x] != 0; };
  uint32_t draws = 0;
  for (uint32_t i = object_first_[o]; i < object_first_[o + 1]; ++i) {
    draws += object_change_touches(pack_->group(object_groups_[i]), o, lit_now, visible);
  }
  const float saved_draws = drift_draws_;
  std::memcpy(drift_saved_, drift_weight_, sizeof(Factor) * light_count_);
  count_draws(draws, kNoLight, nullptr, nullptr);
  if (drift() > limits_.drift_tolerance) {
    std::memcpy(drift_weight_, drift_saved_, sizeof(Factor) * light_count_);
    drift_draws_ = saved_draws;
    start_rebuild();
    *started = true;
    return false;
  }
  // Groups carry what the object changes with their own sign: drawing +f applies the change of a
  // visible object, -f takes it back.
  const float sign = want_visible_[o] ? 1.0f : -1.0f;
  for (uint32_t i = object_first_[o]; i < object_first_[o + 1]; ++i) {
    const uint32_t g = object_groups_[i];
    const pack::GroupRecord& gr = pack_->group(g);
    if (!object_change_touches(gr, o, lit_now, visible)) continue;
    const bool has_light = group_has_light(gr.kind);
    float f[3];
    for (int c = 0; c < 3; ++c) f[c] = sign * (has_light ? shown_[gr.light].rgb[c] : 1.0f);
    emit(sink, g, gr.first_patch, gr.first_patch + gr.patch_count, f);
    mark_for_present(g);
  }
  shown_visible_[o] = want_visible_[o];
  return true;
}

void Planner::complete(uint64_t* since) {
  const uint64_t latency = frame_ - *since + 1;
  ++stats_.completed_changes;
  if (latency > stats_.max_latency_frames) stats_.max_latency_frames = uint32_t(latency);
  *since = kNotPending;
}

void Planner::update(uint64_t budget, DrawSink& sink) {
  ++frame_;
  stats_ = FrameStats();
  stats_.frame = frame_;
  marked_count_ = 0;
  marked_texels_ = 0;
  if (!ready_ && !rebuilding_) start_rebuild();
  if (rebuilding_) run_rebuild(budget, sink);

  // Incremental changes against the presented map (none while a rebuild runs: the accumulator
  // holds the rebuild; they wait and are applied after it).
  if (ready_ && !rebuilding_ && !stats_.oversize_steps) {
    bool started = false, blocked = false;
    for (uint32_t l = 0; l < light_count_ && !started && !blocked; ++l) {
      float want[3];
      want_factor(l, want);
      if (same(want, shown_[l].rgb)) continue;
      blocked = !apply_light_change(l, budget, sink, &started);
    }
    for (uint32_t o = 0; o < object_count_ && !started && !blocked; ++o) {
      if (want_visible_[o] == shown_visible_[o]) continue;
      blocked = !apply_object_change(o, budget, sink, &started);
    }
    // Changes drawn this frame become visible before a rebuild started by a later one clears the
    // accumulator (their cost, presents included, was within the budget).
    present_marked(sink);
    if (started) run_rebuild(budget, sink);
  }

  // Completed and pending changes.
  uint64_t oldest = kNotPending;
  for (uint32_t l = 0; l < light_count_; ++l) {
    if (light_since_[l] == kNotPending) continue;
    float want[3];
    want_factor(l, want);
    if (ready_ && same(want, shown_[l].rgb)) {
      complete(&light_since_[l]);
    } else {
      ++stats_.pending_changes;
      if (light_since_[l] < oldest) oldest = light_since_[l];
    }
  }
  for (uint32_t o = 0; o < object_count_; ++o) {
    if (object_since_[o] == kNotPending) continue;
    if (ready_ && want_visible_[o] == shown_visible_[o]) {
      complete(&object_since_[o]);
    } else {
      ++stats_.pending_changes;
      if (object_since_[o] < oldest) oldest = object_since_[o];
    }
  }
  if (oldest != kNotPending) stats_.oldest_pending_frames = uint32_t(frame_ - oldest + 1);
  stats_.rebuild_active = rebuilding_;
  stats_.rebuild_remaining_texels = rebuilding_ ? rebuild_left_ : 0;
  stats_.error_bound = ready_ ? drift() : 0.0f;
}

bool Planner::idle() const {
  if (!ready_ || rebuilding_) return false;
  for (uint32_t l = 0; l < light_count_; ++l) {
    float want[3];
    want_factor(l, want);
    if (!same(want, shown_[l].rgb)) return false;
  }
  for (uint32_t o = 0; o < object_count_; ++o) {
    if (want_visible_[o] != shown_visible_[o]) return false;
  }
  return true;
}

Status check_authored_map_bound(const PackView& pack, Error* error) {
  Planner planner;
  if (Status s = planner.init(pack, PlannerLimits(), error); s != Status::kOk) return s;
  const float bound = planner.wanted_map_bound();
  if (!(bound <= kMaxAuthoredMapBound)) {
    return set_error(error, Status::kOutOfRange,
                     "the authored light map could reach %g, beyond the %g the runtime opens",
                     double(bound), double(kMaxAuthoredMapBound));
  }
  return Status::kOk;
}

}  // namespace lightpatch
