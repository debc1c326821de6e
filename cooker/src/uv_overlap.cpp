#include "uv_overlap.h"

#include <algorithm>
#include <cmath>

namespace lightpatch::cooker {

namespace {

// A triangle spanning more cells than this (huge among tiny ones) is kept in a list that every
// query checks, which bounds the grid's memory.
constexpr int64_t kMaxCellsPerTriangle = 1 << 16;

float cross2(const glm::vec2& a, const glm::vec2& b) {
  return a.x * b.y - a.y * b.x;
}

// Separating-axis test. Projections that overlap by less than `tol` count as separated, so shared
// edges and corners are not overlaps.
bool interiors_overlap(const glm::vec2* a, const glm::vec2* b, float tol) {
  for (int pass = 0; pass < 2; ++pass) {
    const glm::vec2* t = pass == 0 ? a : b;
    for (int k = 0; k < 3; ++k) {
      const glm::vec2 e = t[(k + 1) % 3] - t[k];
      const float len = glm::length(e);
      if (!(len > 0.0f)) continue;
      const glm::vec2 axis(-e.y / len, e.x / len);
      float amin = 1e30f, amax = -1e30f, bmin = 1e30f, bmax = -1e30f;
      for (int j = 0; j < 3; ++j) {
        const float pa = glm::dot(a[j], axis), pb = glm::dot(b[j], axis);
        amin = std::min(amin, pa);
        amax = std::max(amax, pa);
        bmin = std::min(bmin, pb);
        bmax = std::max(bmax, pb);
      }
      if (amax <= bmin + tol || bmax <= amin + tol) return false;
    }
  }
  return true;
}

float extent(const glm::vec2 tri[3]) {
  const glm::vec2 lo = glm::min(tri[0], glm::min(tri[1], tri[2]));
  const glm::vec2 hi = glm::max(tri[0], glm::max(tri[1], tri[2]));
  return std::max(hi.x - lo.x, hi.y - lo.y);
}

}  // namespace

bool UvOverlapGrid::cell_range(const glm::vec2 tri[3], int64_t r[4]) const {
  const glm::vec2 lo = glm::min(tri[0], glm::min(tri[1], tri[2]));
  const glm::vec2 hi = glm::max(tri[0], glm::max(tri[1], tri[2]));
  r[0] = int64_t(std::floor(lo.x / cell_));
  r[1] = int64_t(std::floor(lo.y / cell_));
  r[2] = int64_t(std::floor(hi.x / cell_));
  r[3] = int64_t(std::floor(hi.y / cell_));
  return (r[2] - r[0] + 1) * (r[3] - r[1] + 1) <= kMaxCellsPerTriangle;
}

bool UvOverlapGrid::overlaps(const glm::vec2 tri[3], int* which) const {
  if (tris_.empty()) return false;
  const float size = extent(tri);
  const float area = std::abs(cross2(tri[1] - tri[0], tri[2] - tri[0]));
  if (!(area > 1e-10f * size * size)) return false;  // no interior
  auto test = [&](const std::vector<int>& list) {
    for (int i : list) {
      const glm::vec2* other = &tris_[size_t(i) * 3];
      const float tol = 1e-4f * std::min(size, extent(other));
      if (interiors_overlap(tri, other, tol)) {
        if (which) *which = i;
        return true;
      }
    }
    return false;
  };
  if (test(big_)) return true;
  int64_t r[4];
  if (!cell_range(tri, r)) {
    for (const auto& [cell, list] : grid_)
      if (cell.x >= r[0] && cell.x <= r[2] && cell.y >= r[1] && cell.y <= r[3] && test(list))
        return true;
    return false;
  }
  for (int64_t y = r[1]; y <= r[3]; ++y)
    for (int64_t x = r[0]; x <= r[2]; ++x) {
      auto it = grid_.find(Cell{x, y});
      if (it != grid_.end() && test(it->second)) return true;
    }
  return false;
}

void UvOverlapGrid::insert(const glm::vec2 tri[3]) {
  if (!(cell_ > 0.0f)) {
    const float e = extent(tri);
    cell_ = e > 0.0f ? 2.0f * e : 1.0f;
  }
  const int index = static_cast<int>(tris_.size() / 3);
  tris_.insert(tris_.end(), tri, tri + 3);
  int64_t r[4];
  if (!cell_range(tri, r)) {
    big_.push_back(index);
    return;
  }
  for (int64_t y = r[1]; y <= r[3]; ++y)
    for (int64_t x = r[0]; x <= r[2]; ++x) grid_[Cell{x, y}].push_back(index);
}

}  // namespace lightpatch::cooker
