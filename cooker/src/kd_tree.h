// A balanced 3-d tree over points, stored as one array with no child pointers (seed 004,
// appendix C): the node of the index range [start, end) is its middle element, split on the axis
// of the range's largest extent; its children are [start, mid) and [mid + 1, end). The nodes of
// the top levels, in breadth-first order, are well spread over the points' distribution: the
// indirect-light pass takes its virtual lights from them (seed 004 §2, step 3).
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace lightpatch::cooker {

class KdTree {
 public:
  KdTree() = default;
  // Builds over `points` (copied); deterministic for a given input.
  explicit KdTree(const std::vector<glm::vec3>& points);

  // The first `count` nodes, in breadth-first order, of the tree over `points`, partitioning only
  // the levels they lie in (O(n log count) rather than a whole tree's O(n log n)).
  static std::vector<int> top_levels_of(const std::vector<glm::vec3>& points, size_t count);

  size_t size() const { return order_.size(); }
  // The point index stored at tree slot `slot`.
  int point_at(size_t slot) const { return order_[slot]; }

  // Point indices of the first `count` nodes in breadth-first (level) order: the top levels.
  std::vector<int> top_levels(size_t count) const;

  // Index of the point nearest to p among those for which accept(index) is true; -1 if none.
  // Ties go to the lower index.
  template <typename Accept>
  int nearest(const glm::vec3& p, const Accept& accept) const {
    int best = -1;
    float best_d2 = 0.0f;
    search(0, static_cast<int>(order_.size()), p, accept, best, best_d2);
    return best;
  }

 private:
  void build(int start, int end, int depth, int max_depth);
  // Near side first (recursion), then the far side only if the split plane is closer than the
  // best so far (iteration, seed 004 §6.3.4).
  template <typename Accept>
  void search(int start, int end, const glm::vec3& p, const Accept& accept, int& best,
              float& best_d2) const {
    while (end > start) {
      const int mid = (start + end) / 2;
      const glm::vec3& q = points_[static_cast<size_t>(mid)];
      const int axis = axis_[static_cast<size_t>(mid)];
      const float d = p[axis] - q[axis];
      const glm::vec3 dv = p - q;
      const float d2 = glm::dot(dv, dv);
      const int index = order_[static_cast<size_t>(mid)];
      if ((best < 0 || d2 < best_d2 || (d2 == best_d2 && index < best)) && accept(index)) {
        best = index;
        best_d2 = d2;
      }
      const bool left_first = d < 0.0f;
      search(left_first ? start : mid + 1, left_first ? mid : end, p, accept, best, best_d2);
      if (best >= 0 && d * d > best_d2) return;
      const int far_start = left_first ? mid + 1 : start, far_end = left_first ? end : mid;
      start = far_start;
      end = far_end;
    }
  }

  std::vector<glm::vec3> points_;  // in tree order
  std::vector<int> order_;         // tree slot -> input index
  std::vector<uint8_t> axis_;      // tree slot -> split axis
};

}  // namespace lightpatch::cooker
