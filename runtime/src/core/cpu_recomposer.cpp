#include "lightpatch/cpu_recomposer.h"

#include <new>

#include "lightpatch/patch_decode.h"

namespace lightpatch {

using namespace pack;

CpuRecomposer::~CpuRecomposer() {
  delete[] accum_;
  delete[] rgb_;
  delete[] contribution_;
  delete[] shadow_begin_;
  delete[] shadow_end_;
  delete[] pair_begin_;
  delete[] pair_end_;
  delete[] affected_;
}

Status CpuRecomposer::init(const PackView& pack, Error* error) {
  if (!pack.valid()) return set_error(error, Status::kInvalidArgument, "recomposer: pack not open");
  if (accum_ != nullptr)
    return set_error(error, Status::kInvalidArgument, "recomposer: already initialised");
  pack_ = pack;
  width_ = pack.lightmap_width();
  height_ = pack.lightmap_height();
  const uint64_t n = uint64_t(width_) * height_ * 3;
  const uint32_t nl = pack.light_count() > 0 ? pack.light_count() : 1;
  accum_ = new (std::nothrow) double[n];
  rgb_ = new (std::nothrow) float[n];
  contribution_ = new (std::nothrow) int32_t[nl];
  shadow_begin_ = new (std::nothrow) uint32_t[nl];
  shadow_end_ = new (std::nothrow) uint32_t[nl];
  pair_begin_ = new (std::nothrow) uint32_t[nl];
  pair_end_ = new (std::nothrow) uint32_t[nl];
  affected_ = new (std::nothrow) uint8_t[nl];
  if (!accum_ || !rgb_ || !contribution_ || !shadow_begin_ || !shadow_end_ || !pair_begin_ ||
      !pair_end_ || !affected_) {
    return set_error(error, Status::kOutOfMemory, "recomposer: cannot allocate a %ux%u light map",
                     width_, height_);
  }
  if (Status s = last_.init(pack, error); s != Status::kOk) return s;
  for (uint64_t i = 0; i < n; ++i) {
    accum_[i] = 0.0;
    rgb_[i] = 0.0f;
  }
  for (uint32_t l = 0; l < nl; ++l) {
    contribution_[l] = -1;
    shadow_begin_[l] = shadow_end_[l] = pair_begin_[l] = pair_end_[l] = 0;
  }
  base_ = -1;
  static_begin_ = static_end_ = 0;
  // Groups are sorted by (kind, light, object_a, object_b): each light's shadow groups and pair
  // groups are contiguous.
  for (uint32_t g = 0; g < pack.group_count(); ++g) {
    const GroupRecord& r = pack.group(g);
    switch (r.kind) {
      case kGroupBase:
        base_ = static_cast<int32_t>(g);
        break;
      case kGroupContribution:
        contribution_[r.light] = static_cast<int32_t>(g);
        break;
      case kGroupShadow:
        if (shadow_end_[r.light] == 0) shadow_begin_[r.light] = g;
        shadow_end_[r.light] = g + 1;
        break;
      case kGroupPairCorrection:
        if (pair_end_[r.light] == 0) pair_begin_[r.light] = g;
        pair_end_[r.light] = g + 1;
        break;
      case kGroupStaticShadow:
        if (static_end_ == 0) static_begin_ = g;
        static_end_ = g + 1;
        break;
      default:
        break;
    }
  }
  has_last_ = false;
  stats_ = Stats();
  return Status::kOk;
}

void CpuRecomposer::draw_group(uint32_t group, const double factor[3]) {
  const GroupRecord& g = pack_.group(group);
  for (uint32_t i = g.first_patch; i < g.first_patch + g.patch_count; ++i) {
    const PatchRecord& p = pack_.patch(i);
    const AtlasRecord& a = pack_.atlas(p.atlas);
    const uint8_t* pixels = pack_.atlas_pixels(p.atlas);
    // Decoding table for this patch: 256 values, so the texel loop is a lookup.
    float table[256];
    for (int q = 0; q < 256; ++q) table[q] = patch_decode(p, static_cast<uint8_t>(q));
    for (uint32_t y = 0; y < p.height; ++y) {
      const uint8_t* src =
          pixels + ((uint64_t(p.atlas_y) + y) * a.width + p.atlas_x) * 4 + p.channel;
      double* dst = accum_ + ((uint64_t(p.dest_y) + y) * width_ + p.dest_x) * 3;
      for (uint32_t x = 0; x < p.width; ++x, src += 4, dst += 3) {
        if (p.channel_count == 1) {
          const double v = table[src[0]];
          dst[0] += factor[0] * v;
          dst[1] += factor[1] * v;
          dst[2] += factor[2] * v;
        } else {
          dst[0] += factor[0] * table[src[0]];
          dst[1] += factor[1] * table[src[1]];
          dst[2] += factor[2] * table[src[2]];
        }
      }
    }
    stats_.patches_drawn++;
    stats_.texels_drawn += uint64_t(p.width) * p.height;
  }
}

void CpuRecomposer::draw_light(uint32_t light, const SceneState& state, const double factor[3]) {
  if (factor[0] == 0.0 && factor[1] == 0.0 && factor[2] == 0.0) return;
  if (contribution_[light] >= 0) draw_group(static_cast<uint32_t>(contribution_[light]), factor);
  const double negated[3] = {-factor[0], -factor[1], -factor[2]};
  for (uint32_t g = shadow_begin_[light]; g < shadow_end_[light]; ++g) {
    if (state.object_visible(pack_.group(g).object_a)) draw_group(g, negated);
  }
  for (uint32_t g = pair_begin_[light]; g < pair_end_[light]; ++g) {
    const GroupRecord& r = pack_.group(g);
    if (state.object_visible(r.object_a) && state.object_visible(r.object_b)) draw_group(g, factor);
  }
}

void CpuRecomposer::draw_static_shadows(const SceneState* from, const SceneState& to) {
  for (uint32_t g = static_begin_; g < static_end_; ++g) {
    const uint32_t o = pack_.group(g).object_a;
    const bool was = from != nullptr && from->object_visible(o), is = to.object_visible(o);
    if (was == is) continue;
    // Groups carry what the object changes with the opposite sign (as shadow groups do): -1
    // applies the change, +1 takes it back.
    const double f = is ? -1.0 : 1.0;
    const double factor[3] = {f, f, f};
    draw_group(g, factor);
  }
}

bool CpuRecomposer::light_touched_by_objects(uint32_t light, const SceneState& state) const {
  for (uint32_t g = shadow_begin_[light]; g < shadow_end_[light]; ++g) {
    const uint32_t o = pack_.group(g).object_a;
    if (state.object_visible(o) != last_.object_visible(o)) return true;
  }
  for (uint32_t g = pair_begin_[light]; g < pair_end_[light]; ++g) {
    const GroupRecord& r = pack_.group(g);
    if (state.object_visible(r.object_a) != last_.object_visible(r.object_a) ||
        state.object_visible(r.object_b) != last_.object_visible(r.object_b)) {
      return true;
    }
  }
  return false;
}

void CpuRecomposer::publish() {
  const uint64_t n = uint64_t(width_) * height_ * 3;
  for (uint64_t i = 0; i < n; ++i) rgb_[i] = static_cast<float>(accum_[i]);
}

namespace {
void factor_of(const SceneState& s, uint32_t light, double out[3]) {
  float f[3];
  s.light_factor(light, f);
  for (int c = 0; c < 3; ++c) out[c] = f[c];
}
}  // namespace

Status CpuRecomposer::rebuild(const SceneState& state) {
  if (accum_ == nullptr || state.light_count() != pack_.light_count() ||
      state.object_count() != pack_.object_count()) {
    return Status::kInvalidArgument;
  }
  stats_ = Stats();
  stats_.rebuilt = true;
  const uint64_t n = uint64_t(width_) * height_ * 3;
  for (uint64_t i = 0; i < n; ++i) accum_[i] = 0.0;
  const double one[3] = {1.0, 1.0, 1.0};
  if (base_ >= 0) draw_group(static_cast<uint32_t>(base_), one);
  draw_static_shadows(nullptr, state);
  for (uint32_t l = 0; l < pack_.light_count(); ++l) {
    double f[3];
    factor_of(state, l, f);
    draw_light(l, state, f);
  }
  publish();
  last_.assign(state);
  has_last_ = true;
  return Status::kOk;
}

Status CpuRecomposer::apply(const SceneState& state) {
  if (accum_ == nullptr || state.light_count() != pack_.light_count() ||
      state.object_count() != pack_.object_count()) {
    return Status::kInvalidArgument;
  }
  if (!has_last_) return rebuild(state);
  const uint32_t n = pack_.light_count();
  uint32_t m = 0;
  for (uint32_t l = 0; l < n; ++l) {
    double f_old[3], f_new[3];
    factor_of(last_, l, f_old);
    factor_of(state, l, f_new);
    const bool factor_changed =
        f_old[0] != f_new[0] || f_old[1] != f_new[1] || f_old[2] != f_new[2];
    const bool visibility_changed = light_touched_by_objects(l, state);
    const bool lit = f_old[0] != 0.0 || f_old[1] != 0.0 || f_old[2] != 0.0 || f_new[0] != 0.0 ||
                     f_new[1] != 0.0 || f_new[2] != 0.0;
    // 1: factor only (Alg. 8); 2: the light's shadowed contribution itself changed (Alg. 7).
    affected_[l] =
        factor_changed ? (visibility_changed ? 2 : 1) : (visibility_changed && lit ? 2 : 0);
    if (affected_[l] != 0) ++m;
  }
  if (!(2 * m < n)) {
    const Status s = rebuild(state);
    stats_.lights_updated = m;
    return s;
  }
  stats_ = Stats();
  stats_.lights_updated = m;
  draw_static_shadows(&last_, state);
  for (uint32_t l = 0; l < n; ++l) {
    if (affected_[l] == 0) continue;
    double f_old[3], f_new[3];
    factor_of(last_, l, f_old);
    factor_of(state, l, f_new);
    if (affected_[l] == 1) {
      const double delta[3] = {f_new[0] - f_old[0], f_new[1] - f_old[1], f_new[2] - f_old[2]};
      draw_light(l, state, delta);
    } else {
      const double remove[3] = {-f_old[0], -f_old[1], -f_old[2]};
      draw_light(l, last_, remove);
      draw_light(l, state, f_new);
    }
  }
  publish();
  last_.assign(state);
  return Status::kOk;
}

}  // namespace lightpatch
