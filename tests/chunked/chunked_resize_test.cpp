// The chunked mode (issue 14) writes byte for byte what the in-memory mode
// writes, with tiny chunks and with positions gathered from disk or kept in
// memory: the shared dress with its features to two bodies, the multi-layer
// outfit, the polygon soup, and a procedural garment with `vn` normals.
#include <refit/chunked/chunked_resize.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>

#include <mannequin/mannequin.hpp>
#include "support/test_support.hpp"

#include <gtest/gtest.h>

namespace refit {
namespace {

struct Case {
  std::string name, garment, features;
  ResizeOptions options;
};

ResizeOptions options_for(Stage stage, SymmetryMode symmetry = SymmetryMode::Auto) {
  ResizeOptions o;
  o.stage = stage;
  o.symmetry = symmetry;
  o.collision = false;
  return o;
}

// The report's figures (everything but timings) that both modes must agree on.
nlohmann::json figures(nlohmann::json r) {
  r.erase("timings_ms");
  r.erase("chunks");
  r.erase("memory_estimate_mb");
  if (r.contains("surface")) r["surface"].erase("timings_ms");
  return r;
}

void expect_same_outputs(const Case& c, const std::string& from, const std::vector<std::string>& to) {
  test::TempDir dir;
  auto garment = std::make_shared<const Garment>(read_garment_obj(c.garment));
  const std::vector<FeatureSpec> features = c.features.empty() ? std::vector<FeatureSpec>{} : read_feature_file(c.features);
  const GarmentBinding memory(garment, read_body(from), c.options, features, Progress(true));
  std::vector<std::string> expected;
  std::vector<nlohmann::json> reports;
  for (const std::string& b : to) {
    const ResizeResult r = memory.resize(read_body(b), Progress(true));
    write_garment_obj(dir.file("memory.obj"), *garment, r.positions);
    expected.push_back(test::read_text(dir.file("memory.obj")));
    reports.push_back(figures(r.report));
  }
  // Tiny chunks with positions gathered from disk; larger ones with positions in memory.
  for (const auto& [chunk, gather] : {std::pair<std::size_t, std::size_t>{97, 0}, {5000, std::size_t(1) << 30}}) {
      std::string trace = c.name;
      trace += ": chunks of " + std::to_string(chunk);
      trace += ", gather " + std::to_string(gather);
      SCOPED_TRACE(trace);
      ChunkPlan plan;
      plan.chunk_vertices = plan.chunk_faces = chunk;
      plan.group_bytes = 1;
      plan.gather_bytes = gather;
      plan.folder = dir.path();
      ObjStream obj(c.garment, plan.group_bytes);
      auto store = std::make_shared<const GarmentStore>(std::move(obj), plan.folder);
      const ChunkedBinding chunked(store, read_body(from), c.options, features, plan, Progress(true));
      for (std::size_t i = 0; i < to.size(); ++i) {
        const ChunkedResult r = chunked.resize(read_body(to[i]), dir.file("chunked.obj"), Progress(true));
        EXPECT_TRUE(test::read_text(dir.file("chunked.obj")) == expected[i]) << to[i] << ": the written garments differ";
        EXPECT_EQ(figures(r.report), reports[i]) << to[i];
      }
  }
}

TEST(ChunkedResize, SharedGarmentsAsInMemory) {
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent: the chunked mode's real-garment test skipped";
  const std::string src = REFIT_SOURCE_DIR;
  const std::string a = data + "/bodies/A_female.obj";
  const std::vector<std::string> bodies = {data + "/bodies/F_heavier.obj", data + "/bodies/F_thinner.obj"};
  for (const Stage stage : {Stage::Warp, Stage::Features, Stage::Full})
    expect_same_outputs({"dress", data + "/garments/dress_on_A_female.obj", src + "/bench/quality/features/dress.json",
                         options_for(stage)},
                        a, bodies);
  expect_same_outputs({"dress without symmetry", data + "/garments/dress_on_A_female.obj",
                       src + "/bench/quality/features/dress.json", options_for(Stage::Full, SymmetryMode::None)},
                      a, {bodies[0]});
  // On F_thinner the skirt is snapped again after the symmetrisation and that snap
  // is kept (SnapSharedData.TheSnapAfterTheSymmetrisationKeepsTheSkirtSymmetric); on F_heavier it is not.
  expect_same_outputs({"skirt", data + "/garments/skirt_on_A_female.obj", src + "/bench/quality/features/skirt.json",
                       options_for(Stage::Full, SymmetryMode::X)},
                      a, bodies);
  // The outfit to body B, and to body A itself (the input given back byte for byte).
  expect_same_outputs({"outfit", data + "/garments/outfit_dress_jeans_on_A_female.obj", "", options_for(Stage::Full)}, a,
                      {bodies[0], a});
  expect_same_outputs({"soup", data + "/garments/dress_soup_on_A_female.obj", "", options_for(Stage::Full)}, a,
                      {bodies[0]});
}

TEST(ChunkedResize, ProceduralGarmentWithNormalsAsInMemory) {
  test::TempDir dir;
  mannequin::BodyParams body;
  mannequin::GarmentParams p;
  p.target_vertices = 4000;
  p.two_layers = true;
  const Garment g = mannequin::make_garment(body, p);
  // The garment as a file whose faces use `vn` normals (every face corner its vertex's).
  std::string text;
  for (Eigen::Index i = 0; i < g.positions.rows(); ++i)
    text += "v " + std::to_string(g.positions(i, 0)) + " " + std::to_string(g.positions(i, 1)) + " " +
            std::to_string(g.positions(i, 2)) + "\nvn 0 1 0\n";
  for (std::size_t f = 0; f < g.faces.rows(); ++f) {
    text += "f";
    for (Index v : g.faces.row(f)) {
      const std::string i = std::to_string(v + 1);
      (((text += ' ') += i) += "//") += i;
    }
    text += "\n";
  }
  test::write_text(dir.file("g.obj"), text);
  BodyMesh a = mannequin::make_body(body);
  mannequin::BodyParams heavier = body;
  heavier.bust += 6;
  heavier.waist += 8;
  heavier.hip += 6;
  BodyMesh b = mannequin::make_body(heavier);
  write_body_obj(dir.file("a.obj"), a);
  write_body_obj(dir.file("b.obj"), b);
  expect_same_outputs({"procedural", dir.file("g.obj"), "", options_for(Stage::Full)}, dir.file("a.obj"), {dir.file("b.obj")});
}

}  // namespace
}  // namespace refit
