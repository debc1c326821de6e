#include "farm/group_inputs.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "direct_light.h"
#include "texel_footprint.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

namespace {

Digest mesh_digest(const Scene& scene, size_t index) {
  const MeshInstance& m = scene.meshes[index];
  ContentHash h;
  h.value(uint64_t(index));
  h.value(m.object);
  h.value(m.cast_shadows);
  h.array(m.positions);
  h.array(m.normals);
  h.array(m.indices);
  // Emission makes a static mesh a light (EmissiveLights); albedo reaches the bake through the
  // texels.
  const bool has_material = m.material >= 0 && size_t(m.material) < scene.materials.size();
  h.value(m.material);
  h.value(has_material ? scene.materials[size_t(m.material)].emissive : glm::vec3(0.0f));
  return h.finish();
}

// The texels of each layout region (the last bucket: texels of no region), and the bounds of
// their valid positions.
struct TexelBuckets {
  std::vector<Digest> digest;
  std::vector<glm::vec3> lo, hi;  // lo.x > hi.x: no valid texel
};

// `foot`: the texels' footprints (empty: sample points only), whose receiver points spread up to
// a texel around each sample point: part of the digest, and of the bounds.
TexelBuckets texel_buckets(const TexelSet& t, const std::vector<TexelFootprint>& foot,
                           size_t regions, int threads) {
  std::vector<std::vector<uint32_t>> members(regions + 1);
  for (size_t i = 0; i < t.position.size(); ++i) {
    const int32_t r = i < t.region.size() ? t.region[i] : -1;
    members[r >= 0 && size_t(r) < regions ? size_t(r) : regions].push_back(uint32_t(i));
  }
  TexelBuckets b;
  b.digest.resize(regions + 1);
  b.lo.assign(regions + 1, glm::vec3(std::numeric_limits<float>::max()));
  b.hi.assign(regions + 1, glm::vec3(-std::numeric_limits<float>::max()));
  const bool has_albedo = t.albedo.size() == t.position.size();
  const bool has_mesh = t.mesh.size() == t.position.size();
  parallel_for(int(regions + 1), threads, [&](int r) {
    ContentHash h;
    h.value(uint64_t(r));
    h.value(uint64_t(members[size_t(r)].size()));
    for (uint32_t i : members[size_t(r)]) {
      struct {
        uint32_t index;
        glm::vec3 position, normal, albedo;
        int32_t mesh;
        uint8_t valid;
      } rec{};
      rec.index = i;
      rec.position = t.position[i];
      rec.normal = t.normal[i];
      rec.albedo = has_albedo ? t.albedo[i] : glm::vec3(0.0f);
      rec.mesh = has_mesh ? t.mesh[i] : -1;
      rec.valid = t.valid[i];
      h.bytes(&rec.index, sizeof rec.index);
      h.value(rec.position);
      h.value(rec.normal);
      h.value(rec.albedo);
      h.value(rec.mesh);
      h.value(rec.valid);
      float spread = 0.0f;
      if (i < foot.size()) {
        const TexelFootprint& f = foot[i];
        h.value(f.u);
        h.value(f.v);
        h.value(f.a0);
        h.value(f.a1);
        h.value(f.b0);
        h.value(f.b1);
        spread = glm::length(f.u) * std::max(std::abs(f.a0), std::abs(f.a1)) +
                 glm::length(f.v) * std::max(std::abs(f.b0), std::abs(f.b1));
      }
      if (t.valid[i]) {
        b.lo[size_t(r)] = glm::min(b.lo[size_t(r)], t.position[i] - glm::vec3(spread));
        b.hi[size_t(r)] = glm::max(b.hi[size_t(r)], t.position[i] + glm::vec3(spread));
      }
    }
    b.digest[size_t(r)] = h.finish();
  });
  return b;
}

Digest layout_digest(const Layout& l) {
  ContentHash h;
  h.value(l.width);
  h.value(l.height);
  h.value(l.texels_per_unit);
  h.value(l.verbatim_uv1);
  h.value(uint64_t(l.regions.size()));
  for (const Region& r : l.regions) {
    h.value(r.object);
    h.array(r.meshes);
    h.value(r.rect.x);
    h.value(r.rect.y);
    h.value(r.rect.w);
    h.value(r.rect.h);
  }
  h.value(uint64_t(l.meshes.size()));
  for (const MeshLayout& m : l.meshes) {
    h.array(m.source_vertex);
    h.array(m.uv);
    h.array(m.indices);
  }
  return h.finish();
}

// Whether any valid texel of a bucket can be within `reach` of `at` (with a margin for rounding:
// a bucket let in needlessly only costs reuse, never correctness).
bool within(const TexelBuckets& tb, size_t r, const glm::vec3& at, float reach, float eps) {
  if (tb.lo[r].x > tb.hi[r].x) return false;
  if (!(reach < std::numeric_limits<float>::infinity())) return true;
  const glm::vec3 nearest = glm::clamp(at, tb.lo[r], tb.hi[r]);
  return glm::length(nearest - at) <= reach * 1.001f + 8.0f * eps;
}

void light_record(ContentHash& h, const Light& l, const LightPlan& lp, bool with_colour) {
  h.value(l.type);
  h.value(l.position);
  h.value(l.direction);
  h.value(l.range);
  h.value(l.inner_cone);
  h.value(l.outer_cone);
  h.value(l.radius);
  h.value(l.semi_dynamic);
  if (with_colour) {
    h.value(l.color);
    h.value(l.intensity);
  }
  h.value(lp.threshold);
  h.value(lp.cutoff);
  h.value(lp.samples);
}

}  // namespace

JobDigests job_input_digests(const PreparedScene& p, const BakeContext& b, const BakePlan& plan,
                             const std::string& tool) {
  const Scene& scene = p.scene;
  std::vector<Digest> meshes(scene.meshes.size());
  parallel_for(int(meshes.size()), b.threads,
               [&](int m) { meshes[size_t(m)] = mesh_digest(scene, size_t(m)); });
  ContentHash statics;
  statics.value(uint64_t(meshes.size()));
  for (size_t m = 0; m < meshes.size(); ++m)
    if (scene.meshes[m].object < 0) statics.digest(meshes[m]);
  const Digest static_digest = statics.finish();
  std::vector<Digest> objects(scene.objects.size());
  for (size_t o = 0; o < objects.size(); ++o) {
    ContentHash h;
    h.value(uint64_t(o));
    h.array(scene.objects[o].meshes);
    for (int m : scene.objects[o].meshes)
      if (m >= 0 && size_t(m) < meshes.size()) h.digest(meshes[size_t(m)]);
    objects[o] = h.finish();
  }
  const TexelBuckets tb = texel_buckets(p.texels, b.footprints, p.layout.regions.size(), b.threads);
  ContentHash common;
  common.text("lightpatch cook job");
  common.value(kJobInputsVersion);
  common.text(tool);
  const BakeOptions& o = b.options;
  const GatherPreset gp = gather_preset(o);
  common.value(o.quality);
  common.value(b.area_samples);
  common.value(b.texel_samples);
  common.value(o.seed);
  common.value(o.indirect);
  common.value(o.integrator);
  common.value(gp.rays);
  common.value(gp.level);
  common.value(gp.denoise);
  common.value(gp.contact_texels);
  common.value(o.plan_effects);
  common.value(p.texels.width);
  common.value(p.texels.height);
  common.value(p.layout.align);  // the blocks of the indirect parts
  common.value(b.eps);
  common.value(b.extent);
  common.value(b.output_step);
  common.value(uint64_t(scene.lights.size()));
  common.value(uint64_t(scene.objects.size()));
  common.digest(static_digest);
  const Digest common_digest = common.finish();

  const bool indirect = b.options.indirect;
  JobDigests out;
  Digest gather{};
  if (indirect) {
    // The gather operator: rays from every texel, hits on every surface and object, mapped to
    // texels through the layout. Not the lights or the output step: an edit of a light keeps it.
    ContentHash h;
    h.text("lightpatch gather rays");
    h.value(kJobInputsVersion);
    h.text(tool);
    h.value(o.seed);
    h.value(o.integrator);
    h.value(gp.rays);
    h.value(gp.level);
    h.value(p.texels.width);
    h.value(p.texels.height);
    h.value(b.eps);
    h.value(b.extent);
    h.digest(static_digest);
    h.digest(layout_digest(p.layout));
    for (const Digest& d : tb.digest) h.digest(d);
    for (const Digest& d : objects) h.digest(d);
    gather = h.finish();
    out.has_gather = true;
    out.gather = gather;
  }

  for (size_t g = 0; g < plan.groups.size(); ++g) {
    const LightGroup& lg = plan.groups[g];
    ContentHash h;
    h.digest(common_digest);
    h.value(uint64_t(g));
    h.value(lg.light);
    h.value(lg.threshold);
    std::vector<std::pair<glm::vec3, float>> reach;  // the group's lights: where, how far
    bool everywhere = false;
    if (lg.light < 0) {
      h.value(b.static_step);
      for (size_t i = 0; i < scene.lights.size(); ++i) {
        if (scene.lights[i].semi_dynamic) continue;
        h.value(uint64_t(i));
        light_record(h, scene.lights[i], b.lights[i], true);
        reach.push_back(
            {scene.lights[i].position, light_reach(scene.lights[i], b.lights[i].cutoff)});
      }
      everywhere = !b.emissive.empty();  // emissive surfaces are sampled from every texel
    } else {
      const size_t i = size_t(lg.light);
      light_record(h, scene.lights[i], b.lights[i], false);
      reach.push_back({scene.lights[i].position, light_reach(scene.lights[i], b.lights[i].cutoff)});
    }
    h.value(uint64_t(lg.candidates.size()));
    for (int c : lg.candidates) {
      h.value(c);
      h.digest(objects[size_t(c)]);
    }
    h.value(uint64_t(lg.bounce_only.size()));
    for (size_t q = 0; q < lg.bounce_only.size(); ++q) {
      h.value(lg.bounce_only[q]);
      h.text(q < lg.bounce_only_why.size() ? lg.bounce_only_why[q] : std::string());
    }
    if (indirect) {
      h.digest(gather);
    } else {
      // Direct light only: a texel beyond every light's reach gets exactly zero (the early outs
      // of sample_punctual), whatever it is; only the texels within reach are read.
      for (size_t r = 0; r < tb.digest.size(); ++r) {
        bool in = everywhere && tb.lo[r].x <= tb.hi[r].x;
        for (size_t k = 0; k < reach.size() && !in; ++k)
          in = within(tb, r, reach[k].first, reach[k].second, b.eps);
        if (!in) continue;
        h.value(uint64_t(r));
        h.digest(tb.digest[r]);
      }
    }
    out.groups.push_back(h.finish());
  }
  return out;
}

}  // namespace lightpatch::cooker
