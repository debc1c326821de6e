// lightpatch runtime: the library a game links. It maps nothing itself: the game maps the pack
// (platform::FileMapping, or PackMemory for bytes it holds), validates it (PackView::open) and
// opens a Runtime on it with a GLES 3.0 context current. Frame by frame the game sets lights and
// objects, calls update(budget) once, and samples light_map_texture() times light_map_scale().
//
// Packs with an indirect map (PackView::has_indirect_map(): bounce light at 1/2, 1/4 or 1/8 of
// the light map's resolution per axis) have a second sampled map, indirect_map_texture(), with
// its own accumulator; the game lights a surface at light-map UV (u, v) with
//   max(texture(light_map, uv) + texture(indirect_map, uv), 0) * light_map_scale()
// both sampled with the textures' own bilinear filtering (pack_format.h, "Two target maps"; the
// indirect texture clamps at its edges). Without one, indirect_map_texture() is 0.
//
// Fixed memory: open() allocates everything (GL objects included): the atlases (uploaded straight
// from the mapping), the light map the game samples (RGBA16F), one accumulator the patches are
// drawn into, one static vertex and index buffer with every patch's quad in pack order (a group's
// patches, e.g. a light's contribution, are one contiguous index range per target: one draw
// call), the programs, one VAO, two FBOs; with an indirect map, its sampled map, its accumulator
// and their two FBOs too. update() makes no heap allocation and creates no GL object.
//
// Recomposition, budgets, incremental changes and drift control: see planner.h. Paths, chosen at
// open() from what the driver offers (see path()):
//  * kGpuFloat: an RGBA32F accumulator with additive blending (EXT_color_buffer_float and
//    EXT_float_blend): the sums are as exact as float arithmetic; the sampled map is written from
//    it once per completed change or rebuild.
//  * kGpuHalf: an RGBA16F accumulator (EXT_color_buffer_half_float, EXT_color_buffer_float or
//    ES 3.2, without float blending). open() probes how the target rounds a blended write (Mesa's
//    llvmpipe truncates toward zero; drivers differ) and the planner counts a full ulp per write
//    where it does not round to nearest, which makes it rebuild rather than pile up subtractions.
//  * kCpu: no renderable float target (or RuntimeLimits::force_cpu_fallback): the same plan runs
//    on the CPU in double precision (cpu_sink.h) and the changed rows of the light map are
//    uploaded (glTexSubImage2D) after each frame that presented something.
//
// The sampled map holds, per channel, max(L, 0) / light_map_scale() rounded to the nearest half
// float (ties to even) on every path. With an indirect map both maps keep their sign, L and I
// alike: the light map corrects the indirect map's filter where it blends across a crease, so it
// may be negative there, and the game clamps the sum: max(L + I, 0) * light_map_scale().
// Light is never negative: the 8-bit quantization of B, C and S does not cancel exactly where a
// visible object removes all of a light, and leaves a few quantization steps of either sign there
// (planner.h); presenting clamps the negative ones at 0. light_map_scale() is a power of two chosen
// at open() from the pack so that its authored state fits the half-float range with 16x headroom (1
// unless the pack is brighter than 4096, e.g. a sun of 100,000 lux); set_light() refuses, with
// kOutOfRange, a state whose light map could exceed the largest half float times the scale: nothing
// is ever clamped at the top or wraps negative.
//
// Image orientation: texel row 0 of every texture (GL's t = 0 end, the first row uploaded or read
// back) is the image's top row, glTF v = 0. Sample the light map at (u, v) = the glTF light-map UV
// unchanged; read_light_map() returns the top row first.
//
// GL state: update(), restore() and draw_fill_floor() bind their own framebuffer, program, VAO,
// textures (units 0..8) and blending; they return with framebuffer 0, program 0, VAO 0, blending
// disabled, texture units 0..8 unbound, active unit 0, and the viewport set to the light map's
// size. Depth, stencil, scissor and face culling are disabled while drawing and left disabled.
//
// Light probes (light_probes.h) are evaluated on the CPU on every path: the game keeps a
// LightProbes, calls probes.update(runtime.planner()) each frame after update() (the state the
// light map shows), samples the SH where its moving things are and uploads it as uniforms; the
// runtime draws no probe.
//
// Moving lights (pack_format.h, "Moving lights"; moving_lights.h): set_light_pose() moves a light
// flagged moving; its colour, intensity, on and pose set the factors of the pack's panes (pseudo-
// lights whose contribution groups hold the bounce light of a patch of surface). update() follows
// them with set_light changes of the panes, within limits: when a moving light changed since the
// last update() it computes every pane's target factor (O(panes * moving lights * entry points),
// no allocation) and pushes, largest first, at most RuntimeLimits::max_pane_changes panes whose
// error |target - wanted factor| (max over channels) times the planner's bound of the pane's
// light (Planner::light_bound) exceeds pane_tolerance times the sum over panes of max_c(target) *
// bound. In an update() with no moving-light change since the last one the tolerance is 0: every
// pane off its target is pushed, so a light that stops gets every pane's factor exactly (bit for
// bit what SceneState::light_factor gives for state()) within ceil(P / max_pane_changes)
// update()s after the one that saw its last change (P: the panes off target then, at most
// pane_count()); the planner then shows those changes with its own latency (FrameStats). A push the
// planner refuses (kOutOfRange) leaves the pane at its old factor (FrameStats::pane_refused) and
// is tried again the next frame.
//
// GL errors are checked (glGetError, which can stall a driver) only in builds with
// LIGHTPATCH_GL_CHECKS (CMake option; on in Debug builds); elsewhere update() does not look.
#pragma once

#include <cstdint>

#include "lightpatch/pack_view.h"
#include "lightpatch/planner.h"
#include "lightpatch/scene_state.h"
#include "lightpatch/status.h"

namespace lightpatch {

struct RuntimeLimits {
  PlannerLimits planner;
  // Use the CPU path even where a renderable float target exists (tests, broken drivers).
  bool force_cpu_fallback = false;
  // Accumulate in RGBA16F even where float blending exists (tests, comparisons).
  bool force_half_accumulator = false;
  // Moving lights (see above): at most this many pane factors pushed to the planner per update()
  // (0: the panes keep their factors), largest error first.
  uint32_t max_pane_changes = 16;
  // While moving lights change, a pane is pushed only when its error exceeds this fraction of the
  // sum over panes of target * bound (the light the panes bring at most): 1/256, an 8-bit step.
  float pane_tolerance = 1.0f / 256.0f;
};

enum class RecomposePath : uint8_t { kGpuFloat, kGpuHalf, kCpu };
const char* path_name(RecomposePath path);

// Memory owned by the runtime, in bytes, by texture and buffer.
struct RuntimeMemory {
  uint64_t atlases = 0;
  uint64_t light_map = 0;             // the texture the game samples (RGBA16F)
  uint64_t accumulator = 0;           // the texture the patches are drawn into (0 on the CPU path)
  uint64_t indirect_map = 0;          // the indirect map the game samples (RGBA16F; 0 without one)
  uint64_t indirect_accumulator = 0;  // its accumulator (0 without one and on the CPU path)
  uint64_t vertex_buffer = 0;
  uint64_t index_buffer = 0;
  uint64_t cpu_fallback = 0;  // host memory of the CPU path (0 on the GPU paths)
};

class Runtime {
 public:
  Runtime() = default;
  ~Runtime();  // close()
  Runtime(const Runtime&) = delete;
  Runtime& operator=(const Runtime&) = delete;

  // Creates every resource in the current context. `pack` (and the memory it views) must outlive
  // the runtime. The wanted state starts at the pack's authored defaults; the first update()s
  // build it (ready() turns true when the first complete map is presented). kOutOfRange when the
  // authored light map could exceed the float range.
  Status open(const PackView& pack, const RuntimeLimits& limits, Error* error);
  // Deletes the GL objects (the context that made them must be current) and frees memory.
  void close();

  // After context loss: forget the old GL names (they died with their context), create everything
  // again in the now-current context from the mapping, and rebuild over the next update()s.
  Status restore(Error* error);

  uint32_t light_count() const { return pack_.light_count(); }
  uint32_t object_count() const { return pack_.object_count(); }
  // Index of the light/object with this glTF node name (NUL-terminated), or -1.
  int32_t find_light(const char* name) const;
  int32_t find_object(const char* name) const;

  // Wanted state; visible after later update()s (see stats() for latency). kInvalidArgument for a
  // value that is not finite and >= 0; kOutOfRange (state unchanged) when the light map of the
  // resulting state could exceed what the sampled map represents (see light_map_scale()). An
  // index out of range is a caller bug: it asserts (kInvalidArgument where asserts are off).
  Status set_light(uint32_t light, const LightState& state);
  Status set_light_on(uint32_t light, bool on);
  Status set_light_color(uint32_t light, const float rgb[3]);
  Status set_light_intensity(uint32_t light, float intensity);
  Status set_object_visible(uint32_t object, bool visible);
  // A light flagged moving (PackView::light_moves): its pose, world space, metres (position at
  // most 1e6 from the origin; direction unit within 1e-3, normalised; spots only). The panes follow
  // over the next update()s (see "Moving lights"). kInvalidArgument for another light or a pose
  // outside those ranges (state unchanged). The setters above refuse a pane light
  // (kInvalidArgument: a pane's factor follows the moving lights).
  Status set_light_pose(uint32_t light, const LightPose& pose);
  // The wanted pose (all zero for a light that does not move).
  LightPose light_pose(uint32_t light) const;
  // The light's wanted state as the planner holds it (a pane: on, its pushed factor, intensity 1).
  LightState light(uint32_t light) const;
  bool object_visible(uint32_t object) const { return planner_.object_visible(object); }
  // The wanted state as a SceneState (what the setters above accepted), e.g. for
  // LightProbes::update(). Valid from open() to close().
  const SceneState& state() const { return wanted_; }

  // Once per frame, on an open runtime: at most `budget_texels` texels written (planner.h's
  // budget rule). kGlError if GL checks are built in and the driver reported an error.
  Status update(uint64_t budget_texels);

  // Starts a full rebuild of the wanted state now (spread over the next update()s; a no-op while
  // one runs). The runtime also rebuilds on its own when its drift bound is reached.
  void request_rebuild() { planner_.request_rebuild(); }

  // The texture to sample (RGBA16F; linear irradiance divided by light_map_scale(); alpha 1). Its
  // name is fixed from open() to close() (restore() makes a new one). Holds a complete map once
  // ready().
  uint32_t light_map_texture() const { return light_map_; }
  // The indirect map to sample besides it (RGBA16F, linear filtering, clamped at its edges,
  // divided by light_map_scale() like the light map): indirect_width() x indirect_height() texels,
  // indirect_scale() light-map texels per texel along each axis. 0 (and scale 0) when the pack has
  // no indirect map. Fixed from open() to close() like light_map_texture().
  uint32_t indirect_map_texture() const { return indirect_map_; }
  uint32_t indirect_scale() const { return pack_.indirect_scale(); }
  uint32_t indirect_width() const { return pack_.indirect_width(); }
  uint32_t indirect_height() const { return pack_.indirect_height(); }
  // Multiply what the texture holds by this to get irradiance in the lights' units: a power of
  // two, fixed from open() to close().
  float light_map_scale() const { return scale_; }
  bool ready() const { return planner_.map_ready(); }
  // The limits open() was given.
  const RuntimeLimits& limits() const { return limits_; }
  // Presented, nothing pending, and every pane at its target factor (see "Moving lights").
  bool idle() const { return planner_.idle() && !panes_dirty_ && !panes_off_; }
  RecomposePath path() const { return path_; }
  bool gpu_path() const { return path_ != RecomposePath::kCpu; }
  // How the accumulator rounds (probed at open() on the GPU paths).
  const TargetPrecision& precision() const { return precision_; }
  // The planner's stats of the last update(), with its pane pushes (FrameStats::pane_*).
  const FrameStats& stats() const { return stats_; }
  const Planner& planner() const { return planner_; }
  RuntimeMemory memory() const { return memory_; }
  uint32_t width() const { return pack_.lightmap_width(); }
  uint32_t height() const { return pack_.lightmap_height(); }

  // Reads the sampled map back as irradiance (RGBA float, times light_map_scale(), width*height*4,
  // row 0 = top). For tools and tests: it stalls the pipeline. `out` must hold
  // width()*height()*4 floats.
  Status read_light_map(float* out, Error* error) const;
  // The same for the indirect map: indirect_width()*indirect_height()*4 floats (kInvalidArgument
  // when the pack has none). indirect_map.h adds it, magnified, to the light map.
  Status read_indirect_map(float* out, Error* error) const;

  // Benchmark aid (the fill-rate floor): draws `texels` texels of full-target quads with the patch
  // program and additive blending into the accumulator, the same per-texel work as a rebuild with
  // the fewest possible draws. Only while idle() and on a GPU path; it overwrites the accumulator,
  // so it starts a rebuild (the sampled map keeps the presented state meanwhile).
  Status draw_fill_floor(uint64_t texels, Error* error);

 private:
  friend class GlSink;
  Status create_gl(Error* error);
  Status choose_path(Error* error);
  Status create_programs(Error* error);
  Status create_buffers(Error* error);
  Status probe_rounding(Error* error);
  void delete_gl();
  void forget_gl();
  void set_draw_state() const;
  void reset_draw_state() const;
  Status read_map(uint8_t target, float* out, Error* error) const;
  // Pushes pane factors to the planner (see "Moving lights"); fills the stats' pane fields.
  void update_panes(FrameStats* stats);
  Status update_planner(uint64_t budget_texels);

  PackView pack_;
  RuntimeLimits limits_;
  Planner planner_;
  SceneState wanted_;  // mirrors the planner's wanted state (state())
  bool open_ = false;
  RecomposePath path_ = RecomposePath::kCpu;
  TargetPrecision precision_;
  float scale_ = 1.0f;          // light_map_scale()
  float inverse_scale_ = 1.0f;  // 1 / scale_ (exact: a power of two)
  RuntimeMemory memory_;
  FrameStats stats_;

  // Moving lights: per pane its target factor (RGB) and error; the chosen pushes (a heap of at
  // most pane_pick_capacity_ panes). Allocated at open().
  float* pane_target_ = nullptr;
  float* pane_error_ = nullptr;
  uint32_t* pane_pick_ = nullptr;
  uint32_t pane_pick_capacity_ = 0;
  bool panes_dirty_ = true;  // a moving light changed since the targets were computed
  bool panes_off_ = true;    // some pane's wanted factor differs from its target

  // GL objects.
  uint32_t* atlas_textures_ = nullptr;  // [atlas_count]
  // Per target (pack::PatchTarget: [0] the light map, [1] the indirect map): the sampled map, the
  // accumulator and their framebuffers.
  uint32_t light_map_ = 0, accumulator_ = 0;
  uint32_t light_map_fbo_ = 0, accumulator_fbo_ = 0;
  uint32_t indirect_map_ = 0, indirect_accumulator_ = 0;
  uint32_t indirect_map_fbo_ = 0, indirect_accumulator_fbo_ = 0;
  uint32_t vbo_ = 0, ibo_ = 0, vao_ = 0;
  // The patch programs: [0] level-0 patches of any of 8 atlases, [1] magnified patches
  // (pack_format.h, "Magnified patches"), [2] level-0 patches of one atlas; and present steps'.
  uint32_t patch_programs_[3] = {0, 0, 0}, present_program_ = 0;
  int32_t factor_location_[3] = {-1, -1, -1}, present_scale_location_ = -1;
  int32_t patch_size_location_[3] = {-1, -1, -1}, present_size_location_ = -1;  // u_target_size
  // The u_atlas of the programs that read one atlas ([1] magnified, [2] one atlas; [0] unused).
  int32_t atlas_location_[3] = {-1, -1, -1};
  // Per patch: end of the run of following patches whose atlases share a batch of 8 texture
  // units (one draw call per run; with <= 8 atlases every group is one run), and whether the
  // patches from it to that end read one atlas (drawn by the one-atlas program).
  uint32_t* run_end_ = nullptr;
  uint8_t* run_one_atlas_ = nullptr;
  // CPU path: the double accumulator and the half-float maps uploaded to the textures (the pack's
  // map set, pack_view.h).
  double* cpu_accumulator_ = nullptr;
  uint16_t* cpu_map_ = nullptr;
};

}  // namespace lightpatch
