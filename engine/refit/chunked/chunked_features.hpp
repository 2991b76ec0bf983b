#pragma once
// Feature curves on a stored garment (issue 14): what build_feature_curves
// reads of the garment (its box, planes' ranges, slices, boundary loops),
// found by streaming it. A slice only needs the faces its plane cuts: they are
// gathered into a small garment of their own and cut as in memory.
#include <refit/chunked/chunk_plan.hpp>
#include <refit/chunked/garment_store.hpp>
#include <refit/features/feature_curves.hpp>

namespace refit {

/// The FeatureGarment of a stored garment (valid while `g` and `x` live).
FeatureGarment chunked_feature_garment(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan);

}  // namespace refit
