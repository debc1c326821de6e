// lightpatch runtime: the library a game links. It maps nothing itself: the game maps the pack
// (platform::FileMapping), validates it (PackView::open) and opens a Runtime on it with a GLES 3.0
// context current. Frame by frame the game sets lights and objects, calls update(budget) once, and
// samples light_map_texture().
//
// Fixed memory: open() allocates everything (GL objects included): the atlases (uploaded straight
// from the mapping), two RGBA16F light-map textures (the one the game samples and the one
// intermediate a rebuild is drawn into; they swap when a rebuild completes), one static vertex
// buffer and index buffer with every patch's quad in pack order (a group's patches, e.g. a light's
// contribution, are one contiguous index range: one draw call), one program, one VAO, two FBOs.
// update() makes no heap allocation and creates no GL object.
//
// Recomposition, budgets, incremental changes and drift control: see planner.h.
//
// Image orientation: texel row 0 of every texture (GL's t = 0 end, the first row uploaded or read
// back) is the image's top row, glTF v = 0. Sample the light map at (u, v) = the glTF light-map UV
// unchanged; glReadPixels of the map returns the top row first.
//
// Devices without a renderable half-float target (EXT_color_buffer_half_float / ES 3.2): the same
// plan runs on the CPU into two float buffers and the light map is uploaded (glTexSubImage2D)
// after each frame that changed it.
//
// GL state: update() and restore() bind their own framebuffer, program, VAO, textures (units 0..7)
// and blending; they return with framebuffer 0, program 0, VAO 0, blending disabled, texture
// units 0..7 unbound, active unit 0, and the viewport set to the light map's size. Depth, stencil,
// scissor and face culling are disabled while drawing and left disabled.
#pragma once

#include <cstdint>

#include "lightpatch/pack_view.h"
#include "lightpatch/planner.h"
#include "lightpatch/scene_state.h"
#include "lightpatch/status.h"

namespace lightpatch {

struct RuntimeLimits {
  PlannerLimits planner;
  // Use the CPU path even where a half-float render target exists (tests, broken drivers).
  bool force_cpu_fallback = false;
};

// GPU memory owned by the runtime, in bytes.
struct RuntimeMemory {
  uint64_t atlases = 0;
  uint64_t light_map = 0;     // the texture the game samples
  uint64_t intermediate = 0;  // the rebuild target
  uint64_t vertex_buffer = 0;
  uint64_t index_buffer = 0;
  uint64_t cpu_fallback = 0;  // host memory of the CPU path (0 on the GPU path)
};

class Runtime {
 public:
  Runtime() = default;
  ~Runtime();  // close()
  Runtime(const Runtime&) = delete;
  Runtime& operator=(const Runtime&) = delete;

  // Creates every resource in the current context. `pack` (and the memory it views) must outlive
  // the runtime. The wanted state starts at the pack's authored defaults; the first update()s
  // build it (ready() turns true when the first complete map is presented).
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

  // Wanted state; visible after later update()s (see stats() for latency). kInvalidArgument for
  // an index out of range or a value that is not finite and >= 0.
  Status set_light(uint32_t light, const LightState& state);
  Status set_light_on(uint32_t light, bool on);
  Status set_light_color(uint32_t light, const float rgb[3]);
  Status set_light_intensity(uint32_t light, float intensity);
  Status set_object_visible(uint32_t object, bool visible);
  LightState light(uint32_t light) const;
  bool object_visible(uint32_t object) const { return planner_.object_visible(object); }

  // Once per frame: at most `budget_texels` texels written (planner.h's budget rule).
  // kGlError if the driver reported an error.
  Status update(uint64_t budget_texels);

  // Starts a full rebuild of the wanted state now (spread over the next update()s; a no-op while
  // one runs). The runtime also rebuilds on its own when its drift bound is reached.
  void request_rebuild() { planner_.request_rebuild(); }

  // The texture to sample (RGBA16F, linear irradiance; alpha 1). Its name changes when a rebuild
  // is presented: read it every frame. Holds a complete map once ready().
  uint32_t light_map_texture() const;
  bool ready() const { return planner_.map_ready(); }
  bool idle() const { return planner_.idle(); }
  bool gpu_path() const { return !cpu_; }
  const FrameStats& stats() const { return planner_.stats(); }
  const Planner& planner() const { return planner_; }
  RuntimeMemory memory() const { return memory_; }
  uint32_t width() const { return pack_.lightmap_width(); }
  uint32_t height() const { return pack_.lightmap_height(); }

  // Reads the light map back (RGBA float, width*height*4, row 0 = top). For tools and tests: it
  // stalls the pipeline. `out` must hold width()*height()*4 floats.
  Status read_light_map(float* out, Error* error) const;

  // Benchmark aid (the fill-rate floor): draws `texels` texels of full-target quads with the patch
  // program and additive blending into the intermediate, the same per-texel work as a rebuild with
  // the fewest possible draws. Only while idle() (the intermediate is free then); GPU path only.
  Status draw_fill_floor(uint64_t texels, Error* error);

 private:
  friend class GlSink;
  friend class CpuSink;
  Status create_gl(Error* error);
  void delete_gl();
  void forget_gl();

  PackView pack_;
  RuntimeLimits limits_;
  Planner planner_;
  bool open_ = false;
  bool cpu_ = false;
  RuntimeMemory memory_;

  // GL objects.
  uint32_t* atlas_textures_ = nullptr;  // [atlas_count]
  uint32_t map_textures_[2] = {0, 0};
  uint32_t framebuffers_[2] = {0, 0};
  uint32_t shown_ = 0;  // index of the sampled map in map_textures_
  uint32_t vbo_ = 0, ibo_ = 0, vao_ = 0, program_ = 0;
  int32_t factor_location_ = -1, target_size_location_ = -1;
  // Per patch: end of the run of following patches whose atlases share a batch of 8 texture
  // units (one draw call per run; with <= 8 atlases every group is one run).
  uint32_t* run_end_ = nullptr;
  // CPU path: two float RGBA maps.
  float* cpu_maps_ = nullptr;
  bool cpu_dirty_ = false;
};

}  // namespace lightpatch
