#pragma once
// Union-find over a parent vector (parent[i] == i for a root; start with
// std::iota), with path halving. Groups garment vertices into layers and pieces.
// Not thread-safe: find_root shortens paths as it walks.

#include <algorithm>
#include <vector>

#include <refit/core/types.hpp>

namespace refit {

inline Index find_root(std::vector<Index>& parent, Index a) {
  while (parent[a] != a) a = parent[a] = parent[parent[a]];
  return a;
}

/// Joins the sets of a and b. The smaller root stays the root, so every root is
/// its set's smallest index whatever the order of the unions (deterministic labels).
inline void unite_roots(std::vector<Index>& parent, Index a, Index b) {
  a = find_root(parent, a);
  b = find_root(parent, b);
  if (a != b) parent[std::max(a, b)] = std::min(a, b);
}

/// Every entry pointed at its root, in one pass: a parent is never larger than
/// its child (unite_roots keeps the smaller root, find_root only skips to
/// ancestors), so a vertex's parent is flat before the vertex.
inline void flatten_roots(std::vector<Index>& parent) {
  for (Index& p : parent) p = parent[p];
}

}  // namespace refit
