// Half-edges of a mesh put in order of (lower vertex, higher vertex,
// triangle) in linear time: counted by lower vertex (stable, and they are
// made in triangle order), then each vertex's few sorted. The same order a
// comparison sort gives, at a fraction of its cost on a large mesh.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

namespace truecut::offline::geometry {

// low(h): h's lower vertex; less: the order within one lower vertex.
template <class HalfEdge, class Low, class Less>
void sort_half_edges(std::vector<HalfEdge>& half, Low low, Less less) {
  constexpr std::size_t kInsertionSortLimit = 32;
  std::uint32_t top = 0;
  for (const HalfEdge& h : half)
    top = std::max(top, low(h));
  std::vector<std::uint32_t> start(std::size_t{top} + 2, 0);
  for (const HalfEdge& h : half)
    ++start[std::size_t{low(h)} + 1];
  for (std::size_t v = 1; v < start.size(); ++v)
    start[v] += start[v - 1];
  std::vector<HalfEdge> out(half.size());
  std::vector<std::uint32_t> next(start.begin(), start.end() - 1);
  for (const HalfEdge& h : half)
    out[next[low(h)]++] = h;
  for (std::size_t v = 0; v + 1 < start.size(); ++v) {
    const auto first = out.begin() + start[v], last = out.begin() + start[v + 1];
    if (static_cast<std::size_t>(last - first) > kInsertionSortLimit) {
      std::sort(first, last, less);
      continue;
    }
    for (auto i = first; i != last; ++i)
      for (auto j = i; j != first && less(*j, *(j - 1)); --j)
        std::iter_swap(j, j - 1);
  }
  half.swap(out);
}

}  // namespace truecut::offline::geometry
