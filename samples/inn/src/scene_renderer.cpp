#include "scene_renderer.h"

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <string>

#include <glm/gtc/type_ptr.hpp>

#include "gl_program.h"
#include "lightpatch/platform/gl.h"
#include "view_culling.h"
#include "world.h"

namespace lightpatch::inn {
namespace {

const char* const kVertexShader = R"(#version 300 es
uniform mat4 u_view_projection;
uniform vec4 u_flames[32];  // glow of each light's flame, 4 lights per vec4
in vec3 a_position;
in vec2 a_lightmap_uv;
in vec4 a_albedo;
in vec3 a_emissive;
in float a_flame;
out vec2 v_lightmap_uv;
out vec3 v_albedo;
out vec3 v_emission;
out vec3 v_position;
void main() {
  gl_Position = u_view_projection * vec4(a_position, 1.0);
  v_position = a_position;
  v_lightmap_uv = a_lightmap_uv;
  v_albedo = a_albedo.rgb;
  float glow = 1.0;
  if (a_flame >= 0.0) {
    int i = int(a_flame + 0.5);
    glow = u_flames[i / 4][i % 4];
  }
  v_emission = a_emissive * glow;
}
)";

// The start of both fragment shaders: radiance exposed, tone mapped and sRGB-encoded (header).
const char* const kFragmentOutput = R"(#version 300 es
precision highp float;
uniform float u_exposure;
out vec4 o_color;
void write_color(vec3 radiance) {
  vec3 c = 1.0 - exp(-u_exposure * radiance);
  // sRGB transfer curve (the framebuffer is a plain 8-bit one).
  vec3 lo = c * 12.92;
  vec3 hi = 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055;
  o_color = vec4(mix(lo, hi, step(vec3(0.0031308), c)), 1.0);
}
)";

const char* const kFragmentShader = R"(
uniform sampler2D u_light_map;
uniform sampler2D u_indirect_map;
// The lantern's direct light (SceneRenderer::Frame): the cooker's punctual irradiance
// (direct_light.cpp: cos / d^2 times the glTF range window), shadowed by its depth cube map.
uniform vec3 u_lantern_position;
uniform vec3 u_lantern_shadow_origin;  // where the depth cube map was drawn from
uniform vec3 u_lantern_factor;  // 0: no lantern
uniform vec3 u_lantern_planes;  // near, far, range
uniform highp samplerCubeShadow u_lantern_shadow;
in vec2 v_lightmap_uv;
in vec3 v_albedo;
in vec3 v_emission;
in vec3 v_position;
vec3 lantern_irradiance() {
  vec3 to = u_lantern_position - v_position;
  float d2 = dot(to, to);
  float d = sqrt(d2);
  // The triangle's own normal, facing the camera (the world's vertices carry none).
  vec3 n = normalize(cross(dFdx(v_position), dFdy(v_position)));
  float c = dot(n, to) / max(d, 1e-4);
  float x = d / u_lantern_planes.z;
  float window = clamp(1.0 - x * x * x * x, 0.0, 1.0);
  if (c <= 0.0 || window <= 0.0) return vec3(0.0);
  // The fragment's depth in the cube face it falls on, pulled towards the lantern by a bias that
  // grows with the distance (the depth texels' footprint).
  vec3 v = v_position - u_lantern_shadow_origin;
  float m = max(abs(v.x), max(abs(v.y), abs(v.z)));
  m = max(m - (0.02 + 0.015 * m), u_lantern_planes.x);
  float nr = u_lantern_planes.x, fr = u_lantern_planes.y;
  float z = (fr + nr) / (fr - nr) - 2.0 * fr * nr / ((fr - nr) * m);
  float lit = texture(u_lantern_shadow, vec4(v, 0.5 * z + 0.5));
  return u_lantern_factor * (c / (d2 + 1e-4) * window * lit);
}
void main() {
  // L + I (pack_format.h, "Two target maps"): the indirect map's own bilinear filtering magnifies
  // it; without one it is a black texel.
  vec3 irradiance = max(texture(u_light_map, v_lightmap_uv).rgb +
                        texture(u_indirect_map, v_lightmap_uv).rgb, vec3(0.0));
  if (u_lantern_factor != vec3(0.0)) irradiance += lantern_irradiance();
  write_color(v_albedo * irradiance * 0.31830988 + v_emission);
}
)";

// The lantern's flame: a round sprite at its position, hidden by what is in front of it.
const char* const kGlowVertexShader = R"(#version 300 es
uniform mat4 u_view_projection;
uniform vec3 u_lantern_position;
void main() {
  gl_Position = u_view_projection * vec4(u_lantern_position, 1.0);
  gl_PointSize = clamp(24.0 / max(gl_Position.w, 0.05), 2.0, 48.0);
}
)";

const char* const kGlowFragmentShader = R"(
void main() {
  vec2 c = gl_PointCoord * 2.0 - 1.0;
  float r2 = dot(c, c);
  if (r2 > 1.0) discard;
  write_color(vec3(8.0, 5.5, 3.0) * (1.0 - r2));
}
)";

// The carried item: its baked triangles moved by u_model, lit by the light probes' irradiance SH.
const char* const kHeldVertexShader = R"(#version 300 es
uniform mat4 u_view_projection;
uniform mat4 u_model;
in vec3 a_position;
in vec2 a_lightmap_uv;  // unused: bound so that the attribute locations match the scene's
in vec4 a_albedo;
out vec3 v_position;
out vec3 v_albedo;
void main() {
  vec4 p = u_model * vec4(a_position, 1.0);
  gl_Position = u_view_projection * p;
  v_position = p.xyz;
  v_albedo = a_albedo.rgb;
}
)";

const char* const kHeldFragmentShader = R"(
uniform vec3 u_sh[9];  // irradiance SH per channel, lightpatch/spherical_harmonics.h's order
in vec3 v_position;
in vec3 v_albedo;
void main() {
  // The item's meshes carry no normals: the triangle's own, facing the camera.
  vec3 n = normalize(cross(dFdx(v_position), dFdy(v_position)));
  // E(n) = sum_k sh_k Y_k(n) with sh_basis()'s constants (spherical_harmonics.h), clamped at 0.
  vec3 e = u_sh[0] * 0.282095 + (u_sh[1] * n.y + u_sh[2] * n.z + u_sh[3] * n.x) * 0.488603 +
           (u_sh[4] * (n.x * n.y) + u_sh[5] * (n.y * n.z) + u_sh[7] * (n.x * n.z)) * 1.092548 +
           u_sh[6] * (0.315392 * (3.0 * n.z * n.z - 1.0)) +
           u_sh[8] * (0.546274 * (n.x * n.x - n.y * n.y));
  write_color(v_albedo * max(e, vec3(0.0)) * 0.31830988);
}
)";

}  // namespace

SceneRenderer::~SceneRenderer() {
  if (program_) glDeleteProgram(program_);
  if (held_program_) glDeleteProgram(held_program_);
  if (glow_program_) glDeleteProgram(glow_program_);
  if (vao_) glDeleteVertexArrays(1, &vao_);
  if (vbo_) glDeleteBuffers(1, &vbo_);
  if (ibo_) glDeleteBuffers(1, &ibo_);
  if (black_) glDeleteTextures(1, &black_);
}

bool SceneRenderer::init(const World& world, char* message, unsigned message_size) {
  world_ = &world;
  // Flames belong to the scene's lights; the moving lights' panes come after them in the pack's
  // light table and have none.
  flame_lights_ = 0;
  for (size_t l = 0; l < world.lights.size(); ++l)
    if (!world.lights[l].name.empty()) flame_lights_ = l + 1;
  if (flame_lights_ > kMaxLights) {
    std::snprintf(message, message_size,
                  "the scene has %zu semi-dynamic lights; the renderer draws flames of at most %u",
                  flame_lights_, kMaxLights);
    return false;
  }
  const char* const attributes[] = {"a_position", "a_lightmap_uv", "a_albedo",
                                    "a_emissive", "a_flame",       nullptr};
  program_ = build_program(kVertexShader, (std::string(kFragmentOutput) + kFragmentShader).c_str(),
                           attributes, message, message_size);
  if (!program_) return false;
  view_projection_location_ = glGetUniformLocation(program_, "u_view_projection");
  light_map_location_ = glGetUniformLocation(program_, "u_light_map");
  indirect_map_location_ = glGetUniformLocation(program_, "u_indirect_map");
  // What a pack without an indirect map adds: one black texel.
  glGenTextures(1, &black_);
  glBindTexture(GL_TEXTURE_2D, black_);
  const uint16_t zero[4] = {0, 0, 0, 0};
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA16F, 1, 1, 0, GL_RGBA, GL_HALF_FLOAT, zero);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glBindTexture(GL_TEXTURE_2D, 0);
  exposure_location_ = glGetUniformLocation(program_, "u_exposure");
  flames_location_ = glGetUniformLocation(program_, "u_flames");
  lantern_position_location_ = glGetUniformLocation(program_, "u_lantern_position");
  lantern_factor_location_ = glGetUniformLocation(program_, "u_lantern_factor");
  lantern_origin_location_ = glGetUniformLocation(program_, "u_lantern_shadow_origin");
  lantern_planes_location_ = glGetUniformLocation(program_, "u_lantern_planes");
  lantern_shadow_location_ = glGetUniformLocation(program_, "u_lantern_shadow");
  glow_program_ =
      build_program(kGlowVertexShader, (std::string(kFragmentOutput) + kGlowFragmentShader).c_str(),
                    attributes, message, message_size);
  if (!glow_program_) return false;
  glow_view_projection_location_ = glGetUniformLocation(glow_program_, "u_view_projection");
  glow_position_location_ = glGetUniformLocation(glow_program_, "u_lantern_position");
  glow_exposure_location_ = glGetUniformLocation(glow_program_, "u_exposure");
  if (!shadow_.init(world, message, message_size)) return false;
  held_program_ =
      build_program(kHeldVertexShader, (std::string(kFragmentOutput) + kHeldFragmentShader).c_str(),
                    attributes, message, message_size);
  if (!held_program_) return false;
  held_view_projection_location_ = glGetUniformLocation(held_program_, "u_view_projection");
  held_model_location_ = glGetUniformLocation(held_program_, "u_model");
  held_sh_location_ = glGetUniformLocation(held_program_, "u_sh");
  held_exposure_location_ = glGetUniformLocation(held_program_, "u_exposure");

  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &vbo_);
  glGenBuffers(1, &ibo_);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(world.vertices.size() * sizeof(WorldVertex)),
               world.vertices.data(), GL_STATIC_DRAW);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo_);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(world.indices.size() * sizeof(uint32_t)),
               world.indices.data(), GL_STATIC_DRAW);
  const GLsizei stride = sizeof(WorldVertex);
  auto at = [](size_t offset) { return reinterpret_cast<const void*>(offset); };
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, at(offsetof(WorldVertex, position)));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, stride, at(offsetof(WorldVertex, lightmap_uv)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 4, GL_UNSIGNED_BYTE, GL_TRUE, stride, at(offsetof(WorldVertex, albedo)));
  glEnableVertexAttribArray(3);
  glVertexAttribPointer(3, 3, GL_FLOAT, GL_FALSE, stride, at(offsetof(WorldVertex, emissive)));
  glEnableVertexAttribArray(4);
  glVertexAttribPointer(4, 1, GL_FLOAT, GL_FALSE, stride, at(offsetof(WorldVertex, flame)));
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  if (glGetError() != GL_NO_ERROR) {
    std::snprintf(message, message_size,
                  "uploading the scene's geometry failed (out of GPU memory?)");
    return false;
  }
  return true;
}

SceneRenderer::DrawStats SceneRenderer::draw(const Frame& frame) {
  const bool lantern = frame.lantern_factor != glm::vec3(0.0f);
  // The shadow reaches as far as the light (within LanternShadow::kReach).
  const float far =
      std::min(frame.lantern_range > 0.0f ? frame.lantern_range : 1.0e9f, LanternShadow::kReach);
  if (lantern)
    shadow_.update(vao_, frame.lantern_position, far, frame.object_visible, frame.view_projection);
  glViewport(0, 0, frame.viewport_width, frame.viewport_height);
  glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
  glClearDepthf(1.0f);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
  if (world_->double_sided) {
    glDisable(GL_CULL_FACE);
  } else {
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);
  }
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glUseProgram(program_);
  glUniformMatrix4fv(view_projection_location_, 1, GL_FALSE, glm::value_ptr(frame.view_projection));
  glUniform1f(exposure_location_, frame.exposure);
  float flames[kMaxLights] = {};
  for (size_t l = 0; l < flame_lights_; ++l) flames[l] = frame.flame[l];
  glUniform4fv(flames_location_, kMaxLights / 4, flames);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, frame.light_map);
  glUniform1i(light_map_location_, 0);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, frame.indirect_map ? frame.indirect_map : black_);
  glUniform1i(indirect_map_location_, 1);
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_CUBE_MAP, shadow_.texture());
  glUniform1i(lantern_shadow_location_, 2);
  const glm::vec3 factor = lantern ? frame.lantern_factor : glm::vec3(0.0f);
  glUniform3fv(lantern_factor_location_, 1, glm::value_ptr(factor));
  glUniform3fv(lantern_position_location_, 1, glm::value_ptr(frame.lantern_position));
  const glm::vec3 origin = shadow_.origin();
  glUniform3fv(lantern_origin_location_, 1, glm::value_ptr(origin));
  glUniform3f(lantern_planes_location_, LanternShadow::kNear, far,
              frame.lantern_range > 0.0f ? frame.lantern_range : 1.0e9f);
  glActiveTexture(GL_TEXTURE0);
  glBindVertexArray(vao_);
  DrawStats stats;
  auto draw_range = [&stats](const IndexRange& r) {
    if (r.count == 0) return;
    stats.scene_triangles += r.count / 3;
    glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(r.count), GL_UNSIGNED_INT,
                   reinterpret_cast<const void*>(static_cast<size_t>(r.first) * sizeof(uint32_t)));
  };
  // The static chunks the camera can see, consecutive ones in one draw.
  for_each_chunk_run(
      *world_,
      [&](const WorldChunk& ch) {
        return box_in_view(frame.view_projection, ch.bounds_min, ch.bounds_max);
      },
      draw_range);
  for (size_t o = 0; o < world_->objects.size(); ++o) {
    const WorldObject& ob = world_->objects[o];
    if (frame.object_visible[o] && box_in_view(frame.view_projection, ob.bounds_min, ob.bounds_max))
      draw_range(ob.range);
  }
  if (frame.held_object >= 0 && static_cast<size_t>(frame.held_object) < world_->objects.size()) {
    glUseProgram(held_program_);
    glUniformMatrix4fv(held_view_projection_location_, 1, GL_FALSE,
                       glm::value_ptr(frame.view_projection));
    glUniformMatrix4fv(held_model_location_, 1, GL_FALSE, glm::value_ptr(frame.held_model));
    glUniform3fv(held_sh_location_, 9, frame.held_sh);
    glUniform1f(held_exposure_location_, frame.exposure);
    draw_range(world_->objects[static_cast<size_t>(frame.held_object)].range);
  }
  if (lantern && !frame.lantern_hidden) {
    glUseProgram(glow_program_);
    glUniformMatrix4fv(glow_view_projection_location_, 1, GL_FALSE,
                       glm::value_ptr(frame.view_projection));
    glUniform3fv(glow_position_location_, 1, glm::value_ptr(frame.lantern_position));
    glUniform1f(glow_exposure_location_, frame.exposure);
    glDrawArrays(GL_POINTS, 0, 1);
  }
  glBindVertexArray(0);
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_CUBE_MAP, 0);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, 0);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, 0);
  glUseProgram(0);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  stats.shadow_triangles = shadow_.triangles_drawn();
  return stats;
}

}  // namespace lightpatch::inn
