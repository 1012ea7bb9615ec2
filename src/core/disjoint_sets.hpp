#pragma once
// Union-find over dense ids 0..n-1 (path halving; the smaller id becomes the root, so the result
// does not depend on the order of unions).

#include <cstddef>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

namespace esf {

class DisjointSets {
  public:
    explicit DisjointSets(std::size_t n) : parent_(n) {
        std::iota(parent_.begin(), parent_.end(), std::uint32_t{0});
    }
    std::uint32_t find(std::uint32_t i) {
        while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
        return i;
    }
    void unite(std::uint32_t a, std::uint32_t b) {
        a = find(a);
        b = find(b);
        if (a == b) return;
        if (a > b) std::swap(a, b);
        parent_[b] = a;
    }
    std::size_t size() const { return parent_.size(); }

    /// Replaces each id in `ids` (each < size()) by the number of its set, sets numbered
    /// 0, 1, ... in order of first appearance in `ids`.
    void number_sets(std::vector<std::uint32_t>& ids) {
        constexpr std::uint32_t kNone = ~std::uint32_t{0};
        std::vector<std::uint32_t> number(parent_.size(), kNone);
        std::uint32_t next = 0;
        for (std::uint32_t& id : ids) {
            const std::uint32_t root = find(id);
            if (number[root] == kNone) number[root] = next++;
            id = number[root];
        }
    }

  private:
    std::vector<std::uint32_t> parent_;
};

}  // namespace esf
