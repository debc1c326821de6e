#include "light_meter.h"

#include <algorithm>
#include <cmath>

#include "lightpatch/indirect_map.h"
#include "lightpatch/platform/gl.h"
#include "ray_cast.h"
#include "world.h"

namespace lightpatch::inn {
float LightMeter::luminance(const float rgb[3]) {
  return 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2];
}

LightMeter::~LightMeter() {
  if (framebuffer_) glDeleteFramebuffers(1, &framebuffer_);
}

void LightMeter::init() {
  glGenFramebuffers(1, &framebuffer_);
}

std::vector<glm::ivec2> LightMeter::texels_around(const World& world, glm::vec3 origin,
                                                  uint32_t map_width, uint32_t map_height,
                                                  float min_distance, float max_distance) {
  std::vector<glm::ivec2> texels;
  // Three rings of eight rays, 20..60 degrees below the horizon: the surfaces a flame lights most.
  for (int ring = 0; ring < 3; ++ring) {
    const float elevation = -glm::radians(20.0f + 20.0f * static_cast<float>(ring));
    for (int k = 0; k < 8; ++k) {
      const float azimuth =
          glm::radians(45.0f * static_cast<float>(k) + 22.5f * static_cast<float>(ring));
      const glm::vec3 dir(std::cos(elevation) * std::cos(azimuth), std::sin(elevation),
                          std::cos(elevation) * std::sin(azimuth));
      RayHit hit;
      if (!cast_ray(world, world.static_range, origin, dir, max_distance, true, &hit) ||
          hit.distance < min_distance) {
        continue;
      }
      const glm::vec2 uv = hit_lightmap_uv(world, hit);
      const int x = std::clamp(static_cast<int>(uv.x * static_cast<float>(map_width)), 0,
                               static_cast<int>(map_width) - 1);
      const int y = std::clamp(static_cast<int>(uv.y * static_cast<float>(map_height)), 0,
                               static_cast<int>(map_height) - 1);
      texels.emplace_back(x, y);
    }
  }
  return texels;
}

float LightMeter::measure(const Runtime& runtime, const std::vector<glm::ivec2>& texels) {
  if (texels.empty() || !runtime.ready()) return -1.0f;
  double sum = 0.0;
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D,
                         runtime.light_map_texture(), 0);
  const bool readable = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  if (readable) {
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    for (const glm::ivec2& t : texels) {
      float rgba[4] = {};
      glReadPixels(t.x, t.y, 1, 1, GL_RGBA, GL_FLOAT, rgba);
      sum += luminance(rgba) * runtime.light_map_scale();
    }
  }
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, 0, 0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (!readable) {
    // The CPU path's texture may not be renderable: read the whole map through the runtime.
    whole_map_.resize(static_cast<size_t>(runtime.width()) * runtime.height() * 4);
    if (runtime.read_light_map(whole_map_.data(), nullptr) != Status::kOk) return -1.0f;
    for (const glm::ivec2& t : texels) {
      sum += luminance(
          &whole_map_[(static_cast<size_t>(t.y) * runtime.width() + static_cast<size_t>(t.x)) * 4]);
    }
  }
  if (runtime.indirect_map_texture() != 0) {  // L + I: the indirect map magnified at each texel
    const uint32_t iw = runtime.indirect_width(), ih = runtime.indirect_height();
    indirect_.resize(static_cast<size_t>(iw) * ih * 4);
    if (runtime.read_indirect_map(indirect_.data(), nullptr) != Status::kOk) return -1.0f;
    for (const glm::ivec2& t : texels) {
      float rgb[3];
      sample_indirect(indirect_.data(), 4, iw, ih, runtime.indirect_scale(),
                      static_cast<uint32_t>(t.x), static_cast<uint32_t>(t.y), rgb);
      sum += luminance(rgb);
    }
  }
  if (glGetError() != GL_NO_ERROR) return -1.0f;
  return static_cast<float>(sum / static_cast<double>(texels.size()));
}

}  // namespace lightpatch::inn
