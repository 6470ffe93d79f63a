#pragma once
// A 4-ary min-heap: half the depth of a binary heap, and the four children of a node share a cache
// line or two, which matters when the queue holds millions of candidates.
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

  T pop() {
    T out = std::move(items_.front());
    T last = std::move(items_.back());
    items_.pop_back();
    if (!items_.empty()) {
      std::size_t i = 0;
      const std::size_t n = items_.size();
      for (;;) {
        const std::size_t first = 4 * i + 1;
        if (first >= n) break;
        std::size_t best = first;
        const std::size_t end = std::min(first + 4, n);
        for (std::size_t c = first + 1; c < end; ++c)
          if (less_(items_[c], items_[best])) best = c;
        if (!less_(items_[best], last)) break;
        items_[i] = std::move(items_[best]);
        i = best;
      }
      items_[i] = std::move(last);
    }
    return out;
  }

 private:
  std::vector<T> items_;
  Less less_;
};

}  // namespace lodkit::detail
