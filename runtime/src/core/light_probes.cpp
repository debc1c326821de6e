// LightProbes: incremental evaluation of the probe sets for a state, and the grid query
// (light_probes.h).
#include "lightpatch/light_probes.h"

#include <cmath>
#include <cstdlib>
#include <cstring>

#include "lightpatch/group_rules.h"
#include "lightpatch/spherical_harmonics.h"

namespace lightpatch {

using namespace pack;

LightProbes::~LightProbes() {
  std::free(accumulator_);
  std::free(applied_);
  std::free(per_probe_);
}

Status LightProbes::init(const PackView& pack, Error* error) {
  if (!pack.valid())
    return set_error(error, Status::kInvalidArgument, "light probes: pack not open");
  std::free(accumulator_);
  std::free(applied_);
  std::free(per_probe_);
  accumulator_ = nullptr;
  applied_ = nullptr;
  per_probe_ = nullptr;
  stats_ = Stats();
  memory_ = 0;
  pack_ = pack;
  const uint64_t probes = pack.probe_count(), sets = pack.probe_set_count();
  // One element at least, so that a pack without probes still has valid pointers.
  const uint64_t acc_bytes = (probes > 0 ? probes : 1) * kProbeShFloats * sizeof(double);
  const uint64_t applied_bytes = (sets > 0 ? sets : 1) * 3 * sizeof(float);
  const uint64_t per_probe_bytes = (probes > 0 ? probes : 1) * sizeof(uint32_t);
  accumulator_ = static_cast<double*>(std::calloc(1, acc_bytes));
  applied_ = static_cast<float*>(std::calloc(1, applied_bytes));
  per_probe_ = static_cast<uint32_t*>(std::calloc(1, per_probe_bytes));
  if (accumulator_ == nullptr || applied_ == nullptr || per_probe_ == nullptr) {
    pack_ = PackView();
    return set_error(error, Status::kOutOfMemory, "light probes: cannot allocate %llu probes",
                     static_cast<unsigned long long>(probes));
  }
  memory_ = acc_bytes + applied_bytes + per_probe_bytes;
  for (uint32_t e = 0; e < pack.probe_entry_count(); ++e) ++per_probe_[pack.probe_entry(e).probe];
  for (uint32_t p = 0; p < pack.probe_count(); ++p) {
    if (per_probe_[p] > stats_.max_entries_per_probe) stats_.max_entries_per_probe = per_probe_[p];
  }
  stats_.rebuild_entries = pack.probe_entry_count();
  return Status::kOk;
}

// The set's factor in `state` with its sign: group_rules.h's, as the light map applies its groups.
template <typename Factor, typename Visible>
Status LightProbes::apply(Factor&& factor, Visible&& visible, bool from_zero) {
  if (from_zero) {
    std::memset(accumulator_, 0, sizeof(double) * kProbeShFloats * pack_.probe_count());
    std::memset(applied_, 0, sizeof(float) * 3 * pack_.probe_set_count());
  }
  uint64_t entries = 0;
  uint32_t changed = 0;
  for (uint32_t s = 0; s < pack_.probe_set_count(); ++s) {
    const ProbeSetRecord& r = pack_.probe_set(s);
    // The set's factor, its sign included: group_rules.h, as for the map's groups.
    const bool active = group_active(
        r,
        [&](uint32_t l) {
          float f[3];
          factor(l, f);
          return f[0] != 0.0f || f[1] != 0.0f || f[2] != 0.0f;
        },
        visible);
    const float sign = group_sign(r.kind);
    float f[3] = {0.0f, 0.0f, 0.0f};
    if (active && group_has_light(r.kind)) {
      factor(r.light, f);
      for (int c = 0; c < 3; ++c) f[c] *= sign;
    } else if (active) {
      f[0] = f[1] = f[2] = sign;
    }
    float* old = applied_ + size_t(s) * 3;
    if (f[0] == old[0] && f[1] == old[1] && f[2] == old[2]) continue;
    const double d[3] = {double(f[0]) - old[0], double(f[1]) - old[1], double(f[2]) - old[2]};
    for (uint32_t e = r.first_entry; e < r.first_entry + r.entry_count; ++e) {
      const ProbeEntry& pe = pack_.probe_entry(e);
      double* acc = accumulator_ + size_t(pe.probe) * kProbeShFloats;
      for (uint32_t k = 0; k < kProbeShCount; ++k) {
        for (int c = 0; c < 3; ++c) acc[k * 3 + c] += d[c] * double(pe.sh[k * 3 + c]);
      }
    }
    old[0] = f[0];
    old[1] = f[1];
    old[2] = f[2];
    entries += r.entry_count;
    ++changed;
  }
  stats_.entries_last_update = entries;
  stats_.sets_changed_last_update = changed;
  stats_.entries_total += entries;
  return Status::kOk;
}

namespace {

bool same_pack(const PackView& pack, const SceneState& state) {
  return pack.valid() && state.light_count() == pack.light_count() &&
         state.object_count() == pack.object_count();
}

}  // namespace

Status LightProbes::apply_state(const SceneState& state, bool from_zero) {
  if (!same_pack(pack_, state)) return Status::kInvalidArgument;
  return apply([&](uint32_t l, float out[3]) { state.light_factor(l, out); },
               [&](uint32_t o) { return state.object_visible(o); }, from_zero);
}

Status LightProbes::update(const SceneState& state) {
  return apply_state(state, false);
}

Status LightProbes::rebuild(const SceneState& state) {
  return apply_state(state, true);
}

Status LightProbes::update(const Planner& planner) {
  if (!pack_.valid() || planner.light_count() != pack_.light_count() ||
      planner.object_count() != pack_.object_count()) {
    return Status::kInvalidArgument;
  }
  if (!planner.map_ready()) return Status::kOk;  // nothing presented: the probes stay
  return apply([&](uint32_t l, float out[3]) { planner.shown_factor(l, out); },
               [&](uint32_t o) { return planner.shown_visible(o); }, false);
}

void LightProbes::probe_sh(uint32_t i, float out[kProbeShFloats]) const {
  const double* acc = accumulator_ + size_t(i) * kProbeShFloats;
  for (uint32_t k = 0; k < kProbeShFloats; ++k) out[k] = float(acc[k]);
}

int32_t LightProbes::find_probe(const char* name) const {
  if (name == nullptr || !pack_.valid()) return -1;
  return pack_.find_probe(name, uint32_t(std::strlen(name)));
}

bool LightProbes::sample(const float pos[3], float out[kProbeShFloats]) const {
  if (!pack_.valid() || !pack_.has_probe_grid()) return false;
  const ProbeGridRecord& g = pack_.probe_grid();
  const uint32_t* index = pack_.probe_grid_indices();
  // Per axis: the cell's lower grid index and the point's fraction across it, clamped to the cell
  // (outside the grid: the nearest cell's face). Computed in float, clamped before any cast, so
  // that a far or non-finite position cannot overflow an integer.
  uint32_t base[3];
  float frac[3];
  for (int a = 0; a < 3; ++a) {
    const float t = (pos[a] - g.origin[a]) / g.spacing;
    const float last_cell = float(g.size[a] >= 2 ? g.size[a] - 2 : 0);
    float cell = std::floor(t);
    if (!(cell >= 0.0f)) cell = 0.0f;  // also NaN
    if (cell > last_cell) cell = last_cell;
    base[a] = uint32_t(cell);
    float f = g.size[a] >= 2 ? t - cell : 0.0f;
    if (!(f >= 0.0f)) f = 0.0f;
    if (f > 1.0f) f = 1.0f;
    frac[a] = f;
  }
  // The corners: probe index, weight, whether the point reaches it, its squared distance.
  uint32_t probe[8];
  float weight[8];
  bool reachable[8];
  float distance2[8];
  float total = 0.0f;
  for (uint32_t k = 0; k < 8; ++k) {
    uint32_t idx[3];
    float w = 1.0f;
    for (int a = 0; a < 3; ++a) {
      const uint32_t bit = (k >> a) & 1u;
      idx[a] = base[a] + (g.size[a] >= 2 ? bit : 0u);
      w *= bit ? frac[a] : 1.0f - frac[a];
    }
    // The point's index is < the product of the sizes (validated), so this fits 64 bits.
    const uint64_t point = idx[0] + uint64_t(g.size[0]) * (idx[1] + uint64_t(g.size[1]) * idx[2]);
    probe[k] = index[point];
    weight[k] = 0.0f;
    reachable[k] = false;
    distance2[k] = 0.0f;
    if (probe[k] == kNone32) continue;
    const ProbeRecord& pr = pack_.probe(probe[k]);
    bool reach = true;
    float d2 = 0.0f;
    for (int a = 0; a < 3; ++a) {
      const float d = pos[a] - pr.position[a];
      // reach[2a] looks along +axis, reach[2a + 1] along -axis (pack_format.h).
      const float r = d >= 0.0f ? pr.reach[2 * a] : pr.reach[2 * a + 1];
      if (!(std::fabs(d) <= r)) reach = false;  // NaN: not reachable
      d2 += d * d;
    }
    distance2[k] = d2;
    reachable[k] = reach;
    if (reach) {
      weight[k] = w;
      total += w;
    }
  }
  if (total > 0.0f) {
    double sum[kProbeShFloats] = {};
    for (uint32_t k = 0; k < 8; ++k) {
      if (weight[k] <= 0.0f) continue;
      const double w = double(weight[k]) / double(total);
      const double* acc = accumulator_ + size_t(probe[k]) * kProbeShFloats;
      for (uint32_t i = 0; i < kProbeShFloats; ++i) sum[i] += w * acc[i];
    }
    for (uint32_t i = 0; i < kProbeShFloats; ++i) out[i] = float(sum[i]);
    return true;
  }
  // No corner left with a weight: the nearest reachable corner probe, else the nearest at all.
  int best = -1;
  for (int pass = 0; pass < 2 && best < 0; ++pass) {
    for (uint32_t k = 0; k < 8; ++k) {
      if (probe[k] == kNone32 || (pass == 0 && !reachable[k])) continue;
      // NaN distances (a non-finite position) lose to any number; the first corner stands in.
      if (best < 0 || distance2[k] < distance2[best]) best = int(k);
    }
  }
  if (best < 0) return false;
  probe_sh(probe[best], out);
  return true;
}

void LightProbes::irradiance(const float sh[kProbeShFloats], const float n[3], float rgb[3]) {
  sh_irradiance(sh, n[0], n[1], n[2], rgb);
  for (int c = 0; c < 3; ++c) rgb[c] = rgb[c] > 0.0f ? rgb[c] : 0.0f;  // also NaN -> 0
}

}  // namespace lightpatch
