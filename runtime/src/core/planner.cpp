#include "lightpatch/planner.h"

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <new>

namespace lightpatch {
namespace {

constexpr uint64_t kNotPending = ~0ull;
constexpr float kHalfUlp = 1.0f / 2048.0f;  // unit roundoff of IEEE half floats

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
  error_bound_ = 0.0f;
  base_max_ = 0.0f;
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

  // References from lights and objects to their shadow/pair groups.
  uint32_t light_refs = 0, object_refs = 0;
  for (uint32_t g = 0; g < ng; ++g) {
    const pack::GroupRecord& gr = pack.group(g);
    if (gr.kind == pack::kGroupShadow) ++light_refs, ++object_refs;
    if (gr.kind == pack::kGroupPairCorrection) ++light_refs, object_refs += 2;
    if (gr.kind == pack::kGroupStaticShadow) ++object_refs;
  }

  for (int pass = 0; pass < 2; ++pass) {
    Carver c{static_cast<uint8_t*>(block_)};
    group_texels_ = c.take<uint64_t>(ng);
    patch_prefix_ = c.take<uint64_t>(size_t(patch_count) + 1);
    light_since_ = c.take<uint64_t>(nl);
    object_since_ = c.take<uint64_t>(no);
    group_max_ = c.take<float>(ng);
    light_max_ = c.take<float>(nl);
    contribution_ = c.take<int32_t>(nl);
    light_first_ = c.take<uint32_t>(size_t(nl) + 1);
    light_groups_ = c.take<uint32_t>(light_refs);
    object_first_ = c.take<uint32_t>(size_t(no) + 1);
    object_groups_ = c.take<uint32_t>(object_refs);
    color_ = c.take<Factor>(nl);
    shown_ = c.take<Factor>(nl);
    build_ = c.take<Factor>(nl);
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

  clear_texels_ = uint64_t(pack.lightmap_width()) * pack.lightmap_height();
  patch_prefix_[0] = 0;
  for (uint32_t p = 0; p < patch_count; ++p) {
    const pack::PatchRecord& pr = pack.patch(p);
    patch_prefix_[p + 1] = patch_prefix_[p] + uint64_t(pr.width) * pr.height;
  }
  for (uint32_t l = 0; l < nl; ++l) contribution_[l] = -1;
  // Counting sort of the references.
  for (uint32_t g = 0; g < ng; ++g) {
    const pack::GroupRecord& gr = pack.group(g);
    group_texels_[g] =
        patch_prefix_[gr.first_patch + gr.patch_count] - patch_prefix_[gr.first_patch];
    float m = 0.0f;
    for (uint32_t p = gr.first_patch; p < gr.first_patch + gr.patch_count; ++p) {
      if (pack.patch(p).scale > m) m = pack.patch(p).scale;
    }
    group_max_[g] = m;
    if (gr.kind == pack::kGroupStaticShadow) {
      base_max_ += m;
      ++object_first_[gr.object_a + 1];
      continue;
    }
    if (gr.kind == pack::kGroupBase) base_max_ += m;
    if (gr.kind == pack::kGroupContribution) contribution_[gr.light] = int32_t(g);
    if (gr.kind != pack::kGroupBase) light_max_[gr.light] += m;
    if (gr.kind == pack::kGroupShadow || gr.kind == pack::kGroupPairCorrection) {
      ++light_first_[gr.light + 1];
      ++object_first_[gr.object_a + 1];
      if (gr.kind == pack::kGroupPairCorrection) ++object_first_[gr.object_b + 1];
    }
  }
  for (uint32_t l = 0; l < nl; ++l) light_first_[l + 1] += light_first_[l];
  for (uint32_t o = 0; o < no; ++o) object_first_[o + 1] += object_first_[o];
  {
    // Fill using the since arrays as temporary cursors (reset below).
    for (uint32_t l = 0; l < nl; ++l) light_since_[l] = light_first_[l];
    for (uint32_t o = 0; o < no; ++o) object_since_[o] = object_first_[o];
    for (uint32_t g = 0; g < ng; ++g) {
      const pack::GroupRecord& gr = pack.group(g);
      if (gr.kind == pack::kGroupStaticShadow) object_groups_[object_since_[gr.object_a]++] = g;
      if (gr.kind != pack::kGroupShadow && gr.kind != pack::kGroupPairCorrection) continue;
      light_groups_[light_since_[gr.light]++] = g;
      object_groups_[object_since_[gr.object_a]++] = g;
      if (gr.kind == pack::kGroupPairCorrection) object_groups_[object_since_[gr.object_b]++] = g;
    }
  }
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

Status Planner::set_light(uint32_t light, bool on, const float color[3], float intensity) {
  if (light >= light_count_) return Status::kInvalidArgument;
  for (int c = 0; c < 3; ++c) {
    if (!std::isfinite(color[c]) || color[c] < 0.0f) return Status::kInvalidArgument;
  }
  if (!std::isfinite(intensity) || intensity < 0.0f) return Status::kInvalidArgument;
  on_[light] = on ? 1 : 0;
  std::memcpy(color_[light].rgb, color, sizeof(float) * 3);
  intensity_[light] = intensity;
  float f[3];
  want_factor(light, f);
  if (std::isinf(max3(f))) return Status::kInvalidArgument;  // colour * intensity overflowed
  if (light_since_[light] == kNotPending) light_since_[light] = frame_ + 1;
  return Status::kOk;
}

Status Planner::set_object_visible(uint32_t object, bool visible) {
  if (object >= object_count_) return Status::kInvalidArgument;
  want_visible_[object] = visible ? 1 : 0;
  if (object_since_[object] == kNotPending) object_since_[object] = frame_ + 1;
  return Status::kOk;
}

bool Planner::group_active(uint32_t g, const Factor* factors, const uint8_t* visible) const {
  const pack::GroupRecord& gr = pack_->group(g);
  if (gr.kind == pack::kGroupBase) return true;
  if (gr.kind == pack::kGroupStaticShadow) return visible[gr.object_a] != 0;
  if (!nonzero(factors[gr.light].rgb)) return false;
  if (gr.kind == pack::kGroupContribution) return true;
  if (!visible[gr.object_a]) return false;
  return gr.kind == pack::kGroupShadow || visible[gr.object_b];
}

float Planner::magnitude(const Factor* factors) const {
  float m = base_max_;
  for (uint32_t l = 0; l < light_count_; ++l) m += max3(factors[l].rgb) * light_max_[l];
  return m;
}

uint64_t Planner::rebuild_texels() const {
  // The wanted state's factors, computed on the fly.
  uint64_t total = clear_texels_;
  for (uint32_t g = 0; g < group_count_; ++g) {
    const pack::GroupRecord& gr = pack_->group(g);
    bool active = true;
    if (gr.kind == pack::kGroupStaticShadow) {
      active = want_visible_[gr.object_a] != 0;
    } else if (gr.kind != pack::kGroupBase) {
      float f[3];
      want_factor(gr.light, f);
      active = nonzero(f);
      if (active && gr.kind != pack::kGroupContribution) {
        active = want_visible_[gr.object_a] &&
                 (gr.kind == pack::kGroupShadow || want_visible_[gr.object_b]);
      }
    }
    if (active) total += group_texels_[g];
  }
  return total;
}

uint64_t Planner::light_change_texels(uint32_t l) const {
  uint64_t total = contribution_[l] >= 0 ? group_texels_[contribution_[l]] : 0;
  for (uint32_t i = light_first_[l]; i < light_first_[l + 1]; ++i) {
    const pack::GroupRecord& gr = pack_->group(light_groups_[i]);
    if (!shown_visible_[gr.object_a]) continue;
    if (gr.kind == pack::kGroupPairCorrection && !shown_visible_[gr.object_b]) continue;
    total += group_texels_[light_groups_[i]];
  }
  return total;
}

uint64_t Planner::object_change_texels(uint32_t o) const {
  uint64_t total = 0;
  for (uint32_t i = object_first_[o]; i < object_first_[o + 1]; ++i) {
    const pack::GroupRecord& gr = pack_->group(object_groups_[i]);
    if (gr.kind != pack::kGroupStaticShadow && !nonzero(shown_[gr.light].rgb)) continue;
    if (gr.kind == pack::kGroupPairCorrection) {
      const uint32_t other = gr.object_a == o ? gr.object_b : gr.object_a;
      if (!shown_visible_[other]) continue;
    }
    total += group_texels_[object_groups_[i]];
  }
  return total;
}

void Planner::emit(DrawSink& sink, DrawTarget target, uint32_t group, uint32_t first,
                   uint32_t count, const float factor[3], uint64_t texels) {
  sink.draw(target, group, first, count, factor);
  stats_.texels += texels;
  ++stats_.draws;
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
  rebuild_left_ = clear_texels_;
  for (uint32_t g = 0; g < group_count_; ++g) {
    if (group_active(g, build_, build_visible_)) rebuild_left_ += group_texels_[g];
  }
}

// Runs rebuild steps within the budget; true when the rebuild was presented.
bool Planner::run_rebuild(uint64_t budget, DrawSink& sink) {
  auto room = [&] { return budget - stats_.texels; };
  if (!rebuild_cleared_) {
    if (clear_texels_ > room()) {
      if (stats_.texels != 0 || clear_texels_ <= budget) return false;
      stats_.oversize_steps = 1;  // alone in its frame
    }
    sink.clear_intermediate();
    stats_.texels += clear_texels_;
    rebuild_left_ -= clear_texels_;
    rebuild_cleared_ = true;
    if (stats_.oversize_steps) return false;
  }
  for (; rebuild_group_ < group_count_; ++rebuild_group_, rebuild_patch_ = 0) {
    if (!group_active(rebuild_group_, build_, build_visible_)) continue;
    const pack::GroupRecord& gr = pack_->group(rebuild_group_);
    // Base and static shadows have the fixed factor 1 (the sign is the group's).
    const float* f = gr.kind == pack::kGroupBase || gr.kind == pack::kGroupStaticShadow
                         ? nullptr
                         : build_[gr.light].rgb;
    const float one[3] = {1.0f, 1.0f, 1.0f};
    const uint32_t first = gr.first_patch + rebuild_patch_;
    const uint32_t end = gr.first_patch + gr.patch_count;
    if (first == end) continue;  // finished by an earlier partial step
    const uint64_t whole = patch_prefix_[end] - patch_prefix_[first];
    if (whole <= room()) {
      emit(sink, DrawTarget::kIntermediate, rebuild_group_, first, end - first, f ? f : one, whole);
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
    emit(sink, DrawTarget::kIntermediate, rebuild_group_, first, k - first, f ? f : one, texels);
    rebuild_left_ -= texels;
    rebuild_patch_ = k - gr.first_patch;
    return false;
  }
  sink.present();
  std::memcpy(shown_, build_, sizeof(Factor) * light_count_);
  std::memcpy(shown_visible_, build_visible_, object_count_);
  rebuilding_ = false;
  ready_ = true;
  error_bound_ = 0.0f;
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
  if (cost > budget - stats_.texels) return false;  // next frame
  float want[3], d[3];
  want_factor(l, want);
  for (int c = 0; c < 3; ++c) d[c] = want[c] - shown_[l].rgb[c];
  const float before = magnitude(shown_);
  uint32_t draws = 0;
  if (contribution_[l] >= 0) {
    const pack::GroupRecord& gr = pack_->group(uint32_t(contribution_[l]));
    emit(sink, DrawTarget::kLightMap, uint32_t(contribution_[l]), gr.first_patch, gr.patch_count, d,
         group_texels_[contribution_[l]]);
    ++draws;
  }
  for (uint32_t i = light_first_[l]; i < light_first_[l + 1]; ++i) {
    const uint32_t g = light_groups_[i];
    const pack::GroupRecord& gr = pack_->group(g);
    if (!shown_visible_[gr.object_a]) continue;
    if (gr.kind == pack::kGroupPairCorrection && !shown_visible_[gr.object_b]) continue;
    emit(sink, DrawTarget::kLightMap, g, gr.first_patch, gr.patch_count, d, group_texels_[g]);
    ++draws;
  }
  std::memcpy(shown_[l].rgb, want, sizeof want);
  const float after = magnitude(shown_);
  error_bound_ += float(draws) * kHalfUlp * (before > after ? before : after);
  return true;
}

bool Planner::apply_object_change(uint32_t o, uint64_t budget, DrawSink& sink, bool* started) {
  const uint64_t cost = object_change_texels(o);
  if (cost > budget || cost >= rebuild_texels()) {
    start_rebuild();
    *started = true;
    return false;
  }
  if (cost > budget - stats_.texels) return false;
  const float sign = want_visible_[o] ? 1.0f : -1.0f;
  const float m = magnitude(shown_);
  uint32_t draws = 0;
  for (uint32_t i = object_first_[o]; i < object_first_[o + 1]; ++i) {
    const uint32_t g = object_groups_[i];
    const pack::GroupRecord& gr = pack_->group(g);
    const bool fixed = gr.kind == pack::kGroupStaticShadow;
    if (!fixed && !nonzero(shown_[gr.light].rgb)) continue;
    if (gr.kind == pack::kGroupPairCorrection) {
      const uint32_t other = gr.object_a == o ? gr.object_b : gr.object_a;
      if (!shown_visible_[other]) continue;
    }
    const float f[3] = {sign * (fixed ? 1.0f : shown_[gr.light].rgb[0]),
                        sign * (fixed ? 1.0f : shown_[gr.light].rgb[1]),
                        sign * (fixed ? 1.0f : shown_[gr.light].rgb[2])};
    emit(sink, DrawTarget::kLightMap, g, gr.first_patch, gr.patch_count, f, group_texels_[g]);
    ++draws;
  }
  shown_visible_[o] = want_visible_[o];
  error_bound_ += float(draws) * kHalfUlp * m;
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
  if (!ready_ && !rebuilding_) start_rebuild();
  if (rebuilding_) run_rebuild(budget, sink);

  // Incremental changes against the presented map (none while a rebuild runs: they would be lost
  // when it is presented; they wait and are applied after it).
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
    if (!started && error_bound_ > limits_.drift_tolerance_ulps * kHalfUlp * magnitude(shown_)) {
      start_rebuild();
      started = true;
    }
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
  stats_.error_bound = error_bound_;
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

}  // namespace lightpatch
