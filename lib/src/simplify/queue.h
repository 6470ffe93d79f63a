#pragma once
// A 4-ary min-heap: half the depth of a binary heap, and the four children of a node share a cache
// line or two, which matters when the queue holds millions of candidates.
#include <algorithm>
#include <tbb/parallel_sort.h>
#include <utility>
#include <vector>

#include "core/huge_pages.h"

namespace lodkit::detail {

template <typename T, typename Less>
class QuadHeap {
 public:
  bool empty() const { return items_.empty(); }
  std::size_t size() const { return items_.size(); }
  const T& top() const { return items_.front(); }

  void push(const T& item) {
    std::size_t i = items_.size();
    // Grown as push_back would, into storage advised for huge pages: a lane's heap doubles to megabytes.
    if (i == items_.capacity()) reserve_huge(items_, std::max<std::size_t>(16, 2 * i));
    items_.push_back(item);
    while (i > 0) {
      const std::size_t parent = (i - 1) / 4;
      if (!less_(items_[i], items_[parent])) break;
      std::swap(items_[i], items_[parent]);
      i = parent;
    }
  }

  /// Moves every item out, in no particular order, and leaves the heap empty.
  std::vector<T> take() { return std::exchange(items_, {}); }

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

/// A priority queue for a run that starts with many items and then adds a few at a time: the first
/// batch sorted once in a flat array, read front to back; later items in a 4-ary heap; pop takes the
/// smaller front. Popping from one big heap sifted through levels far outside the cache; the sorted
/// batch is read in order. Pops come out in the same order as from one heap.
template <typename T, typename Less>
class BatchQueue {
 public:
  bool empty() const { return next_ == run_.size() && heap_.empty(); }
  std::size_t size() const { return run_.size() - next_ + heap_.size(); }

  /// Replaces the contents with `items`.
  void load(std::vector<T> items) {
    run_ = std::move(items);
    next_ = 0;
    heap_ = {};
    tbb::parallel_sort(run_.begin(), run_.end(), less_);
  }
  void push(const T& item) { heap_.push(item); }

  const T& top() const { return from_run() ? run_[next_] : heap_.top(); }
  T pop() { return from_run() ? run_[next_++] : heap_.pop(); }

  /// Moves every item out, in no particular order, and leaves the queue empty.
  std::vector<T> take() {
    std::vector<T> out = std::exchange(run_, {});
    out.erase(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(next_));
    const std::vector<T> rest = heap_.take();
    out.insert(out.end(), rest.begin(), rest.end());
    next_ = 0;
    return out;
  }

  /// Drops the items `keep` rejects (and the sorted batch's items already read), in one pass.
  template <typename Keep>
  void filter(Keep keep) {
    std::size_t kept = 0;
    for (std::size_t i = next_; i < run_.size(); ++i)
      if (keep(run_[i])) run_[kept++] = run_[i];
    run_.resize(kept);
    next_ = 0;
    heap_.filter(keep);
  }

 private:
  bool from_run() const { return next_ < run_.size() && (heap_.empty() || !less_(heap_.top(), run_[next_])); }

  std::vector<T> run_;
  std::size_t next_ = 0;
  QuadHeap<T, Less> heap_;
  Less less_;
};

}  // namespace lodkit::detail
