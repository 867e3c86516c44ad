// Disjoint sets over 0..n-1 with path halving; the lower index is the root of
// a union, so a group's root is its oldest member when indices follow age.
#pragma once

#include <algorithm>
#include <cstddef>
#include <numeric>
#include <vector>

namespace semrec {

class UnionFind {
 public:
  explicit UnionFind(size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  size_t Find(size_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void Unite(size_t a, size_t b) {
    a = Find(a), b = Find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }
  /// Groups of two or more members, each ascending, in order of their roots.
  std::vector<std::vector<size_t>> Groups() {
    std::vector<std::vector<size_t>> by_root(parent_.size());
    for (size_t i = 0; i < parent_.size(); ++i) by_root[Find(i)].push_back(i);
    std::vector<std::vector<size_t>> groups;
    for (auto& g : by_root) {
      if (g.size() > 1) groups.push_back(std::move(g));
    }
    return groups;
  }

 private:
  std::vector<size_t> parent_;
};

}  // namespace semrec
