#include <refit/chunked/chunk_plan.hpp>

#include <refit/core/error.hpp>
#include <refit/core/progress.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>

namespace refit {
namespace {

constexpr double kMB = 1024.0 * 1024.0;
// What a run holds whatever the garment: the program, the bodies with their
// trees, the agent system (about 20k agents), the feature curves (a small
// garment's run peaks at 35-38 MB; the agent system of a dense one adds more).
constexpr double kFixedBytes = 64.0 * kMB;
// Per vertex of a chunk at the heaviest pass (the surface step's re-emission:
// original, warped and new positions, the blends, the warp's triangle sets).
constexpr double kChunkVertexBytes = 640.0;
// Per face of a face chunk: indices and offsets, corner positions when gathered.
constexpr double kChunkFaceBytes = 112.0;
// Kept per vertex for the whole run: the layer of each vertex and the union-find
// over the faces that finds them (4 bytes each), a few flags.
constexpr double kResidentVertexBytes = 10.0;

}  // namespace

std::size_t parse_size(const std::string& text, const std::string& what) {
  std::size_t i = 0;
  while (i < text.size() && (std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == '.')) ++i;
  double value = 0.0;
  try {
    std::size_t used = 0;
    value = i > 0 ? std::stod(text.substr(0, i), &used) : -1.0;
    if (used != i) value = -1.0;
  } catch (const std::exception&) {
    value = -1.0;
  }
  std::string unit = text.substr(i);
  if (!unit.empty() && (unit.back() == 'B' || unit.back() == 'b')) unit.pop_back();
  double scale = 1.0;
  if (unit == "k" || unit == "K") scale = 1024.0;
  else if (unit == "m" || unit == "M") scale = kMB;
  else if (unit == "g" || unit == "G") scale = kMB * 1024.0;
  else if (unit == "t" || unit == "T") scale = kMB * kMB;
  else if (!unit.empty()) value = -1.0;
  if (!(value > 0.0) || !std::isfinite(value * scale) || value * scale > 1e18)
    throw Error(what + ": '" + text + "' is not a size (a positive number with k, M, G or T, e.g. 800M or 1G)");
  return static_cast<std::size_t>(value * scale);
}

double estimated_agents(std::size_t vertices, std::size_t agent_budget, double voxel) {
  if (voxel == 0.0) return double(std::min(agent_budget, std::max<std::size_t>(vertices, 1000)));
  return double(agent_budget);
}

bool might_exceed_memory(const std::filesystem::path& file) {
  // The vertex lines of the file's first few MB (where OBJ writers put them) as
  // dense as they are there over the whole file: an overestimate for a garment
  // of faces too, and cheap where counting the whole file is not (measured: 6 s
  // against the read's 10 s on the 1M dense dress, loaded machine).
  std::error_code error;
  const std::size_t bytes = std::filesystem::file_size(file, error);
  if (error) return false;  // the reader names the problem
  std::ifstream in(file, std::ios::binary);
  std::string sample(std::min<std::size_t>(bytes, std::size_t(4) << 20), '\0');
  in.read(sample.data(), std::streamsize(sample.size()));
  sample.resize(std::size_t(std::max<std::streamsize>(in.gcount(), 0)));
  std::size_t vertex_lines = 0;
  for (std::size_t i = 0; i + 1 < sample.size(); ++i)
    if ((i == 0 || sample[i - 1] == '\n') && sample[i] == 'v' && (sample[i + 1] == ' ' || sample[i + 1] == '\t'))
      ++vertex_lines;
  if (sample.empty()) return false;
  const double vertices = double(vertex_lines) * double(bytes) / double(sample.size());
  // The in-memory run takes about 600 bytes per vertex (estimated_memory_mb).
  return 600.0 * vertices > physical_memory_mb() * kMB;
}

ChunkPlan plan_chunks(const GarmentSize& s, const ChunkOptions& o) {
  ChunkPlan p;
  p.folder = o.temp_folder.empty() ? std::filesystem::temp_directory_path() : o.temp_folder;
  const double n = double(std::max<std::size_t>(s.vertices, 1));
  const double faces_per_vertex = std::max(1.0, double(s.faces) / n);
  const double resident = kResidentVertexBytes * n;
  // Without a budget (and not forced), the machine's memory, less a quarter for the rest of it.
  const double machine = o.chunk_vertices > 0 ? 0.0 : 0.75 * physical_memory_mb() * kMB;
  if (o.memory_budget > 0 || machine > 0.0) {
    const double budget = o.memory_budget > 0 ? double(o.memory_budget) : machine;
    double free = budget - kFixedBytes - resident;
    const double least = 4096.0 * (kChunkVertexBytes + faces_per_vertex * kChunkFaceBytes) + 3.0 * (1 << 18);
    if (free < least) {
      char text[300];
      std::snprintf(text, sizeof text,
                    "a garment of %zu vertices needs at least %.0f MB even in chunks (%.0f MB fixed, %.0f bytes per "
                    "vertex, the smallest chunks), more than the memory budget of %.0f MB",
                    s.vertices, (kFixedBytes + resident + least) / kMB, kFixedBytes / kMB, kResidentVertexBytes,
                    budget / kMB);
      throw ResourceError(text);
    }
    // Positions stay in memory for the face passes when they take at most half
    // of what is left; else they are gathered from disk by windows.
    const double positions = 24.0 * n;
    if (positions <= 0.5 * free) {
      p.gather_bytes = static_cast<std::size_t>(positions);
      free -= positions;
    } else {
      p.gather_bytes = static_cast<std::size_t>(0.25 * free);
      free -= 0.25 * free;
    }
    p.group_bytes = static_cast<std::size_t>(std::clamp(free / 12.0, double(1 << 18), 64.0 * kMB));
    free -= 3.0 * double(p.group_bytes);
    p.chunk_vertices = static_cast<std::size_t>(free / (kChunkVertexBytes + faces_per_vertex * kChunkFaceBytes));
  } else {
    p.gather_bytes = static_cast<std::size_t>(24.0 * n);
    p.group_bytes = std::size_t(64) << 20;
    p.chunk_vertices = std::size_t(1) << 20;
  }
  if (o.chunk_vertices > 0) {
    p.chunk_vertices = o.chunk_vertices;
    // Small chunks for tests: groups of the OBJ as small as its chunks allow.
    p.group_bytes = std::min<std::size_t>(p.group_bytes, std::max<std::size_t>(o.chunk_vertices * 64, 1));
  }
  p.chunk_vertices = std::max<std::size_t>(p.chunk_vertices, 1);
  p.chunk_faces = std::max<std::size_t>(1, static_cast<std::size_t>(double(p.chunk_vertices) * faces_per_vertex));
  p.estimate_mb = (kFixedBytes + resident + double(std::min<std::size_t>(p.gather_bytes, std::size_t(24.0 * n))) +
                   3.0 * double(p.group_bytes) + double(p.chunk_vertices) * kChunkVertexBytes +
                   double(p.chunk_faces) * kChunkFaceBytes) /
                  kMB;
  return p;
}

bool use_chunks(const GarmentSize&, const ChunkOptions& o, double in_memory_mb) {
  if (o.chunk_vertices > 0) return true;
  const double budget = o.memory_budget > 0 ? double(o.memory_budget) / kMB : physical_memory_mb();
  return budget > 0.0 && in_memory_mb > budget;
}

}  // namespace refit
