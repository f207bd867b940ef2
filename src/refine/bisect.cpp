// 4-8 subdivision by newest-vertex bisection of block diagonals (ALGORITHM.md 2.8).
//
// References: Velho & Zorin, "4-8 subdivision" (CAGD 2001); Bänsch, "Local mesh refinement in 2
// and 3 dimensions" (1991); Kossaczký, "A recursive approach to local mesh refinement in two and
// three dimensions" (1994); Duchaineau et al., "ROAMing terrain" (1997) for the forced splits.
//
// Splitting the block of t = (v0, v1, v2) with neighbour n = (w0, v2, v1) across the refinement
// edge inserts m on (v1, v2) and makes the children
//     c0 = (m, v0, v1)   c1 = (m, v2, v0)   (of t)      d0 = (m, w0, v2)   d1 = (m, v1, w0)   (of n)
// whose refinement edges (opposite m) are the block's outer edges, so new blocks form across old
// block borders and a compatible labelling stays compatible. The outer neighbours' links are
// moved from t and n to the children. Forced splits (splitting coarser incompatible neighbours
// first) are the drivers' business: here a split only happens when the block is complete.
#include <algorithm>
#include <stdexcept>
#include <string>

#include "forest.h"

namespace adamesh::detail {

Forest::Forest(std::span<const std::array<std::uint32_t, 3>> base, std::uint32_t num_base_vertices)
    : f0_(static_cast<std::uint32_t>(base.size())), v0_(num_base_vertices), tris_(base.size()) {
  struct HalfEdge {
    std::uint64_t key;  // (min, max)
    std::uint32_t t;
    std::uint8_t i;     // edge opposite v[i]
    bool forward;       // v[i+1] < v[i+2]
  };
  std::vector<HalfEdge> he;
  he.reserve(3 * base.size());
  for (std::uint32_t t = 0; t < f0_; ++t) {
    tris_[t].v = base[t];
    tris_[t].alive = 1;
    for (std::uint8_t i = 0; i < 3; ++i) {
      const std::uint32_t a = base[t][(i + 1) % 3], b = base[t][(i + 2) % 3];
      he.push_back({(static_cast<std::uint64_t>(std::min(a, b)) << 32) | std::max(a, b), t, i,
                    a < b});
    }
  }
  std::sort(he.begin(), he.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.key != y.key ? x.key < y.key : x.t != y.t ? x.t < y.t : x.i < y.i;
  });
  for (std::size_t i = 0; i < he.size();) {
    std::size_t j = i + 1;
    while (j < he.size() && he[j].key == he[i].key) ++j;
    if (j - i == 2 && he[i].forward != he[i + 1].forward) {
      tris_[he[i].t].nbr[he[i].i] = he[i + 1].t;
      tris_[he[i + 1].t].nbr[he[i + 1].i] = he[i].t;
    } else if (j - i >= 2) {
      ++nonmanifold_;
    }
    i = j;
  }
  leaves_ = f0_;
}

void Forest::ensure(std::uint32_t s) {
  const std::size_t need = static_cast<std::size_t>(f0_) + 4 * (static_cast<std::size_t>(s) + 1);
  if (tris_.size() < need) tris_.resize(std::max(need, tris_.size() + tris_.size() / 2));
  if (used_split_.size() <= s) used_split_.resize(std::max<std::size_t>(s + 1, used_split_.size() * 3 / 2));
}

void Forest::relink(std::uint32_t t, std::uint32_t old_nbr, std::uint32_t new_nbr) {
  if (t == kNone) return;
  for (auto& x : tris_[t].nbr)
    if (x == old_nbr) {
      x = new_nbr;
      return;
    }
}

bool Forest::split(std::uint32_t t, std::uint32_t s) {
  if (!is_leaf(t)) return false;
  const std::uint32_t n = tris_[t].nbr[0];
  if (n != kNone && (!is_leaf(n) || tris_[n].nbr[0] != t)) return false;
  ensure(s);
  if (used_split_[s]) return false;
  used_split_[s] = 1;

  const ForestTri T = tris_[t];
  const std::uint32_t m = v0_ + s;
  const std::uint32_t c0 = f0_ + 4 * s, c1 = c0 + 1, d0 = c0 + 2, d1 = c0 + 3;
  const std::uint8_t level = static_cast<std::uint8_t>(T.level + 1);
  const std::uint32_t v0 = T.v[0], v1 = T.v[1], v2 = T.v[2];
  const std::uint32_t A = T.nbr[1], B = T.nbr[2];
  const bool has_n = n != kNone;

  tris_[c0] = ForestTri{{m, v0, v1}, {B, has_n ? d1 : kNone, c1}, kNone, level, 0, 1};
  tris_[c1] = ForestTri{{m, v2, v0}, {A, c0, has_n ? d0 : kNone}, kNone, level, 0, 1};
  relink(B, t, c0);
  relink(A, t, c1);
  tris_[t].split = s;
  tris_[t].role = 0;
  if (has_n) {
    const ForestTri N = tris_[n];  // (w0, v2, v1)
    const std::uint32_t w0 = N.v[0];
    tris_[d0] = ForestTri{{m, w0, v2}, {N.nbr[2], c1, d1}, kNone, level, 0, 1};
    tris_[d1] = ForestTri{{m, v1, w0}, {N.nbr[1], d0, c0}, kNone, level, 0, 1};
    relink(N.nbr[2], n, d0);
    relink(N.nbr[1], n, d1);
    tris_[n].split = s;
    tris_[n].role = 1;
  }
  leaves_ += has_n ? 2 : 1;
  ++applied_;
  return true;
}

std::vector<std::uint32_t> Forest::leaves() const {
  std::vector<std::uint32_t> out;
  out.reserve(leaves_);
  std::vector<std::uint32_t> stack;
  for (std::uint32_t b = 0; b < f0_; ++b) {
    stack.push_back(b);
    while (!stack.empty()) {
      const std::uint32_t x = stack.back();
      stack.pop_back();
      if (tris_[x].split == kNone) {
        out.push_back(x);
      } else {
        stack.push_back(child(x, 1));
        stack.push_back(child(x, 0));
      }
    }
  }
  return out;
}

void Forest::check() const {
  auto fail = [](const std::string& what) { throw std::logic_error("forest: " + what); };
  std::size_t leaves = 0;
  for (std::uint32_t t = 0; t < tris_.size(); ++t) {
    if (!is_leaf(t)) continue;
    ++leaves;
    const auto& x = tris_[t];
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t n = x.nbr[i];
      if (n == kNone) continue;
      if (!is_leaf(n)) fail("triangle " + std::to_string(t) + " links a non-leaf");
      const std::uint32_t a = x.v[(i + 1) % 3], b = x.v[(i + 2) % 3];
      bool back = false;
      for (int j = 0; j < 3; ++j)
        back |= tris_[n].nbr[j] == t && tris_[n].v[(j + 1) % 3] == b && tris_[n].v[(j + 2) % 3] == a;
      if (!back) fail("triangles " + std::to_string(t) + " and " + std::to_string(n) +
                      " are not mutual neighbours across one edge");
    }
  }
  if (leaves != leaves_) fail("leaf count");
}

}  // namespace adamesh::detail
