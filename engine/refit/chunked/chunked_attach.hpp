#pragma once
// Points attached to a stored garment's surface (issue 14): GarmentLocator's
// closest element (the first in file order among equally close ones), found
// block by block of elements, so the attachment is the same.
#include <refit/attach/attachment.hpp>
#include <refit/chunked/chunk_plan.hpp>
#include <refit/chunked/garment_store.hpp>

namespace refit {

/// attach_points(garment, samples) for a stored garment: each block of faces,
/// lines and points gets a GarmentLocator of its own, and each sample keeps the
/// closest element over the blocks (ties to the earlier element). For a few
/// thousand samples (the feature curves): every sample meets every block.
SurfaceAttachment chunked_attach(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan, const Points& samples);

}  // namespace refit
