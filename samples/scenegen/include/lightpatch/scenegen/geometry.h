// Geometry: an indexed triangle list in memory (positions, normals, optional texture
// coordinates), the unit that the shape helpers produce and SceneBuilder turns into a glTF
// primitive. Units are metres; triangles wind counter-clockwise seen from the side the normals
// point to (glTF front faces).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace lightpatch::scenegen {

struct Geometry {
  std::vector<glm::vec3> positions{};
  std::vector<glm::vec3> normals{};      // unit length, one per position
  std::vector<glm::vec2> uv0{};          // empty, or one per position (TEXCOORD_0)
  std::vector<glm::vec2> uv1{};          // empty, or one per position (TEXCOORD_1, light-map UVs)
  std::vector<std::uint32_t> indices{};  // three per triangle

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t triangle_count() const { return indices.size() / 3; }
  bool empty() const { return indices.empty(); }

  // Appends `other`; both must carry the same optional channels (or this one must be empty).
  // Throws std::invalid_argument otherwise.
  void append(const Geometry& other);
  // Appends `other` transformed by `m` (see transform()).
  void append(const Geometry& other, const glm::mat4& m);
  // Transforms positions by `m`, normals by its inverse transpose (renormalized), and reverses
  // the winding when `m` mirrors (negative determinant) so front faces stay front faces.
  void transform(const glm::mat4& m);
  Geometry transformed(const glm::mat4& m) const;
  // Turns the surface inside out: reverses winding and negates normals.
  void flip();
  // Axis-aligned bounds of the positions (both zero when empty).
  glm::vec3 bounds_min() const;
  glm::vec3 bounds_max() const;
  // Throws std::invalid_argument when channel sizes disagree, an index is out of range, the
  // index count is not a multiple of 3, or a position/normal is not finite.
  void check() const;
};

}  // namespace lightpatch::scenegen
