#include "lightpatch/runtime.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "lightpatch/cpu_sink.h"
#include "lightpatch/group_rules.h"
#include "lightpatch/half_float.h"
#include "lightpatch/moving_lights.h"
#include "lightpatch/patch_decode.h"
#include "lightpatch/platform/gl.h"
#include "lightpatch_shaders.h"

namespace lightpatch {
namespace {

constexpr uint32_t kUnits = 8;  // atlas texture units per draw (GLES 3.0 guarantees 16)
constexpr uint32_t kAccumulatorUnit = kUnits;  // where present steps read the accumulator
// Runtime::patch_programs_: level-0 patches of any of kUnits atlases, magnified ones, level-0 ones
// of one atlas.
constexpr int kLevel0Program = 0, kMagnifiedProgram = 1, kOneAtlasProgram = 2;
// dest corner 2, atlas corner 2, params 4, unit 1, atlas rectangle 4 (magnified patches only),
// tint 3, second tint 3 (2-channel patches).
constexpr uint32_t kFloatsPerVertex = 19;
constexpr uint32_t kVertexBytes = kFloatsPerVertex * sizeof(float);
// The scale is chosen so that the authored state's bound stays below this (16x headroom below
// the largest half float).
constexpr float kAuthoredCeiling = kHalfMax / 16.0f;

#if defined(LIGHTPATCH_GL_CHECKS)
Status gl_status() {
  return glGetError() == GL_NO_ERROR ? Status::kOk : Status::kGlError;
}
#else
Status gl_status() {
  return Status::kOk;
}
#endif

bool has_extension(const char* name) {
  GLint count = 0;
  glGetIntegerv(GL_NUM_EXTENSIONS, &count);
  for (GLint i = 0; i < count; ++i) {
    const char* e = reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, GLuint(i)));
    if (e && !std::strcmp(e, name)) return true;
  }
  return false;
}

bool es_version_at_least(int want_major, int want_minor) {
  const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  int major = 0, minor = 0;
  if (!version || std::sscanf(version, "OpenGL ES %d.%d", &major, &minor) != 2) return false;
  return major > want_major || (major == want_major && minor >= want_minor);
}

// `define` (may be null): a line added after the source's first (its #version line).
GLuint compile(GLenum type, const char* source, const char* define, Error* error) {
  GLuint shader = glCreateShader(type);
  const char* newline = define ? std::strchr(source, '\n') : nullptr;
  if (newline) {
    const char* parts[3] = {source, define, newline + 1};
    const GLint lengths[3] = {GLint(newline + 1 - source), -1, -1};
    glShaderSource(shader, 3, parts, lengths);
  } else {
    glShaderSource(shader, 1, &source, nullptr);
  }
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[200] = {};
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    set_error(error, Status::kGlError, "shader compilation failed: %s", log);
    glDeleteShader(shader);
    return 0;
  }
  return shader;
}

GLuint link(const char* vertex, const char* fragment, Error* error,
            const char* fragment_define = nullptr) {
  GLuint vs = compile(GL_VERTEX_SHADER, vertex, nullptr, error);
  if (!vs) return 0;
  GLuint fs = compile(GL_FRAGMENT_SHADER, fragment, fragment_define, error);
  if (!fs) {
    glDeleteShader(vs);
    return 0;
  }
  GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint linked = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &linked);
  if (!linked) {
    char log[200] = {};
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    glDeleteProgram(program);
    set_error(error, Status::kGlError, "program link failed: %s", log);
    return 0;
  }
  return program;
}

// A texture of `format` with one level, nearest filtering (texelFetch and exact reads) unless
// `linear`, clamped at the edges.
GLuint make_texture(GLenum format, uint32_t w, uint32_t h, bool linear) {
  GLuint t = 0;
  glGenTextures(1, &t);
  glBindTexture(GL_TEXTURE_2D, t);
  const GLint filter = linear ? GL_LINEAR : GL_NEAREST;
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
  glTexStorage2D(GL_TEXTURE_2D, 1, format, GLsizei(w), GLsizei(h));
  glBindTexture(GL_TEXTURE_2D, 0);
  return t;
}

// A framebuffer on `texture`; 0 (and nothing left behind) when the driver cannot render to it.
GLuint make_framebuffer(GLuint texture) {
  GLuint fbo = 0;
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture, 0);
  const bool complete = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (!complete) glDeleteFramebuffers(1, &fbo);
  return complete ? fbo : 0;
}

}  // namespace

const char* path_name(RecomposePath path) {
  switch (path) {
    case RecomposePath::kGpuFloat:
      return "gpu-float";
    case RecomposePath::kGpuHalf:
      return "gpu-half";
    case RecomposePath::kCpu:
      return "cpu";
  }
  return "?";
}

// Executes the planner's steps with GL draws: patch draws into the target's accumulator (additive
// blending), present steps from it into the target's sampled map (no blending).
class GlSink final : public DrawSink {
 public:
  explicit GlSink(Runtime& r) : r_(r) {}
  void clear() override {
    glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    set_mode(kDraw, pack::kTargetLightMap);
    glClear(GL_COLOR_BUFFER_BIT);
    if (r_.pack_.has_indirect_map()) {
      set_mode(kDraw, pack::kTargetIndirectMap);
      glClear(GL_COLOR_BUFFER_BIT);
    }
  }
  void draw(uint32_t, uint32_t first, uint32_t count, const float factor[3]) override {
    set_mode(kDraw, r_.pack_.patch(first).target);
    // A half-float accumulator holds the presented scale already (runtime.h).
    const float s = r_.path_ == RecomposePath::kGpuHalf ? r_.inverse_scale_ : 1.0f;
    const float f[3] = {factor[0] * s, factor[1] * s, factor[2] * s};
    bool factor_set[3] = {false, false, false};
    const uint32_t end = first + count;
    while (first < end) {
      uint32_t run = r_.run_end_[first];
      if (run > end) run = end;
      // A run is all magnified or all level 0 (Runtime::open): one program for it, the
      // one-atlas program for level-0 patches that read one atlas.
      const int k = pack::patch_level(r_.pack_.patch(first).flags) > 0 ? kMagnifiedProgram
                    : r_.run_one_atlas_[first]                         ? kOneAtlasProgram
                                                                       : kLevel0Program;
      use_patch_program(k);
      if (!factor_set[k]) {
        glUniform3f(r_.factor_location_[k], f[0], f[1], f[2]);
        factor_set[k] = true;
      }
      const uint32_t atlas = r_.pack_.patch(first).atlas;
      const uint32_t batch = atlas / kUnits;
      if (int(batch) != batch_) {
        for (uint32_t u = 0; u < kUnits; ++u) {
          const uint32_t a = batch * kUnits + u;
          glActiveTexture(GL_TEXTURE0 + u);
          glBindTexture(GL_TEXTURE_2D, a < r_.pack_.atlas_count() ? r_.atlas_textures_[a] : 0);
        }
        batch_ = int(batch);
      }
      // The programs that sample one atlas (a run of magnified patches has one): its unit.
      if (k != kLevel0Program && int(atlas % kUnits) != unit_[k]) {
        unit_[k] = int(atlas % kUnits);
        glUniform1i(r_.atlas_location_[k], unit_[k]);
      }
      draw_quads(first, run - first);
      first = run;
    }
  }
  void present(uint32_t first, uint32_t count) override {
    set_mode(kPresent, r_.pack_.patch(first).target);
    draw_quads(first, count);
  }
  void present_all() override {
    // The full-target quads follow the patches' quads: the light map's, then the indirect map's.
    set_mode(kPresent, pack::kTargetLightMap);
    draw_quads(r_.pack_.patch_count(), 1);
    if (r_.pack_.has_indirect_map()) {
      set_mode(kPresent, pack::kTargetIndirectMap);
      draw_quads(r_.pack_.patch_count() + 1, 1);
    }
  }

 private:
  enum Mode { kNone, kDraw, kPresent };
  // Patch program k (Runtime::patch_programs_), its u_target_size the current target's.
  void use_patch_program(int k) {
    if (program_ != k) {
      glUseProgram(r_.patch_programs_[k]);
      program_ = k;
    }
    if (sized_[k] != target_) {
      glUniform2f(r_.patch_size_location_[k], float(r_.pack_.map_width(target_)),
                  float(r_.pack_.map_height(target_)));
      sized_[k] = target_;
    }
  }
  static void draw_quads(uint32_t first, uint32_t count) {
    glDrawElements(GL_TRIANGLES, GLsizei(count * 6), GL_UNSIGNED_INT,
                   reinterpret_cast<const void*>(uintptr_t(first) * 6 * sizeof(uint32_t)));
  }
  void set_mode(Mode m, uint8_t target) {
    if (m == mode_ && target == target_) return;
    const bool indirect = target == pack::kTargetIndirectMap;
    if (m == kDraw) {
      if (mode_ == kPresent) {
        glActiveTexture(GL_TEXTURE0 + kAccumulatorUnit);
        glBindTexture(GL_TEXTURE_2D, 0);
      }
      glBindFramebuffer(GL_FRAMEBUFFER,
                        indirect ? r_.indirect_accumulator_fbo_ : r_.accumulator_fbo_);
      glEnable(GL_BLEND);
    } else {
      glBindFramebuffer(GL_FRAMEBUFFER, indirect ? r_.indirect_map_fbo_ : r_.light_map_fbo_);
      glUseProgram(r_.present_program_);
      program_ = -1;
      glDisable(GL_BLEND);
      glActiveTexture(GL_TEXTURE0 + kAccumulatorUnit);
      glBindTexture(GL_TEXTURE_2D, indirect ? r_.indirect_accumulator_ : r_.accumulator_);
    }
    // Each target is drawn in its own texels: viewport and the program's target size (the patch
    // programs' when they are next used, use_patch_program).
    const uint32_t w = r_.pack_.map_width(target), h = r_.pack_.map_height(target);
    glViewport(0, 0, GLsizei(w), GLsizei(h));
    mode_ = m;
    target_ = target;
    if (m == kDraw) {
      use_patch_program(0);
    } else {
      glUniform2f(r_.present_size_location_, float(w), float(h));
    }
  }

  Runtime& r_;
  Mode mode_ = kNone;
  uint8_t target_ = pack::kTargetLightMap;
  int batch_ = -1;
  int program_ = -1;            // the patch program in use (use_patch_program), or -1
  int unit_[3] = {-1, -1, -1};  // the unit the one-atlas programs' u_atlas reads (-1: unset)
  uint8_t sized_[3] = {0xFF, 0xFF, 0xFF};  // the target each patch program's size is set for
};

Runtime::~Runtime() {
  close();
}

Status Runtime::open(const PackView& pack, const RuntimeLimits& limits, Error* error) {
  close();
  if (!pack.valid()) return set_error(error, Status::kInvalidArgument, "runtime: pack not open");
  pack_ = pack;
  limits_ = limits;
  Status s = planner_.init(pack_, limits.planner, error);
  if (s != Status::kOk) return s;
  // The planner's wanted state starts at the authored defaults, and so does this one.
  s = wanted_.init(pack_, error);
  if (s != Status::kOk) return s;
  // The presentation scale: the smallest power of two that brings the authored state's bound
  // below the ceiling.
  const float bound = planner_.wanted_map_bound();
  if (!(bound <= kMaxAuthoredMapBound)) {
    return set_error(error, Status::kOutOfRange,
                     "runtime: the pack's authored light map could exceed the float range "
                     "(bound %g)",
                     double(bound));
  }
  scale_ = 1.0f;
  while (bound / scale_ > kAuthoredCeiling) scale_ *= 2.0f;
  inverse_scale_ = 1.0f / scale_;
  planner_.set_value_limit(kHalfMax * scale_);

  run_end_ = static_cast<uint32_t*>(std::malloc(sizeof(uint32_t) * (pack.patch_count() + 1)));
  run_one_atlas_ = static_cast<uint8_t*>(std::malloc(pack.patch_count() + 1));
  atlas_textures_ = static_cast<uint32_t*>(std::calloc(pack.atlas_count() + 1, sizeof(uint32_t)));
  const uint32_t panes = pack.pane_count();
  pane_pick_capacity_ = std::min(limits.max_pane_changes, panes);
  pane_target_ = static_cast<float*>(std::calloc(size_t(panes) * 3 + 1, sizeof(float)));
  pane_error_ = static_cast<float*>(std::calloc(size_t(panes) + 1, sizeof(float)));
  pane_pick_ =
      static_cast<uint32_t*>(std::calloc(size_t(pane_pick_capacity_) + 1, sizeof(uint32_t)));
  panes_dirty_ = panes_off_ = panes > 0;
  stats_ = FrameStats();
  if (!run_end_ || !run_one_atlas_ || !atlas_textures_ || !pane_target_ || !pane_error_ ||
      !pane_pick_) {
    close();
    return set_error(error, Status::kOutOfMemory, "runtime: out of memory");
  }
  // Runs of patches within one group whose atlases share a batch of kUnits units.
  for (uint32_t p = pack.patch_count(); p-- > 0;) {
    const pack::PatchRecord& pr = pack.patch(p);
    const bool joins =
        p + 1 < pack.patch_count() && pack.patch(p + 1).group == pr.group &&
        pack.patch(p + 1).target == pr.target &&
        pack.patch(p + 1).atlas / kUnits == pr.atlas / kUnits &&
        (pack::patch_level(pack.patch(p + 1).flags) > 0) == (pack::patch_level(pr.flags) > 0) &&
        (pack::patch_level(pr.flags) == 0 || pack.patch(p + 1).atlas == pr.atlas);
    run_end_[p] = joins ? run_end_[p + 1] : p + 1;
    run_one_atlas_[p] = !joins || (run_one_atlas_[p + 1] && pack.patch(p + 1).atlas == pr.atlas);
  }
  open_ = true;
  s = create_gl(error);
  if (s != Status::kOk) {
    close();
    return s;
  }
  return Status::kOk;
}

Status Runtime::choose_path(Error* error) {
  const uint32_t w = pack_.lightmap_width(), h = pack_.lightmap_height();
  const bool float_renderable =
      es_version_at_least(3, 2) || has_extension("GL_EXT_color_buffer_float");
  const bool float_blend = has_extension("GL_EXT_float_blend");
  const bool half_renderable = float_renderable || has_extension("GL_EXT_color_buffer_half_float");
  const bool indirect = pack_.has_indirect_map();
  const uint32_t iw = pack_.indirect_width(), ih = pack_.indirect_height();
  path_ = RecomposePath::kCpu;
  if (limits_.force_cpu_fallback) return Status::kOk;
  light_map_fbo_ = make_framebuffer(light_map_);
  if (indirect && light_map_fbo_) {
    indirect_map_fbo_ = make_framebuffer(indirect_map_);
    if (!indirect_map_fbo_) {
      glDeleteFramebuffers(1, &light_map_fbo_);
      light_map_fbo_ = 0;
    }
  }
  if (!light_map_fbo_) return Status::kOk;
  struct Candidate {
    bool usable;
    GLenum format;
    RecomposePath path;
  };
  const Candidate candidates[] = {
      {float_renderable && float_blend && !limits_.force_half_accumulator, GL_RGBA32F,
       RecomposePath::kGpuFloat},
      {half_renderable, GL_RGBA16F, RecomposePath::kGpuHalf}};
  for (const Candidate& c : candidates) {
    if (!c.usable) continue;
    const uint64_t bytes_per_texel = c.format == GL_RGBA32F ? 16 : 8;
    accumulator_ = make_texture(c.format, w, h, false);
    accumulator_fbo_ = make_framebuffer(accumulator_);
    if (indirect && accumulator_fbo_) {
      indirect_accumulator_ = make_texture(c.format, iw, ih, false);
      indirect_accumulator_fbo_ = make_framebuffer(indirect_accumulator_);
    }
    if (accumulator_fbo_ && (!indirect || indirect_accumulator_fbo_)) {
      path_ = c.path;
      memory_.accumulator = uint64_t(w) * h * bytes_per_texel;
      memory_.indirect_accumulator = uint64_t(iw) * ih * bytes_per_texel;
      return Status::kOk;
    }
    const GLuint textures[2] = {accumulator_, indirect_accumulator_};
    glDeleteTextures(2, textures);
    const GLuint fbos[2] = {accumulator_fbo_, indirect_accumulator_fbo_};
    glDeleteFramebuffers(2, fbos);
    accumulator_ = indirect_accumulator_ = 0;
    accumulator_fbo_ = indirect_accumulator_fbo_ = 0;
  }
  const GLuint fbos[2] = {light_map_fbo_, indirect_map_fbo_};
  glDeleteFramebuffers(2, fbos);
  light_map_fbo_ = indirect_map_fbo_ = 0;
  return glGetError() == GL_NO_ERROR
             ? Status::kOk
             : set_error(error, Status::kGlError, "runtime: GL error choosing the render target");
}

Status Runtime::create_gl(Error* error) {
  const uint32_t w = pack_.lightmap_width(), h = pack_.lightmap_height();
  memory_ = RuntimeMemory();
  // Errors the context held before are not ours (glGetError returns one flag per call).
  for (int i = 0; i < 16 && glGetError() != GL_NO_ERROR; ++i) {
  }
  // The map the game samples (linear filtering), then an accumulator the driver can blend into.
  light_map_ = make_texture(GL_RGBA16F, w, h, true);
  memory_.light_map = uint64_t(w) * h * 8;
  if (pack_.has_indirect_map()) {  // sampled bilinearly, clamped at its edges (pack_format.h)
    indirect_map_ = make_texture(GL_RGBA16F, pack_.indirect_width(), pack_.indirect_height(), true);
    memory_.indirect_map = uint64_t(pack_.indirect_width()) * pack_.indirect_height() * 8;
  }
  if (Status s = choose_path(error); s != Status::kOk) return s;

  if (path_ == RecomposePath::kCpu) {
    const size_t texels = size_t(pack_.map_texels());
    if (!cpu_accumulator_) {
      cpu_accumulator_ = static_cast<double*>(std::calloc(texels * 3, sizeof(double)));
      cpu_map_ = static_cast<uint16_t*>(std::calloc(texels * 4, sizeof(uint16_t)));
    }
    if (!cpu_accumulator_ || !cpu_map_) {
      return set_error(error, Status::kOutOfMemory, "runtime: out of memory");
    }
    memory_.cpu_fallback = texels * (3 * sizeof(double) + 4 * sizeof(uint16_t));
    precision_ = TargetPrecision{1.1102230e-16f, false};  // double
    planner_.set_precision(precision_);
    return glGetError() == GL_NO_ERROR
               ? Status::kOk
               : set_error(error, Status::kGlError, "runtime: GL error creating textures");
  }
  // Atlases, straight from the mapping (rows top to bottom = texture rows 0..h-1).
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glGenTextures(GLsizei(pack_.atlas_count()), atlas_textures_);
  for (uint32_t a = 0; a < pack_.atlas_count(); ++a) {
    const pack::AtlasRecord& ar = pack_.atlas(a);
    glBindTexture(GL_TEXTURE_2D, atlas_textures_[a]);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, GLsizei(ar.width), GLsizei(ar.height), 0, GL_RGBA,
                 GL_UNSIGNED_BYTE, pack_.atlas_pixels(a));
    memory_.atlases += uint64_t(ar.width) * ar.height * 4;
  }
  glBindTexture(GL_TEXTURE_2D, 0);
  if (Status s = create_programs(error); s != Status::kOk) return s;
  if (Status s = create_buffers(error); s != Status::kOk) return s;
  if (Status s = probe_rounding(error); s != Status::kOk) return s;
  planner_.set_precision(precision_);
  if (glGetError() != GL_NO_ERROR) {
    return set_error(error, Status::kGlError, "runtime: GL error while creating resources");
  }
  return Status::kOk;
}

Status Runtime::create_programs(Error* error) {
  const uint32_t w = pack_.lightmap_width(), h = pack_.lightmap_height();
  // The level-0 shader twice: branching on the patch's unit, and reading one atlas.
  const char* fragments[3] = {shaders::patch_frag, shaders::patch_magnified_frag,
                              shaders::patch_frag};
  const char* defines[3] = {nullptr, nullptr, "#define LIGHTPATCH_ONE_ATLAS 1\n"};
  for (int k = 0; k < 3; ++k) {
    patch_programs_[k] = link(shaders::patch_vert, fragments[k], error, defines[k]);
    if (!patch_programs_[k]) return Status::kGlError;
  }
  present_program_ = link(shaders::present_vert, shaders::present_frag, error);
  if (!present_program_) return Status::kGlError;
  present_size_location_ = glGetUniformLocation(present_program_, "u_target_size");
  for (int k = 0; k < 3; ++k) {
    const uint32_t program = patch_programs_[k];
    factor_location_[k] = glGetUniformLocation(program, "u_factor");
    patch_size_location_[k] = glGetUniformLocation(program, "u_target_size");
    glUseProgram(program);
    for (uint32_t u = 0; u < kUnits && k == kLevel0Program; ++u) {
      char name[16];
      std::snprintf(name, sizeof name, "u_atlas[%u]", u);
      glUniform1i(glGetUniformLocation(program, name), GLint(u));
    }
    if (k != kLevel0Program) {
      atlas_location_[k] = glGetUniformLocation(program, "u_atlas");
      glUniform1i(atlas_location_[k], 0);
    }
    glUniform2f(patch_size_location_[k], float(w), float(h));
  }
  glUseProgram(present_program_);
  glUniform1i(glGetUniformLocation(present_program_, "u_accumulator"), GLint(kAccumulatorUnit));
  glUniform2f(present_size_location_, float(w), float(h));
  // The float accumulator holds irradiance; the half one holds it scaled already.
  glUniform1f(glGetUniformLocation(present_program_, "u_scale"),
              path_ == RecomposePath::kGpuFloat ? inverse_scale_ : 1.0f);
  glUniform1i(glGetUniformLocation(present_program_, "u_signed"), pack_.presents_signed() ? 1 : 0);
  glUseProgram(0);
  return Status::kOk;
}

Status Runtime::create_buffers(Error* error) {
  // Vertex and index buffers: 4 vertices and 6 indices per patch, pack order, plus one
  // full-target quad at the end (the whole-map present and the fill-rate floor) and, with an
  // indirect map, its full-target quad.
  const uint32_t quads = pack_.patch_count() + (pack_.has_indirect_map() ? 2 : 1);
  const size_t vbytes = size_t(quads) * 4 * kVertexBytes;
  const size_t ibytes = size_t(quads) * 6 * sizeof(uint32_t);
  float* vertices = static_cast<float*>(std::malloc(vbytes));
  uint32_t* indices = static_cast<uint32_t*>(std::malloc(ibytes));
  if (!vertices || !indices) {
    std::free(vertices);
    std::free(indices);
    return set_error(error, Status::kOutOfMemory, "runtime: out of memory");
  }
  for (uint32_t q = 0; q < quads; ++q) {
    float dx0, dy0, dx1, dy1, ax0, ay0, ax1, ay1, params[4], unit, rect[4], tint[6];
    if (q < pack_.patch_count()) {
      const pack::PatchRecord& p = pack_.patch(q);
      // The destination and the atlas rectangle are given separately: a patch drawn magnified
      // from a smaller atlas rectangle needs only other atlas corners here.
      dx0 = p.dest_x, dy0 = p.dest_y, dx1 = dx0 + p.width, dy1 = dy0 + p.height;
      // A level-L patch's atlas corners span width / 2^L (exact in float), so that v_atlas at
      // destination texel centre x is atlas_x + (x + 0.5) / 2^L (pack_format.h, "Magnified
      // patches"); the shader clamps its taps to the atlas rectangle `rect` (inclusive texels).
      const uint32_t level = pack::patch_level(p.flags);
      const float inv = 1.0f / float(1u << level);
      ax0 = p.atlas_x, ay0 = p.atlas_y;
      ax1 = ax0 + float(p.width) * inv, ay1 = ay0 + float(p.height) * inv;
      rect[0] = ax0, rect[1] = ay0;
      rect[2] = float(p.atlas_x + pack::patch_atlas_side(p.width, level) - 1);
      rect[3] = float(p.atlas_y + pack::patch_atlas_side(p.height, level) - 1);
      params[0] = p.scale * patch_sign(pack_.group(p.group).kind, p.flags);
      params[1] = p.channel;
      const int destination = pack::patch_destination(p.flags);
      params[2] = destination >= 0 ? 4.0f + float(destination) : float(p.channel_count);
      params[3] = p.encoding == pack::kEncodingSquare ? 1.0f : 0.0f;
      unit = float(p.atlas % kUnits);
      for (int c = 0; c < 3; ++c) {
        tint[c] = patch_tint<float>(p, c);
        tint[3 + c] = patch_tint_b<float>(p, c);
      }
    } else {  // a full-target quad, sampling atlas 0 stretched over it (fill-rate floor)
      const pack::AtlasRecord& a0 = pack_.atlas(0);
      const uint8_t target =
          q == pack_.patch_count() ? pack::kTargetLightMap : pack::kTargetIndirectMap;
      dx0 = dy0 = 0.0f, dx1 = float(pack_.map_width(target)), dy1 = float(pack_.map_height(target));
      ax0 = ay0 = 0.0f, ax1 = float(a0.width), ay1 = float(a0.height);
      params[0] = 1.0f, params[1] = 0.0f, params[2] = 3.0f, params[3] = 0.0f;
      unit = 0.0f;
      rect[0] = rect[1] = 0.0f, rect[2] = ax1 - 1.0f, rect[3] = ay1 - 1.0f;
      tint[0] = tint[1] = tint[2] = 1.0f;
      tint[3] = tint[4] = tint[5] = 0.0f;
    }
    const float corners[4][4] = {
        {dx0, dy0, ax0, ay0}, {dx1, dy0, ax1, ay0}, {dx0, dy1, ax0, ay1}, {dx1, dy1, ax1, ay1}};
    for (int c = 0; c < 4; ++c) {
      float* v = vertices + (size_t(q) * 4 + c) * kFloatsPerVertex;
      std::memcpy(v, corners[c], sizeof corners[c]);
      std::memcpy(v + 4, params, sizeof params);
      v[8] = unit;
      std::memcpy(v + 9, rect, sizeof rect);
      std::memcpy(v + 13, tint, sizeof tint);
    }
    const uint32_t b = q * 4;
    const uint32_t quad[6] = {b, b + 1, b + 2, b + 2, b + 1, b + 3};
    std::memcpy(indices + size_t(q) * 6, quad, sizeof quad);
  }
  glGenVertexArrays(1, &vao_);
  glBindVertexArray(vao_);
  glGenBuffers(1, &vbo_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(vbytes), vertices, GL_STATIC_DRAW);
  glGenBuffers(1, &ibo_);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo_);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(ibytes), indices, GL_STATIC_DRAW);
  std::free(vertices);
  std::free(indices);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, kVertexBytes, nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, kVertexBytes,
                        reinterpret_cast<const void*>(2 * sizeof(float)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, kVertexBytes,
                        reinterpret_cast<const void*>(4 * sizeof(float)));
  glEnableVertexAttribArray(3);
  glVertexAttribPointer(3, 1, GL_FLOAT, GL_FALSE, kVertexBytes,
                        reinterpret_cast<const void*>(8 * sizeof(float)));
  glEnableVertexAttribArray(4);
  glVertexAttribPointer(4, 4, GL_FLOAT, GL_FALSE, kVertexBytes,
                        reinterpret_cast<const void*>(9 * sizeof(float)));
  glEnableVertexAttribArray(5);
  glVertexAttribPointer(5, 3, GL_FLOAT, GL_FALSE, kVertexBytes,
                        reinterpret_cast<const void*>(13 * sizeof(float)));
  glEnableVertexAttribArray(6);
  glVertexAttribPointer(6, 3, GL_FLOAT, GL_FALSE, kVertexBytes,
                        reinterpret_cast<const void*>(16 * sizeof(float)));
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  memory_.vertex_buffer = vbytes;
  memory_.index_buffer = ibytes;
  return Status::kOk;
}

// Blends 0.75 and 0.25 ulp onto 1 in one texel of the accumulator and reads it back: round to
// nearest gives 1 + ulp and 1, truncation 1 and 1, rounding up 1 + ulp twice. Anything but round
// to nearest counts a full ulp per write.
Status Runtime::probe_rounding(Error* error) {
  const bool half = path_ == RecomposePath::kGpuHalf;
  const float ulp = half ? 1.0f / 1024.0f : 1.0f / 8388608.0f;
  GLuint program = link(shaders::present_vert, shaders::probe_frag, error);
  if (!program) return Status::kGlError;
  glBindFramebuffer(GL_FRAMEBUFFER, accumulator_fbo_);
  glViewport(0, 0, GLsizei(pack_.lightmap_width()), GLsizei(pack_.lightmap_height()));
  glEnable(GL_SCISSOR_TEST);
  glScissor(0, 0, 1, 1);
  glClearColor(1.0f, 1.0f, 1.0f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT);
  glUseProgram(program);
  glUniform2f(glGetUniformLocation(program, "u_target_size"), float(pack_.lightmap_width()),
              float(pack_.lightmap_height()));
  glUniform4f(glGetUniformLocation(program, "u_value"), 0.75f * ulp, 0.25f * ulp, 0.0f, 0.0f);
  glEnable(GL_BLEND);
  glBlendEquation(GL_FUNC_ADD);
  glBlendFunc(GL_ONE, GL_ONE);
  glBindVertexArray(vao_);
  glDrawElements(GL_TRIANGLES, 6, GL_UNSIGNED_INT,
                 reinterpret_cast<const void*>(uintptr_t(pack_.patch_count()) * 6 * 4));
  glBindVertexArray(0);
  glDisable(GL_BLEND);
  glDisable(GL_SCISSOR_TEST);
  float texel[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glReadPixels(0, 0, 1, 1, GL_RGBA, GL_FLOAT, texel);
  glUseProgram(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDeleteProgram(program);
  if (glGetError() != GL_NO_ERROR) {
    return set_error(error, Status::kGlError, "runtime: GL error probing the %s accumulator",
                     path_name(path_));
  }
  const bool nearest = texel[0] == 1.0f + ulp && texel[1] == 1.0f;
  precision_.truncates = !nearest;
  precision_.unit_roundoff = nearest ? 0.5f * ulp : ulp;
  return Status::kOk;
}

void Runtime::delete_gl() {
  if (atlas_textures_) glDeleteTextures(GLsizei(pack_.atlas_count()), atlas_textures_);
  const GLuint textures[4] = {light_map_, accumulator_, indirect_map_, indirect_accumulator_};
  glDeleteTextures(4, textures);
  const GLuint fbos[4] = {light_map_fbo_, accumulator_fbo_, indirect_map_fbo_,
                          indirect_accumulator_fbo_};
  glDeleteFramebuffers(4, fbos);
  if (vbo_) glDeleteBuffers(1, &vbo_);
  if (ibo_) glDeleteBuffers(1, &ibo_);
  if (vao_) glDeleteVertexArrays(1, &vao_);
  for (uint32_t program : patch_programs_)
    if (program) glDeleteProgram(program);
  if (present_program_) glDeleteProgram(present_program_);
  forget_gl();
}

void Runtime::forget_gl() {
  if (atlas_textures_) std::memset(atlas_textures_, 0, sizeof(uint32_t) * pack_.atlas_count());
  light_map_ = accumulator_ = indirect_map_ = indirect_accumulator_ = 0;
  light_map_fbo_ = accumulator_fbo_ = indirect_map_fbo_ = indirect_accumulator_fbo_ = 0;
  vbo_ = ibo_ = vao_ = present_program_ = 0;
  for (uint32_t& program : patch_programs_) program = 0;
}

void Runtime::close() {
  if (open_) delete_gl();
  std::free(atlas_textures_);
  std::free(run_end_);
  std::free(run_one_atlas_);
  std::free(cpu_accumulator_);
  std::free(cpu_map_);
  std::free(pane_target_);
  std::free(pane_error_);
  std::free(pane_pick_);
  pane_target_ = pane_error_ = nullptr;
  pane_pick_ = nullptr;
  pane_pick_capacity_ = 0;
  atlas_textures_ = nullptr;
  run_end_ = nullptr;
  run_one_atlas_ = nullptr;
  cpu_accumulator_ = nullptr;
  cpu_map_ = nullptr;
  open_ = false;
}

Status Runtime::restore(Error* error) {
  if (!open_) return set_error(error, Status::kInvalidArgument, "runtime: not open");
  forget_gl();
  planner_.invalidate();
  return create_gl(error);
}

int32_t Runtime::find_light(const char* name) const {
  return pack_.find_light(name, uint32_t(std::strlen(name)));
}
int32_t Runtime::find_object(const char* name) const {
  return pack_.find_object(name, uint32_t(std::strlen(name)));
}

LightState Runtime::light(uint32_t i) const {
  LightState s{};
  s.on = planner_.light_on(i);
  planner_.light_color(i, s.color);
  s.intensity = planner_.light_intensity(i);
  return s;
}

Status Runtime::set_light(uint32_t i, const LightState& state) {
  assert(i < light_count() && "set_light: light index out of range");
  if (i >= light_count()) return Status::kInvalidArgument;
  if (pack_.light_is_pane(i)) return Status::kInvalidArgument;  // follows the moving lights
  const Status s = planner_.set_light(i, state.on, state.color, state.intensity);
  if (s == Status::kOk) {
    wanted_.set_light(i, state);
    if (pack_.light_moves(i)) panes_dirty_ = true;
  }
  return s;
}

Status Runtime::set_light_pose(uint32_t i, const LightPose& pose) {
  assert(i < light_count() && "set_light_pose: light index out of range");
  if (i >= light_count()) return Status::kInvalidArgument;
  const LightPose before = wanted_.light_pose(i);
  const Status s = wanted_.set_light_pose(i, pose);
  // The same pose again is no change: the panes settle (tolerance 0) while the light stands.
  if (s == Status::kOk && std::memcmp(&before, &wanted_.light_pose(i), sizeof before) != 0)
    panes_dirty_ = true;
  return s;
}

LightPose Runtime::light_pose(uint32_t i) const {
  return wanted_.light_pose(i);
}

void Runtime::update_panes(FrameStats* stats) {
  const uint32_t np = pack_.pane_count();
  if (np == 0) panes_dirty_ = panes_off_ = false;  // moving lights without panes: nothing to do
  if (!panes_dirty_ && !panes_off_) return;
  const bool moved = panes_dirty_;
  if (moved) {
    pane_factors(pack_, wanted_, pane_target_);
    panes_dirty_ = false;
  }
  // Errors, and the light the panes bring at most (the tolerance's scale).
  float total = 0.0f;
  for (uint32_t k = 0; k < np; ++k) {
    const uint32_t light = pack_.pane(k).light;
    const float bound = planner_.light_bound(light);
    float wanted[3];
    planner_.light_color(light, wanted);  // a pane is on with intensity 1: its factor
    const float* target = pane_target_ + 3 * k;
    float off = 0.0f, peak = 0.0f;
    for (int c = 0; c < 3; ++c) {
      off = std::fmax(off, std::fabs(target[c] - wanted[c]));
      peak = std::fmax(peak, target[c]);
    }
    pane_error_[k] = off * bound;
    total += peak * bound;
  }
  const float threshold = moved ? limits_.pane_tolerance * total : 0.0f;
  // The largest errors above the threshold: a heap whose top is the least of those chosen.
  const float* error = pane_error_;
  auto better = [error](uint32_t a, uint32_t b) {
    return error[a] > error[b] || (error[a] == error[b] && a < b);
  };
  uint32_t chosen = 0, over = 0, off_target = 0;
  for (uint32_t k = 0; k < np; ++k) {
    if (pane_error_[k] > 0.0f) ++off_target;
    if (!(pane_error_[k] > threshold)) continue;
    ++over;
    if (pane_pick_capacity_ == 0) continue;
    if (chosen < pane_pick_capacity_) {
      pane_pick_[chosen++] = k;
      std::push_heap(pane_pick_, pane_pick_ + chosen, better);
    } else if (better(k, pane_pick_[0])) {
      std::pop_heap(pane_pick_, pane_pick_ + chosen, better);
      pane_pick_[chosen - 1] = k;
      std::push_heap(pane_pick_, pane_pick_ + chosen, better);
    }
  }
  uint32_t pushed = 0, refused = 0;
  for (uint32_t i = 0; i < chosen; ++i) {
    const uint32_t k = pane_pick_[i];
    const Status s = planner_.set_light(pack_.pane(k).light, true, pane_target_ + 3 * k, 1.0f);
    if (s == Status::kOk)
      ++pushed;
    else
      ++refused;  // kOutOfRange: the pane keeps its old factor, tried again next frame
  }
  panes_off_ = off_target > pushed;
  stats->pane_changes = pushed;
  stats->pane_refused = refused;
  // Off target beyond the tolerance in force after this frame: while the lights move, those
  // over the threshold not pushed; once they stand, every pane not yet exact.
  stats->pane_pending = moved ? over - pushed : off_target - pushed;
}
Status Runtime::set_light_on(uint32_t i, bool on) {
  assert(i < light_count() && "set_light_on: light index out of range");
  if (i >= light_count()) return Status::kInvalidArgument;
  LightState s = light(i);
  s.on = on;
  return set_light(i, s);
}
Status Runtime::set_light_color(uint32_t i, const float rgb[3]) {
  assert(i < light_count() && "set_light_color: light index out of range");
  if (i >= light_count()) return Status::kInvalidArgument;
  LightState s = light(i);
  std::memcpy(s.color, rgb, sizeof s.color);
  return set_light(i, s);
}
Status Runtime::set_light_intensity(uint32_t i, float intensity) {
  assert(i < light_count() && "set_light_intensity: light index out of range");
  if (i >= light_count()) return Status::kInvalidArgument;
  LightState s = light(i);
  s.intensity = intensity;
  return set_light(i, s);
}
Status Runtime::set_object_visible(uint32_t i, bool visible) {
  const Status s = planner_.set_object_visible(i, visible);
  if (s == Status::kOk) wanted_.set_object_visible(i, visible);
  return s;
}

void Runtime::set_draw_state() const {
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_STENCIL_TEST);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_CULL_FACE);
  glBlendEquation(GL_FUNC_ADD);
  glBlendFunc(GL_ONE, GL_ONE);
  glViewport(0, 0, GLsizei(width()), GLsizei(height()));
  glBindVertexArray(vao_);
}

void Runtime::reset_draw_state() const {
  glViewport(0, 0, GLsizei(width()), GLsizei(height()));  // an indirect target may have set it
  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_BLEND);
  glDisable(GL_SCISSOR_TEST);
  for (uint32_t u = kAccumulatorUnit + 1; u-- > 0;) {
    glActiveTexture(GL_TEXTURE0 + u);
    glBindTexture(GL_TEXTURE_2D, 0);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

Status Runtime::update(uint64_t budget_texels) {
  assert(open_ && "update: the runtime is not open");
  if (!open_) return Status::kInvalidArgument;
  FrameStats panes;
  update_panes(&panes);
  const Status s = update_planner(budget_texels);
  stats_ = planner_.stats();
  stats_.pane_changes = panes.pane_changes;
  stats_.pane_pending = panes.pane_pending;
  stats_.pane_refused = panes.pane_refused;
  return s;
}

Status Runtime::update_planner(uint64_t budget_texels) {
  if (path_ == RecomposePath::kCpu) {
    CpuSink sink;
    sink.bind(&pack_, cpu_accumulator_, nullptr, cpu_map_, inverse_scale_);
    planner_.update(budget_texels, sink);
    for (uint8_t t = pack::kTargetLightMap; t <= pack::kTargetIndirectMap; ++t) {
      const uint32_t begin = sink.dirty_begin(t), end = sink.dirty_end(t);
      if (end <= begin) continue;  // upload the rows that changed
      const uint32_t w = pack_.map_width(t);
      glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
      glBindTexture(GL_TEXTURE_2D, t == pack::kTargetLightMap ? light_map_ : indirect_map_);
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, GLint(begin), GLsizei(w), GLsizei(end - begin), GL_RGBA,
                      GL_HALF_FLOAT,
                      cpu_map_ + (size_t(pack_.map_offset(t)) + size_t(begin) * w) * 4);
      glBindTexture(GL_TEXTURE_2D, 0);
    }
    return gl_status();
  }
  set_draw_state();
  GlSink sink(*this);
  planner_.update(budget_texels, sink);
  reset_draw_state();
  return gl_status();
}

Status Runtime::read_light_map(float* out, Error* error) const {
  assert(out != nullptr && "read_light_map: null output");
  return read_map(pack::kTargetLightMap, out, error);
}

Status Runtime::read_indirect_map(float* out, Error* error) const {
  assert(out != nullptr && "read_indirect_map: null output");
  if (open_ && !pack_.has_indirect_map()) {
    return set_error(error, Status::kInvalidArgument, "runtime: the pack has no indirect map");
  }
  return read_map(pack::kTargetIndirectMap, out, error);
}

Status Runtime::read_map(uint8_t target, float* out, Error* error) const {
  if (!open_) return set_error(error, Status::kInvalidArgument, "runtime: not open");
  const uint32_t w = pack_.map_width(target), h = pack_.map_height(target);
  const size_t n = size_t(w) * h * 4;
  if (path_ == RecomposePath::kCpu) {
    const uint16_t* map = cpu_map_ + size_t(pack_.map_offset(target)) * 4;
    for (size_t i = 0; i < n; ++i) {
      out[i] = (i & 3) == 3 ? 1.0f : half_to_float(map[i]) * scale_;
    }
    return Status::kOk;
  }
  const bool indirect = target == pack::kTargetIndirectMap;
  glBindFramebuffer(GL_FRAMEBUFFER, indirect ? indirect_map_fbo_ : light_map_fbo_);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glReadPixels(0, 0, GLsizei(w), GLsizei(h), GL_RGBA, GL_FLOAT, out);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (glGetError() != GL_NO_ERROR) {
    return set_error(error, Status::kGlError, "runtime: glReadPixels of the %s failed",
                     indirect ? "indirect map" : "light map");
  }
  for (size_t i = 0; i < n; ++i) {
    if ((i & 3) != 3) out[i] *= scale_;
  }
  return Status::kOk;
}

Status Runtime::draw_fill_floor(uint64_t texels, Error* error) {
  if (!open_ || !gpu_path() || !idle()) {
    return set_error(error, Status::kInvalidArgument, "fill floor: needs an idle GPU-path runtime");
  }
  const uint64_t full = uint64_t(width()) * height();
  set_draw_state();
  glEnable(GL_BLEND);
  // The cheapest patch program: one fetch a texel.
  glUseProgram(patch_programs_[kOneAtlasProgram]);
  glUniform2f(patch_size_location_[kOneAtlasProgram], float(width()), float(height()));
  glUniform1i(atlas_location_[kOneAtlasProgram], 0);
  glBindFramebuffer(GL_FRAMEBUFFER, accumulator_fbo_);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, atlas_textures_[0]);
  glUniform3f(factor_location_[kOneAtlasProgram], 0.0f, 0.0f, 0.0f);
  const void* quad =
      reinterpret_cast<const void*>(uintptr_t(pack_.patch_count()) * 6 * sizeof(uint32_t));
  for (uint64_t done = 0; done < texels; done += full) {
    if (texels - done < full) {  // the last partial pass: whole rows
      const uint64_t rows = (texels - done + width() - 1) / width();
      glEnable(GL_SCISSOR_TEST);
      glScissor(0, 0, GLsizei(width()), GLsizei(rows));
    }
    glDrawElements(GL_TRIANGLES, 6, GL_UNSIGNED_INT, quad);
  }
  reset_draw_state();
  planner_.request_rebuild();  // the accumulator no longer holds the presented state
  return glGetError() == GL_NO_ERROR ? Status::kOk
                                     : set_error(error, Status::kGlError, "fill floor: GL error");
}

}  // namespace lightpatch
