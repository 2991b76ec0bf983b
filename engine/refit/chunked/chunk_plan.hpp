#pragma once
// The chunked mode's memory plan (issue 14): how many vertices a chunk holds,
// how much of the OBJ is read at once, whether positions stay in memory for
// the face passes, and what all that is estimated to take; and when a garment
// is resized in chunks rather than in memory.
#include <cstddef>
#include <filesystem>
#include <string>

namespace refit {

/// What the user asks of the chunked mode.
struct ChunkOptions {
  std::size_t memory_budget = 0;      // bytes a run may use; 0: no budget (the in-memory mode unless forced)
  std::size_t chunk_vertices = 0;     // > 0: the chunked mode with chunks of this many vertices (testing)
  std::filesystem::path temp_folder;  // temporary files (empty: the system's temporary folder)
};

/// Parses a size such as "1G", "800M", "512k" or "1000000" (bytes; k, M, G, T
/// in powers of 1024, an optional B); throws refit::Error naming `what`.
std::size_t parse_size(const std::string& text, const std::string& what);

/// The sizes of a garment, as its file's first pass counts them.
struct GarmentSize {
  std::size_t file_bytes = 0, vertices = 0, faces = 0;
};

/// The surface step's agent count, estimated from the vertex count (the
/// automatic voxel size's budget; with an explicit voxel size, the budget too:
/// the binding refuses a voxel size that would make far more).
double estimated_agents(std::size_t vertices, std::size_t agent_budget, double voxel);

/// Whether the garment in `file` could need more memory than this machine has
/// in memory (then its vertices are counted before choosing), from the density
/// of vertex lines at its start; false for a file that cannot be read.
bool might_exceed_memory(const std::filesystem::path& file);

struct ChunkPlan {
  std::size_t chunk_vertices = 0;  // vertices per chunk
  std::size_t chunk_faces = 0;     // faces (and lines, points) per chunk
  std::size_t group_bytes = 0;     // bytes of the OBJ parsed at once
  std::size_t gather_bytes = 0;    // position gathers keep all positions in memory up to this
  std::filesystem::path folder;    // where the temporary files go
  double estimate_mb = 0.0;        // the estimated peak
};

/// The plan for a garment of `size` under `options`. Throws refit::ResourceError
/// (exit code 3) when even the chunked mode cannot stay within the budget.
ChunkPlan plan_chunks(const GarmentSize& size, const ChunkOptions& options);

/// Whether `size` is resized in chunks: forced by options.chunk_vertices, or
/// the in-memory run's estimate (`in_memory_mb`, estimated_memory_mb) above the
/// budget, or above this machine's memory without one.
bool use_chunks(const GarmentSize& size, const ChunkOptions& options, double in_memory_mb);

}  // namespace refit
