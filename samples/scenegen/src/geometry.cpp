#include "lightpatch/scenegen/geometry.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace lightpatch::scenegen {

void Geometry::append(const Geometry& other) {
  if (!positions.empty() &&
      ((uv0.empty() != other.uv0.empty()) || (uv1.empty() != other.uv1.empty()))) {
    throw std::invalid_argument("Geometry::append: texture coordinate channels differ");
  }
  const auto base = static_cast<std::uint32_t>(positions.size());
  positions.insert(positions.end(), other.positions.begin(), other.positions.end());
  normals.insert(normals.end(), other.normals.begin(), other.normals.end());
  uv0.insert(uv0.end(), other.uv0.begin(), other.uv0.end());
  uv1.insert(uv1.end(), other.uv1.begin(), other.uv1.end());
  indices.reserve(indices.size() + other.indices.size());
  for (std::uint32_t i : other.indices) indices.push_back(base + i);
}

void Geometry::append(const Geometry& other, const glm::mat4& m) {
  append(other.transformed(m));
}

void Geometry::transform(const glm::mat4& m) {
  const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(m)));
  for (glm::vec3& p : positions) p = glm::vec3(m * glm::vec4(p, 1.0f));
  for (glm::vec3& n : normals) {
    const glm::vec3 t = normal_matrix * n;
    const float len = glm::length(t);
    n = len > 0.0f ? t / len : n;
  }
  if (glm::determinant(glm::mat3(m)) < 0.0f) {
    for (std::size_t i = 0; i + 2 < indices.size(); i += 3)
      std::swap(indices[i + 1], indices[i + 2]);
  }
}

Geometry Geometry::transformed(const glm::mat4& m) const {
  Geometry g = *this;
  g.transform(m);
  return g;
}

void Geometry::flip() {
  for (glm::vec3& n : normals) n = -n;
  for (std::size_t i = 0; i + 2 < indices.size(); i += 3) std::swap(indices[i + 1], indices[i + 2]);
}

glm::vec3 Geometry::bounds_min() const {
  if (positions.empty()) return glm::vec3(0.0f);
  glm::vec3 r = positions[0];
  for (const glm::vec3& p : positions) r = glm::min(r, p);
  return r;
}

glm::vec3 Geometry::bounds_max() const {
  if (positions.empty()) return glm::vec3(0.0f);
  glm::vec3 r = positions[0];
  for (const glm::vec3& p : positions) r = glm::max(r, p);
  return r;
}

void Geometry::check() const {
  const std::size_t n = positions.size();
  if (normals.size() != n)
    throw std::invalid_argument("Geometry: normals count != positions count");
  if (!uv0.empty() && uv0.size() != n)
    throw std::invalid_argument("Geometry: uv0 count != positions count");
  if (!uv1.empty() && uv1.size() != n)
    throw std::invalid_argument("Geometry: uv1 count != positions count");
  if (indices.size() % 3 != 0)
    throw std::invalid_argument("Geometry: index count is not a multiple of 3");
  for (std::uint32_t i : indices) {
    if (i >= n)
      throw std::invalid_argument("Geometry: index " + std::to_string(i) + " out of range");
  }
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec3& p = positions[i];
    const glm::vec3& q = normals[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      throw std::invalid_argument("Geometry: position " + std::to_string(i) + " is not finite");
    }
    const float len = glm::length(q);
    if (!std::isfinite(len) || std::fabs(len - 1.0f) > 1e-3f) {
      throw std::invalid_argument("Geometry: normal " + std::to_string(i) + " is not unit length");
    }
  }
}

}  // namespace lightpatch::scenegen
