#pragma once
// The resize pipeline in chunks (issue 14, out-of-core): the garment stays on
// disk (GarmentStore) and every stage streams it a chunk of vertices or faces
// at a time; only the bodies, the agents, the feature curves, the current
// chunk and a few bytes per vertex are in memory. The written garment is
// byte-identical to GarmentBinding's (docs/chunked.md says how each stage
// gets there). Units, threads and errors as GarmentBinding's
// (pipeline/resize.hpp); results are the same bits for any thread count and
// any chunk size. The collision step and the metrics are refused
// (check_chunked_options), before any work.
#include <refit/chunked/chunk_plan.hpp>
#include <refit/chunked/garment_store.hpp>
#include <refit/pipeline/resize.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace refit {

struct ChunkedResult {
  FeatureResult features;  // per feature curve: original, warped, optimised samples
  nlohmann::json report;   // as ResizeResult's
  std::vector<std::string> warnings;
  ObjWriteReport written;  // what writing the garment said (write_garment_obj's report)
};

/// Throws refit::Error when `options` ask for what the chunked mode does not do
/// (the collision step, --metrics): checked before any work.
void check_chunked_options(const ResizeOptions& options);

/// GarmentBinding for a garment in a GarmentStore.
class ChunkedBinding {
 public:
  /// Throws refit::Error as GarmentBinding does.
  ChunkedBinding(std::shared_ptr<const GarmentStore> garment, BodyMesh body_a, ResizeOptions options,
                 std::vector<FeatureSpec> features, ChunkPlan plan, const Progress& progress = Progress(true));
  ~ChunkedBinding();

  /// Resizes the garment to body B and writes it to `out` (atomically, as
  /// write_garment_obj: with the outputs of an OutputBatch when one is open).
  ChunkedResult resize(const BodyMesh& body_b, const std::string& out, const Progress& progress = Progress(true)) const;

  const GarmentStore& garment() const { return *store_; }
  const ChunkPlan& plan() const { return plan_; }
  const nlohmann::json& bind_report() const { return bind_report_; }

 private:
  struct Bound;  // what the stages bound (chunked_resize.cpp)
  std::shared_ptr<const GarmentStore> store_;
  ResizeOptions options_;
  ChunkPlan plan_;
  ReferenceBody body_a_;
  std::unique_ptr<Bound> bound_;
  nlohmann::json bind_report_;
};

}  // namespace refit
