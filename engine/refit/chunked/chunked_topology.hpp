#pragma once
// A stored garment's topology in passes (issue 14): its coincident vertices
// welded, its face edges counted on disk, its boundary loops -- what the
// layers and the boundary features find on the whole garment in memory.
#include <refit/chunked/chunk_plan.hpp>
#include <refit/chunked/garment_store.hpp>

#include <tbb/parallel_sort.h>

#include <algorithm>

#include <cstdint>
#include <unordered_map>
#include <vector>

namespace refit {

/// bounding_box_diagonal of the garment's positions.
double bounding_box_diagonal(const GarmentStore& g);

/// weld_points(positions, tolerance) for a stored garment: the vertices whose
/// representative is another, with it.
std::unordered_map<Index, Index> chunked_weld(const GarmentStore& g, const ChunkPlan& plan, double tolerance);

// Edges of the faces, bucketed by key so that each bucket fits in memory
// (garment_layers' sort of all face edges, for garments larger than memory).
/// Face edges as keys (lo << 32 | hi), bucketed on disk by key so that each
/// bucket fits in memory: the keys used exactly once (boundary edges) come out.
class EdgeBuckets {
 public:
  EdgeBuckets(const std::filesystem::path& folder, std::size_t edges, std::size_t bucket_edges) {
    buckets_ = std::max<std::size_t>(1, (edges + bucket_edges - 1) / std::max<std::size_t>(bucket_edges, 1));
    for (std::size_t b = 0; b < buckets_; ++b) files_.emplace_back(folder);
    pending_.resize(buckets_);
  }
  void add(std::uint64_t key) {
    const std::size_t b = buckets_ == 1 ? 0 : (key * 0x9E3779B97F4A7C15ULL >> 20) % buckets_;
    pending_[b].push_back(key);
    if (pending_[b].size() >= (1 << 16)) flush(b);
  }
  // Each key used exactly once (a boundary edge): f(key), bucket by bucket.
  template <class F>
  void singles(F&& f) {
    for (std::size_t b = 0; b < buckets_; ++b) flush(b);
    std::vector<std::uint64_t> keys;
    for (std::size_t b = 0; b < buckets_; ++b) {
      keys.resize(files_[b].size() / sizeof(std::uint64_t));
      files_[b].read(keys.data(), files_[b].size(), 0);
      tbb::parallel_sort(keys.begin(), keys.end());
      for (std::size_t i = 0; i < keys.size();) {
        std::size_t j = i;
        while (j < keys.size() && keys[j] == keys[i]) ++j;
        if (j - i == 1) f(keys[i]);
        i = j;
      }
    }
  }

 private:
  void flush(std::size_t b) {
    files_[b].append(pending_[b].data(), pending_[b].size() * sizeof(std::uint64_t));
    pending_[b].clear();
  }
  std::size_t buckets_ = 1;
  std::vector<TempFile> files_;
  std::vector<std::vector<std::uint64_t>> pending_;
};

/// boundary_loops(weld_garment(garment, tolerance)) for a stored garment, each loop's positions.
std::vector<Points> chunked_boundary_loops(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan,
                                           double tolerance);

}  // namespace refit
