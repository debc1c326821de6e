#include "kd_tree.h"

#include <algorithm>
#include <deque>
#include <limits>
#include <numeric>

namespace lightpatch::cooker {

KdTree::KdTree(const std::vector<glm::vec3>& points) {
  order_.resize(points.size());
  std::iota(order_.begin(), order_.end(), 0);
  points_ = points;
  axis_.assign(points.size(), 0);
  build(0, static_cast<int>(points.size()), 0, std::numeric_limits<int>::max());
  std::vector<glm::vec3> sorted(points.size());
  for (size_t i = 0; i < order_.size(); ++i) sorted[i] = points[static_cast<size_t>(order_[i])];
  points_ = std::move(sorted);
}

// Median split, like QuickSort's partition (seed 004, appendix C). Iterative on the larger half
// would bound the stack further; the depth is log2(n) anyway.
std::vector<int> KdTree::top_levels_of(const std::vector<glm::vec3>& points, size_t count) {
  KdTree t;
  t.order_.resize(points.size());
  std::iota(t.order_.begin(), t.order_.end(), 0);
  t.points_ = points;
  t.axis_.assign(points.size(), 0);
  int levels = 0;
  while (levels < 62 && ((size_t{1} << levels) - 1) < count) ++levels;
  t.build(0, static_cast<int>(points.size()), 0, levels);
  return t.top_levels(count);
}

void KdTree::build(int start, int end, int depth, int max_depth) {
  if (end - start <= 1 || depth >= max_depth) return;
  glm::vec3 lo(points_[static_cast<size_t>(order_[static_cast<size_t>(start)])]), hi(lo);
  for (int i = start + 1; i < end; ++i) {
    const glm::vec3& p = points_[static_cast<size_t>(order_[static_cast<size_t>(i)])];
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::vec3 ext = hi - lo;
  const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
  const int mid = (start + end) / 2;
  // Ties are broken by index so the tree does not depend on the standard library's partition.
  std::nth_element(order_.begin() + start, order_.begin() + mid, order_.begin() + end,
                   [&](int a, int b) {
                     const float pa = points_[static_cast<size_t>(a)][axis];
                     const float pb = points_[static_cast<size_t>(b)][axis];
                     return pa < pb || (pa == pb && a < b);
                   });
  axis_[static_cast<size_t>(mid)] = static_cast<uint8_t>(axis);
  build(start, mid, depth + 1, max_depth);
  build(mid + 1, end, depth + 1, max_depth);
}

std::vector<int> KdTree::top_levels(size_t count) const {
  std::vector<int> out;
  std::deque<std::pair<int, int>> queue;
  if (!order_.empty()) queue.emplace_back(0, static_cast<int>(order_.size()));
  while (!queue.empty() && out.size() < count) {
    const auto [start, end] = queue.front();
    queue.pop_front();
    if (end <= start) continue;
    const int mid = (start + end) / 2;
    out.push_back(order_[static_cast<size_t>(mid)]);
    queue.emplace_back(start, mid);
    queue.emplace_back(mid + 1, end);
  }
  return out;
}

}  // namespace lightpatch::cooker
