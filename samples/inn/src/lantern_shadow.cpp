#include "lantern_shadow.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "gl_program.h"
#include "lightpatch/platform/gl.h"
#include "view_culling.h"
#include "world.h"

namespace lightpatch::inn {
namespace {

const char* const kDepthVertexShader = R"(#version 300 es
uniform mat4 u_face;
in vec3 a_position;
void main() { gl_Position = u_face * vec4(a_position, 1.0); }
)";

const char* const kDepthFragmentShader = R"(#version 300 es
precision mediump float;
void main() {}
)";

// Can face f (axis f / 2, sign + for even f) of a cube centred at the origin see any of the box
// [lo, hi] within `far`? Conservative: the box's nearest point within range, and the face's
// 90-degree pyramid |p_b| <= s p_a, |p_c| <= s p_a against the box's extremes per axis.
bool face_sees(int f, glm::vec3 lo, glm::vec3 hi, float far) {
  float d2 = 0.0f;
  for (int k = 0; k < 3; ++k) {
    const float d = std::max({lo[k], 0.0f, -hi[k]});
    d2 += d * d;
  }
  if (d2 > far * far) return false;
  const int a = f / 2, b = (a + 1) % 3, c = (a + 2) % 3;
  const float reach = f % 2 == 0 ? hi[a] : -lo[a];  // farthest along the face's direction
  if (!(reach > 0.0f)) return false;
  auto nearest_abs = [&](int k) {
    return lo[k] <= 0.0f && hi[k] >= 0.0f ? 0.0f : std::min(std::fabs(lo[k]), std::fabs(hi[k]));
  };
  return nearest_abs(b) <= reach && nearest_abs(c) <= reach;
}

// The cube map's face order and its OpenGL conventions (view direction, up).
const glm::vec3 kFaceDirection[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                     {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
const glm::vec3 kFaceUp[6] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1},
                              {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};

}  // namespace

LanternShadow::~LanternShadow() {
  if (program_) glDeleteProgram(program_);
  if (texture_) glDeleteTextures(1, &texture_);
  glDeleteFramebuffers(6, framebuffers_);
}

bool LanternShadow::init(const World& world, char* message, unsigned message_size) {
  world_ = &world;
  visible_.assign(world.objects.size(), 0);
  const char* const attributes[] = {"a_position", nullptr};
  program_ =
      build_program(kDepthVertexShader, kDepthFragmentShader, attributes, message, message_size);
  if (!program_) return false;
  face_matrix_location_ = glGetUniformLocation(program_, "u_face");
  glGenTextures(1, &texture_);
  glBindTexture(GL_TEXTURE_CUBE_MAP, texture_);
  for (int f = 0; f < 6; ++f) {
    glTexImage2D(GL_TEXTURE_CUBE_MAP_POSITIVE_X + f, 0, GL_DEPTH_COMPONENT24, kFaceSize, kFaceSize,
                 0, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
  }
  glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  glBindTexture(GL_TEXTURE_CUBE_MAP, 0);
  GLint previous = 0;
  glGetIntegerv(GL_FRAMEBUFFER_BINDING, &previous);
  glGenFramebuffers(6, framebuffers_);
  bool complete = true;
  for (int f = 0; f < 6; ++f) {
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffers_[f]);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_CUBE_MAP_POSITIVE_X + f,
                           texture_, 0);
    const GLenum none = GL_NONE;
    glDrawBuffers(1, &none);
    glReadBuffer(GL_NONE);
    complete = complete && glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  }
  glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(previous));
  if (!complete || glGetError() != GL_NO_ERROR) {
    std::snprintf(message, message_size, "the lantern's shadow cube map is not renderable here");
    return false;
  }
  return true;
}

void LanternShadow::update(uint32_t vao, glm::vec3 position, float far,
                           const uint8_t* object_visible, const glm::mat4& camera) {
  triangles_ = 0;
  bool same = drawn_ && glm::distance(position, position_) < kRedrawDistance && far == far_;
  for (size_t o = 0; o < visible_.size() && same; ++o)
    same = (visible_[o] != 0) == (object_visible[o] != 0);
  if (!same) {
    drawn_ = true;
    position_ = position;
    far_ = far;
    for (size_t o = 0; o < visible_.size(); ++o) visible_[o] = object_visible[o] ? 1 : 0;
    for (bool& f : fresh_) f = false;
  }
  // The faces the camera may look up: a fragment it sees reads the face its direction from the
  // origin falls in (or, filtered, a few texels of the next face), out to the light's range,
  // which may pass the far plane. So each face's pyramid, widened by kFaceMargin texels and out
  // to kTestReach, against the camera's view; a face that misses it keeps what it holds, and is
  // drawn (from the same origin) on the first frame it may be seen.
  bool wanted[6] = {};
  bool any = false;
  const float widened = 1.0f + 2.0f * float(kFaceMargin) / float(kFaceSize);
  const glm::mat4 test_projection =
      glm::perspective(2.0f * std::atan(widened), 1.0f, kNear, kTestReach);
  for (int f = 0; f < 6; ++f) {
    if (fresh_[f]) continue;
    const glm::mat4 face =
        test_projection * glm::lookAt(position_, position_ + kFaceDirection[f], kFaceUp[f]);
    wanted[f] = views_meet(camera, face);
    any = any || wanted[f];
  }
  if (!any) return;

  GLint previous = 0, viewport[4] = {};
  glGetIntegerv(GL_FRAMEBUFFER_BINDING, &previous);
  glGetIntegerv(GL_VIEWPORT, viewport);
  glViewport(0, 0, kFaceSize, kFaceSize);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_CULL_FACE);  // rooms are closed boxes seen from inside: both sides occlude
  glUseProgram(program_);
  glBindVertexArray(vao);
  const glm::mat4 projection = glm::perspective(glm::radians(90.0f), 1.0f, kNear, far_);
  auto draw_range = [this](const IndexRange& r) {
    if (r.count == 0) return;
    triangles_ += r.count / 3;
    glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(r.count), GL_UNSIGNED_INT,
                   reinterpret_cast<const void*>(static_cast<size_t>(r.first) * sizeof(uint32_t)));
  };
  for (int f = 0; f < 6; ++f) {
    if (!wanted[f]) continue;
    fresh_[f] = true;
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffers_[f]);
    glClear(GL_DEPTH_BUFFER_BIT);
    const glm::mat4 m =
        projection * glm::lookAt(position_, position_ + kFaceDirection[f], kFaceUp[f]);
    glUniformMatrix4fv(face_matrix_location_, 1, GL_FALSE, glm::value_ptr(m));
    // The static chunks this face can see, consecutive ones in one draw.
    for_each_chunk_run(
        *world_,
        [&](const WorldChunk& ch) {
          return face_sees(f, ch.bounds_min - position_, ch.bounds_max - position_, far_);
        },
        draw_range);
    for (size_t o = 0; o < world_->objects.size(); ++o) {
      const WorldObject& ob = world_->objects[o];
      if (visible_[o] && face_sees(f, ob.bounds_min - position_, ob.bounds_max - position_, far_))
        draw_range(ob.range);
    }
  }
  glBindVertexArray(0);
  glUseProgram(0);
  glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(previous));
  glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
}

}  // namespace lightpatch::inn
