#pragma once
// A 4-ary min-heap: half the depth of a binary heap, and the four children of a node share a cache
// line or two, which matters when the queue holds millions of candidates.
#include <algorithm>
#include <utility>
#include <vector>

namespace lodkit::detail {

template <typename T, typename Less>
class QuadHeap {
 public:
  bool empty() const { return items_.empty(); }
  std::size_t size() const { return items_.size(); }
  void reserve(std::size_t n) { items_.reserve(n); }
  const T& top() const { return items_.front(); }

  void push(const T& item) {
    std::size_t i = items_.size();
    items_.push_back(item);
    while (i > 0) {
      const std::size_t parent = (i - 1) / 4;
      if (!less_(items_[i], items_[parent])) break;
      std::swap(items_[i], items_[parent]);
      i = parent;
    }
  }

  /// Drops the items `keep` rejects and restores the heap order in linear time (Floyd).
  template <typename Keep>
  void filter(Keep keep) {
    items_.erase(std::remove_if(items_.begin(), items_.end(), [&](const T& item) { return !keep(item); }), items_.end());
    for (std::size_t i = items_.size() / 4 + 1; i-- > 0;) sift_down(i);
  }

  T pop() {
    T out = std::move(items_.front());
    items_.front() = std::move(items_.back());
    items_.pop_back();
    if (!items_.empty()) sift_down(0);
    return out;
  }

 private:
  // Moves item i down to where its children are no cheaper.
  void sift_down(std::size_t i) {
    const std::size_t n = items_.size();
    if (i >= n) return;
    T moving = std::move(items_[i]);
    for (;;) {
      const std::size_t first = 4 * i + 1;
      if (first >= n) break;
      std::size_t best = first;
      const std::size_t end = std::min(first + 4, n);
      for (std::size_t c = first + 1; c < end; ++c)
        if (less_(items_[c], items_[best])) best = c;
      if (!less_(items_[best], moving)) break;
      items_[i] = std::move(items_[best]);
      i = best;
    }
    items_[i] = std::move(moving);
  }

  std::vector<T> items_;
  Less less_;
};

}  // namespace lodkit::detail
