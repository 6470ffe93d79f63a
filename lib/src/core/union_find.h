#pragma once
#include <numeric>
#include <vector>

namespace lodkit::detail {

/// Disjoint sets with path halving and union by size.
class UnionFind {
 public:
  explicit UnionFind(std::size_t n = 0) { reset(n); }
  /// n singletons again, reusing the storage (for many small problems in a row).
  void reset(std::size_t n) {
    parent_.resize(n);
    size_.assign(n, 1);
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  int find(int x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  bool unite(int a, int b) {
    a = find(a), b = find(b);
    if (a == b) return false;
    if (size_[a] < size_[b]) std::swap(a, b);
    parent_[b] = a;
    size_[a] += size_[b];
    return true;
  }

 private:
  std::vector<int> parent_;
  std::vector<int> size_;
};

}  // namespace lodkit::detail
