#pragma once
// The surface step's garment passes in chunks (issue 14): what
// SurfaceBinding::bind finds on the whole garment -- the voxel size, the
// layers, the agents -- found by streaming a GarmentStore, with the same
// results, so that SurfaceBinding::bind_agents makes the same binding.
#include <refit/chunked/chunk_plan.hpp>
#include <refit/chunked/garment_store.hpp>
#include <refit/surface/surface.hpp>

#include <cstdint>
#include <utility>
#include <vector>

namespace refit {

/// surface_measure for a stored garment: the face area and the `l` lines' length.
std::pair<double, double> chunked_surface_measure(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan);

/// surface_voxel for a stored garment of that measure.
double chunked_surface_voxel(const GarmentStore& g, std::pair<double, double> measure, const SurfaceOptions& options);

/// garment_layers for a stored garment (per vertex; in memory, 4 bytes per vertex).
std::vector<std::uint32_t> chunked_layers(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan,
                                          double min_area, double join_distance);

/// select_agents for a stored garment (`vertex_layer`: per vertex, empty: all 0).
GarmentAgents chunked_select_agents(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan,
                                    const VoxelGrid& grid, const std::vector<VoxelLayer>& skip,
                                    const std::vector<std::uint32_t>& vertex_layer);

/// SurfaceBinding::bind's garment part for a stored garment; the layers per
/// vertex go to `vertex_layer` (empty without layers).
SurfaceGarmentPart chunked_surface_part(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan,
                                        const Points& features, const SurfaceOptions& options,
                                        const SurfaceAttachment& feature_attachment,
                                        std::vector<std::uint32_t>& vertex_layer);

}  // namespace refit
