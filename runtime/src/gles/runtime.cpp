#include "lightpatch/runtime.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "lightpatch/platform/gl.h"
#include "lightpatch_shaders.h"

namespace lightpatch {
namespace {

constexpr uint32_t kUnits = 8;  // atlas texture units per draw (GLES 3.0 guarantees 16)
constexpr uint32_t kFloatsPerVertex = 9;
constexpr uint32_t kVertexBytes = kFloatsPerVertex * sizeof(float);

bool has_extension(const char* name) {
  GLint count = 0;
  glGetIntegerv(GL_NUM_EXTENSIONS, &count);
  for (GLint i = 0; i < count; ++i) {
    const char* e = reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, GLuint(i)));
    if (e && !std::strcmp(e, name)) return true;
  }
  return false;
}

bool half_float_renderable() {
  const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  int major = 0, minor = 0;
  if (version && std::sscanf(version, "OpenGL ES %d.%d", &major, &minor) == 2 &&
      (major > 3 || (major == 3 && minor >= 2))) {
    return true;
  }
  return has_extension("GL_EXT_color_buffer_half_float") ||
         has_extension("GL_EXT_color_buffer_float");
}

GLuint compile(GLenum type, const char* source, Error* error) {
  GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
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

// Decoded sign of a patch: shadow groups are subtracted; kFlagNegative flips.
float patch_sign(const PackView& pack, const pack::PatchRecord& p) {
  float s = (p.flags & pack::kFlagNegative) ? -1.0f : 1.0f;
  if (pack::group_subtracts(pack.group(p.group).kind)) s = -s;
  return s;
}

}  // namespace

// Executes the planner's steps with GL draws.
class GlSink final : public DrawSink {
 public:
  explicit GlSink(Runtime& r) : r_(r) {}
  void bind(uint32_t map) {
    if (bound_ == int(map)) return;
    glBindFramebuffer(GL_FRAMEBUFFER, r_.framebuffers_[map]);
    bound_ = int(map);
  }
  void clear_intermediate() override {
    bind(r_.shown_ ^ 1u);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
  }
  void draw(DrawTarget target, uint32_t, uint32_t first, uint32_t count,
            const float factor[3]) override {
    bind(target == DrawTarget::kLightMap ? r_.shown_ : r_.shown_ ^ 1u);
    glUniform3f(r_.factor_location_, factor[0], factor[1], factor[2]);
    const uint32_t end = first + count;
    while (first < end) {
      uint32_t run = r_.run_end_[first];
      if (run > end) run = end;
      const uint32_t batch = r_.pack_.patch(first).atlas / kUnits;
      if (int(batch) != batch_) {
        for (uint32_t u = 0; u < kUnits; ++u) {
          const uint32_t a = batch * kUnits + u;
          glActiveTexture(GL_TEXTURE0 + u);
          glBindTexture(GL_TEXTURE_2D, a < r_.pack_.atlas_count() ? r_.atlas_textures_[a] : 0);
        }
        batch_ = int(batch);
      }
      glDrawElements(GL_TRIANGLES, GLsizei((run - first) * 6), GL_UNSIGNED_INT,
                     reinterpret_cast<const void*>(uintptr_t(first) * 6 * sizeof(uint32_t)));
      first = run;
    }
  }
  void present() override {
    r_.shown_ ^= 1u;
    bound_ = -1;
  }

 private:
  Runtime& r_;
  int bound_ = -1;
  int batch_ = -1;
};

// The same plan on the CPU (no renderable half-float target): float maps, uploaded after.
class CpuSink final : public DrawSink {
 public:
  explicit CpuSink(Runtime& r) : r_(r) {}
  float* map(uint32_t i) { return r_.cpu_maps_ + size_t(i) * r_.width() * r_.height() * 4; }
  void clear_intermediate() override {
    float* m = map(r_.shown_ ^ 1u);
    const size_t n = size_t(r_.width()) * r_.height();
    for (size_t i = 0; i < n; ++i) {
      m[i * 4 + 0] = m[i * 4 + 1] = m[i * 4 + 2] = 0.0f;
      m[i * 4 + 3] = 1.0f;
    }
  }
  void draw(DrawTarget target, uint32_t, uint32_t first, uint32_t count,
            const float factor[3]) override {
    const PackView& pack = r_.pack_;
    float* m = map(target == DrawTarget::kLightMap ? r_.shown_ : r_.shown_ ^ 1u);
    if (target == DrawTarget::kLightMap) r_.cpu_dirty_ = true;
    const uint32_t w = r_.width();
    for (uint32_t p = first; p < first + count; ++p) {
      const pack::PatchRecord& pr = pack.patch(p);
      const uint8_t* atlas = pack.atlas_pixels(pr.atlas);
      const uint32_t aw = pack.atlas(pr.atlas).width;
      const float s = pr.scale * patch_sign(pack, pr);
      const uint32_t step = pr.channel_count == 3 ? 1 : 0;
      for (uint32_t y = 0; y < pr.height; ++y) {
        for (uint32_t x = 0; x < pr.width; ++x) {
          const uint8_t* q = atlas + (size_t(pr.atlas_y + y) * aw + pr.atlas_x + x) * 4;
          float* out = m + (size_t(pr.dest_y + y) * w + pr.dest_x + x) * 4;
          for (uint32_t c = 0; c < 3; ++c) {
            float v = float(q[pr.channel + c * step]) / 255.0f;
            if (pr.encoding == pack::kEncodingSquare) v *= v;
            out[c] += v * s * factor[c];
          }
        }
      }
    }
  }
  void present() override {
    r_.shown_ ^= 1u;
    r_.cpu_dirty_ = true;
  }

 private:
  Runtime& r_;
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
  run_end_ = static_cast<uint32_t*>(std::malloc(sizeof(uint32_t) * (pack.patch_count() + 1)));
  atlas_textures_ = static_cast<uint32_t*>(std::calloc(pack.atlas_count() + 1, sizeof(uint32_t)));
  if (!run_end_ || !atlas_textures_) {
    close();
    return set_error(error, Status::kOutOfMemory, "runtime: out of memory");
  }
  // Runs of patches within one group whose atlases share a batch of kUnits units.
  for (uint32_t p = pack.patch_count(); p-- > 0;) {
    const pack::PatchRecord& pr = pack.patch(p);
    const bool joins = p + 1 < pack.patch_count() && pack.patch(p + 1).group == pr.group &&
                       pack.patch(p + 1).atlas / kUnits == pr.atlas / kUnits;
    run_end_[p] = joins ? run_end_[p + 1] : p + 1;
  }
  open_ = true;
  s = create_gl(error);
  if (s != Status::kOk) {
    close();
    return s;
  }
  return Status::kOk;
}

Status Runtime::create_gl(Error* error) {
  const uint32_t w = pack_.lightmap_width(), h = pack_.lightmap_height();
  memory_ = RuntimeMemory();
  cpu_ = limits_.force_cpu_fallback || !half_float_renderable();
  shown_ = 0;

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
  // The light map and the intermediate.
  glGenTextures(2, map_textures_);
  for (uint32_t i = 0; i < 2; ++i) {
    glBindTexture(GL_TEXTURE_2D, map_textures_[i]);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA16F, GLsizei(w), GLsizei(h));
  }
  memory_.light_map = memory_.intermediate = uint64_t(w) * h * 8;
  glBindTexture(GL_TEXTURE_2D, 0);

  if (!cpu_) {
    glGenFramebuffers(2, framebuffers_);
    for (uint32_t i = 0; i < 2 && !cpu_; ++i) {
      glBindFramebuffer(GL_FRAMEBUFFER, framebuffers_[i]);
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, map_textures_[i],
                             0);
      if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) cpu_ = true;
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }
  if (cpu_) {
    const size_t floats = size_t(w) * h * 4 * 2;
    if (!cpu_maps_) cpu_maps_ = static_cast<float*>(std::calloc(floats, sizeof(float)));
    if (!cpu_maps_) return set_error(error, Status::kOutOfMemory, "runtime: out of memory");
    memory_.cpu_fallback = floats * sizeof(float);
    return glGetError() == GL_NO_ERROR
               ? Status::kOk
               : set_error(error, Status::kGlError, "runtime: GL error creating textures");
  }

  // Program.
  GLuint vs = compile(GL_VERTEX_SHADER, shaders::patch_vert, error);
  if (!vs) return Status::kGlError;
  GLuint fs = compile(GL_FRAGMENT_SHADER, shaders::patch_frag, error);
  if (!fs) {
    glDeleteShader(vs);
    return Status::kGlError;
  }
  program_ = glCreateProgram();
  glAttachShader(program_, vs);
  glAttachShader(program_, fs);
  glLinkProgram(program_);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint linked = 0;
  glGetProgramiv(program_, GL_LINK_STATUS, &linked);
  if (!linked) {
    char log[200] = {};
    glGetProgramInfoLog(program_, sizeof log, nullptr, log);
    return set_error(error, Status::kGlError, "program link failed: %s", log);
  }
  factor_location_ = glGetUniformLocation(program_, "u_factor");
  target_size_location_ = glGetUniformLocation(program_, "u_target_size");
  glUseProgram(program_);
  for (uint32_t u = 0; u < kUnits; ++u) {
    char name[16];
    std::snprintf(name, sizeof name, "u_atlas[%u]", u);
    glUniform1i(glGetUniformLocation(program_, name), GLint(u));
  }
  glUniform2f(target_size_location_, float(w), float(h));
  glUseProgram(0);

  // Vertex and index buffers: 4 vertices and 6 indices per patch, pack order, plus one
  // full-target quad at the end (the fill-rate floor).
  const uint32_t quads = pack_.patch_count() + 1;
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
    float dx0, dy0, dx1, dy1, ax0, ay0, ax1, ay1, params[4], unit;
    if (q < pack_.patch_count()) {
      const pack::PatchRecord& p = pack_.patch(q);
      dx0 = p.dest_x, dy0 = p.dest_y, dx1 = dx0 + p.width, dy1 = dy0 + p.height;
      ax0 = p.atlas_x, ay0 = p.atlas_y, ax1 = ax0 + p.width, ay1 = ay0 + p.height;
      params[0] = p.scale * patch_sign(pack_, p);
      params[1] = p.channel;
      params[2] = p.channel_count;
      params[3] = p.encoding == pack::kEncodingSquare ? 1.0f : 0.0f;
      unit = float(p.atlas % kUnits);
    } else {  // the floor quad: the whole target, sampling atlas 0 stretched over it
      const pack::AtlasRecord& a0 = pack_.atlas(0);
      dx0 = dy0 = 0.0f, dx1 = float(w), dy1 = float(h);
      ax0 = ay0 = 0.0f, ax1 = float(a0.width), ay1 = float(a0.height);
      params[0] = 1.0f, params[1] = 0.0f, params[2] = 3.0f, params[3] = 0.0f;
      unit = 0.0f;
    }
    const float corners[4][4] = {
        {dx0, dy0, ax0, ay0}, {dx1, dy0, ax1, ay0}, {dx0, dy1, ax0, ay1}, {dx1, dy1, ax1, ay1}};
    for (int c = 0; c < 4; ++c) {
      float* v = vertices + (size_t(q) * 4 + c) * kFloatsPerVertex;
      std::memcpy(v, corners[c], sizeof corners[c]);
      std::memcpy(v + 4, params, sizeof params);
      v[8] = unit;
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
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  memory_.vertex_buffer = vbytes;
  memory_.index_buffer = ibytes;
  if (glGetError() != GL_NO_ERROR) {
    return set_error(error, Status::kGlError, "runtime: GL error while creating resources");
  }
  return Status::kOk;
}

void Runtime::delete_gl() {
  if (atlas_textures_) glDeleteTextures(GLsizei(pack_.atlas_count()), atlas_textures_);
  glDeleteTextures(2, map_textures_);
  if (framebuffers_[0]) glDeleteFramebuffers(2, framebuffers_);
  if (vbo_) glDeleteBuffers(1, &vbo_);
  if (ibo_) glDeleteBuffers(1, &ibo_);
  if (vao_) glDeleteVertexArrays(1, &vao_);
  if (program_) glDeleteProgram(program_);
  forget_gl();
}

void Runtime::forget_gl() {
  if (atlas_textures_) std::memset(atlas_textures_, 0, sizeof(uint32_t) * pack_.atlas_count());
  map_textures_[0] = map_textures_[1] = 0;
  framebuffers_[0] = framebuffers_[1] = 0;
  vbo_ = ibo_ = vao_ = program_ = 0;
}

void Runtime::close() {
  if (open_) delete_gl();
  std::free(atlas_textures_);
  std::free(run_end_);
  std::free(cpu_maps_);
  atlas_textures_ = nullptr;
  run_end_ = nullptr;
  cpu_maps_ = nullptr;
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
  return planner_.set_light(i, state.on, state.color, state.intensity);
}
Status Runtime::set_light_on(uint32_t i, bool on) {
  if (i >= light_count()) return Status::kInvalidArgument;
  LightState s = light(i);
  s.on = on;
  return set_light(i, s);
}
Status Runtime::set_light_color(uint32_t i, const float rgb[3]) {
  if (i >= light_count()) return Status::kInvalidArgument;
  LightState s = light(i);
  std::memcpy(s.color, rgb, sizeof s.color);
  return set_light(i, s);
}
Status Runtime::set_light_intensity(uint32_t i, float intensity) {
  if (i >= light_count()) return Status::kInvalidArgument;
  LightState s = light(i);
  s.intensity = intensity;
  return set_light(i, s);
}
Status Runtime::set_object_visible(uint32_t i, bool visible) {
  return planner_.set_object_visible(i, visible);
}

uint32_t Runtime::light_map_texture() const {
  return map_textures_[shown_];
}

Status Runtime::update(uint64_t budget_texels) {
  if (!open_) return Status::kInvalidArgument;
  if (cpu_) {
    CpuSink sink(*this);
    planner_.update(budget_texels, sink);
    if (cpu_dirty_ && planner_.map_ready()) {
      glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
      glBindTexture(GL_TEXTURE_2D, map_textures_[shown_]);
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, GLsizei(width()), GLsizei(height()), GL_RGBA,
                      GL_FLOAT, sink.map(shown_));
      glBindTexture(GL_TEXTURE_2D, 0);
      cpu_dirty_ = false;
    }
    return glGetError() == GL_NO_ERROR ? Status::kOk : Status::kGlError;
  }
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_STENCIL_TEST);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_CULL_FACE);
  glEnable(GL_BLEND);
  glBlendEquation(GL_FUNC_ADD);
  glBlendFunc(GL_ONE, GL_ONE);
  glViewport(0, 0, GLsizei(width()), GLsizei(height()));
  glUseProgram(program_);
  glBindVertexArray(vao_);
  GlSink sink(*this);
  planner_.update(budget_texels, sink);
  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_BLEND);
  for (uint32_t u = kUnits; u-- > 0;) {
    glActiveTexture(GL_TEXTURE0 + u);
    glBindTexture(GL_TEXTURE_2D, 0);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return glGetError() == GL_NO_ERROR ? Status::kOk : Status::kGlError;
}

Status Runtime::read_light_map(float* out, Error* error) const {
  if (!open_) return set_error(error, Status::kInvalidArgument, "runtime: not open");
  const size_t n = size_t(width()) * height() * 4;
  if (cpu_) {
    std::memcpy(out, cpu_maps_ + n * shown_, n * sizeof(float));
    return Status::kOk;
  }
  GLuint fbo = framebuffers_[shown_];
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glReadPixels(0, 0, GLsizei(width()), GLsizei(height()), GL_RGBA, GL_FLOAT, out);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (glGetError() != GL_NO_ERROR) {
    return set_error(error, Status::kGlError, "runtime: glReadPixels of the light map failed");
  }
  return Status::kOk;
}

Status Runtime::draw_fill_floor(uint64_t texels, Error* error) {
  if (!open_ || cpu_ || !idle()) {
    return set_error(error, Status::kInvalidArgument, "fill floor: needs an idle GPU-path runtime");
  }
  const uint64_t full = uint64_t(width()) * height();
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_STENCIL_TEST);
  glDisable(GL_CULL_FACE);
  glEnable(GL_BLEND);
  glBlendEquation(GL_FUNC_ADD);
  glBlendFunc(GL_ONE, GL_ONE);
  glViewport(0, 0, GLsizei(width()), GLsizei(height()));
  glUseProgram(program_);
  glBindVertexArray(vao_);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffers_[shown_ ^ 1u]);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, atlas_textures_[0]);
  glUniform3f(factor_location_, 0.0f, 0.0f, 0.0f);
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
  glDisable(GL_SCISSOR_TEST);
  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_BLEND);
  glBindTexture(GL_TEXTURE_2D, 0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return glGetError() == GL_NO_ERROR ? Status::kOk
                                     : set_error(error, Status::kGlError, "fill floor: GL error");
}

}  // namespace lightpatch
