#pragma once
// The `vn` normals a write recomputes (issue 14): write_garment_obj makes each
// normal a face corner uses the normalised sum of the Newell normals of those
// faces; for a stored garment the faces' normals are found in one pass, then
// summed into the normals a range at a time.
#include <refit/chunked/chunk_plan.hpp>
#include <refit/chunked/garment_store.hpp>

#include <optional>
#include <string>
#include <vector>

namespace refit {

struct ChunkedNormals {
  PointFile normals;                     // per `vn` line: its new value (where recomputed)
  RecordFile<std::uint8_t> recomputed;   // per `vn` line: 1 when recomputed
  std::size_t count = 0;                 // how many were recomputed
  std::vector<std::string> warnings;     // write_garment_obj's
};

/// The normals of the garment at `positions` (null when the garment's faces use none).
std::optional<ChunkedNormals> chunked_normals(const GarmentStore& g, const PointFile& positions, const ChunkPlan& plan);

}  // namespace refit
