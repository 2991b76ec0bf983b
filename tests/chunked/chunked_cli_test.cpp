// The chunked mode from the command line (issue 14): --chunk-vertices and a
// --memory-budget below the garment's estimate resize in chunks and write what
// the in-memory mode writes, for several bodies into --out-dir; bad sizes and a
// budget even the chunks cannot fit are refused before any work.
#include <refit/chunked/chunk_plan.hpp>
#include <refit/core/error.hpp>
#include <refit/pipeline/input_checks.hpp>

#include "support/test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

namespace refit {
namespace {

using ::testing::HasSubstr;

TEST(ChunkedCli, OutDirWithSeveralBodiesAsInMemory) {
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent: the chunked mode's command-line test skipped";
  test::TempDir dir;
  const std::string base = "resize --garment " + data + "/garments/dress_on_A_female.obj --from " + data +
                           "/bodies/A_female.obj --to " + data + "/bodies/F_heavier.obj " + data +
                           "/bodies/F_thinner.obj --features " + std::string(REFIT_SOURCE_DIR) +
                           "/bench/quality/features/dress.json --no-collision --quiet";
  const test::CommandResult memory = test::run_cli(base + " --out-dir " + dir.file("memory"));
  ASSERT_EQ(memory.exit_code, 0) << memory.err;
  const test::CommandResult chunked =
      test::run_cli(base + " --chunk-vertices 700 --temp-dir " + dir.path().string() + " --out-dir " + dir.file("chunked") +
                    " --report " + dir.file("report.json"));
  ASSERT_EQ(chunked.exit_code, 0) << chunked.err;
  for (const char* body : {"F_heavier.obj", "F_thinner.obj"})
    EXPECT_TRUE(test::read_text(dir.file("memory/") + body) == test::read_text(dir.file("chunked/") + body)) << body;
  const nlohmann::json report = nlohmann::json::parse(test::read_text(dir.file("report.json")));
  ASSERT_EQ(report.at("bodies").size(), 2u);
  EXPECT_EQ(report.at("bodies")[0].at("chunks").at("vertices"), 700);
  // Nothing left in the temporary folder: the chunks' files are anonymous.
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path())) ++entries;
  EXPECT_EQ(entries, 3u);  // memory/, chunked/, report.json
}

TEST(ChunkedCli, BudgetsAboveTheEstimateRunInMemoryAndTooSmallOnesAreRefused) {
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent: the chunked mode's command-line test skipped";
  test::TempDir dir;
  const std::string base = "resize --garment " + data + "/garments/skirt_on_A_female.obj --from " + data +
                           "/bodies/A_female.obj --to " + data + "/bodies/F_heavier.obj --no-collision --quiet ";
  // A budget above the estimate: in memory (no "chunks" in the report).
  ASSERT_EQ(test::run_cli(base + "--memory-budget 4G --out " + dir.file("memory.obj") + " --report " + dir.file("r.json")).exit_code, 0);
  EXPECT_FALSE(nlohmann::json::parse(test::read_text(dir.file("r.json"))).contains("chunks"));
  const test::CommandResult tiny = test::run_cli(base + "--memory-budget 20M --out " + dir.file("tiny.obj"));
  EXPECT_NE(tiny.exit_code, 0);
  EXPECT_THAT(tiny.err, HasSubstr("more than the memory budget of 20 MB"));
  EXPECT_FALSE(std::filesystem::exists(dir.file("tiny.obj")));
  const test::CommandResult bad = test::run_cli(base + "--memory-budget 12parsecs --out " + dir.file("bad.obj"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_THAT(bad.err, HasSubstr("--memory-budget: '12parsecs' is not a size"));
}

TEST(ChunkedCli, TheCollisionStepIsRefusedBeforeAnyWorkNotSkipped) {
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent: the chunked mode's command-line test skipped";
  test::TempDir dir;
  const test::CommandResult r =
      test::run_cli("resize --garment " + data + "/garments/skirt_on_A_female.obj --from " + data + "/bodies/A_female.obj --to " +
                    data + "/bodies/F_heavier.obj --chunk-vertices 100 --out " + dir.file("out.obj"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("the chunked mode does not do the collision step yet (use --no-collision)"));
  EXPECT_THAT(r.err, ::testing::Not(HasSubstr("reading")));  // refused before the garment is read in chunks
  EXPECT_FALSE(std::filesystem::exists(dir.file("out.obj")));
  // A small garment is never counted for the automatic choice; a missing one is left to the reader.
  EXPECT_FALSE(might_exceed_memory(data + "/garments/skirt_on_A_female.obj"));
  EXPECT_FALSE(might_exceed_memory(dir.file("missing.obj")));
}

TEST(ChunkPlan, ChunksAboveTheInMemoryEstimateWithinTheBudget) {
  // The dense dress at 17M vertices (the densified dress of bench/chunked.sh) in 1 GB.
  const GarmentSize dress{2'800'000'000, 17'177'471, 34'340'864};
  ChunkOptions o;
  o.memory_budget = std::size_t(1) << 30;
  const double dress_mb = estimated_memory_mb(dress.vertices, 20000, 26756);
  EXPECT_GT(dress_mb, 1024.0);
  EXPECT_TRUE(use_chunks(dress, o, dress_mb));
  const ChunkPlan p = plan_chunks(dress, o);
  EXPECT_LE(p.estimate_mb, 1024.0);
  EXPECT_GE(p.chunk_vertices, 100000u);
  // The 1M dense dress in 4 GB: in memory.
  o.memory_budget = std::size_t(4) << 30;
  EXPECT_FALSE(use_chunks({143'612'458, 1'074'911, 2'146'304}, o, estimated_memory_mb(1'074'911, 20000, 26756)));
  // Forced, with chunks of 100 vertices.
  o.chunk_vertices = 100;
  EXPECT_TRUE(use_chunks({1000, 10, 10}, o, 31.0));
  EXPECT_EQ(plan_chunks({1000, 10, 10}, o).chunk_vertices, 100u);
  EXPECT_EQ(parse_size("800M", "x"), std::size_t(800) << 20);
  EXPECT_EQ(parse_size("1G", "x"), std::size_t(1) << 30);
  EXPECT_EQ(parse_size("1.5k", "x"), std::size_t(1536));
  EXPECT_THROW(parse_size("-1G", "x"), Error);
  EXPECT_THROW(parse_size("G", "x"), Error);
}

}  // namespace
}  // namespace refit
