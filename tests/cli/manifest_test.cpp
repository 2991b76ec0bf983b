// `refit resize --to-list MANIFEST --shard I/N`: the manifest's bodies to their
// outputs, and N shards (a Slurm job array, a Kubernetes indexed job) that cover
// the manifest exactly once.
#include "mannequin/mannequin.hpp"
#include "support/test_support.hpp"

#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>

namespace refit {
namespace {

namespace fs = std::filesystem;
using test::run_cli;

// Body A, a small dress, and bodies B1..Bn of growing hips, with a manifest that
// names each output (a header, a comment, a blank line and quoting included).
struct Batch {
  test::TempDir dir;
  std::string a, garment;
  std::vector<std::string> outputs;  // in manifest order
  explicit Batch(int bodies) {
    mannequin::BodyParams pa;
    mannequin::GarmentParams g;
    g.target_vertices = 1500;
    a = dir.file("A.obj");
    garment = dir.file("dress.obj");
    write_body_obj(a, mannequin::make_body(pa));
    write_garment_obj(garment, mannequin::make_garment(pa, g));
    std::string csv = "body,output,name\n# customers of the week\n\n";
    for (int i = 1; i <= bodies; ++i) {
      mannequin::BodyParams pb;
      pb.hip = 96 + 2 * i;
      // Appends, not "B" + to_string(i): GCC 12's false -Wrestrict (bug 105329).
      std::string body = "B", out = "out/customer ";  // relative to the manifest
      (body += std::to_string(i)) += ".obj";
      (out += std::to_string(i)) += ".obj";
      write_body_obj(dir.file(body), mannequin::make_body(pb));
      ((((csv += body) += ",\"") += out) += "\",customer") += std::to_string(i) + "\n";
      outputs.push_back(dir.file(out));
    }
    test::write_text(dir.file("manifest.csv"), csv);
  }
  std::string resize(const std::string& extra) const {
    return "resize --quiet --stage warp --garment '" + garment + "' --from '" + a + "' --to-list '" +
           dir.file("manifest.csv") + "' " + extra;
  }
};

TEST(Manifest, ShardsCoverTheManifestExactlyOnce) {
  const Batch b(5);
  const int n = 3;
  std::map<std::string, int> written;  // output -> how many shards wrote it
  for (int i = 0; i < n; ++i) {
    const std::string report = b.dir.file("shard" + std::to_string(i) + ".json");
    const auto r = run_cli(b.resize("--shard " + std::to_string(i) + "/" + std::to_string(n) + " --report '" + report + "'"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto doc = nlohmann::json::parse(test::read_text(report));
    for (const auto& body : doc["bodies"]) ++written[body["output"].get<std::string>()];
  }
  ASSERT_EQ(written.size(), b.outputs.size());
  for (const std::string& out : b.outputs) {
    EXPECT_EQ(written[out], 1) << out;
    EXPECT_TRUE(fs::exists(out)) << out;
  }
  // The shards' files are those of one run over the whole manifest.
  const std::vector<std::string> sharded = [&] {
    std::vector<std::string> t;
    for (const std::string& out : b.outputs) t.push_back(test::read_text(out));
    return t;
  }();
  fs::remove_all(b.dir.file("out"));
  const auto whole = run_cli(b.resize(""));
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  for (std::size_t k = 0; k < b.outputs.size(); ++k) EXPECT_EQ(test::read_text(b.outputs[k]), sharded[k]) << k;
}

TEST(Manifest, MoreShardsThanBodiesLeavesSomeEmpty) {
  const Batch b(2);
  std::map<std::string, int> written;
  int empty = 0;
  for (int i = 0; i < 4; ++i) {
    const std::string report = b.dir.file("shard" + std::to_string(i) + ".json");
    const auto r = run_cli(b.resize("--shard " + std::to_string(i) + "/4 --report '" + report + "'"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    if (!fs::exists(report)) {  // an empty shard does nothing, writes nothing
      ++empty;
      continue;
    }
    const auto doc = nlohmann::json::parse(test::read_text(report));
    for (const auto& body : doc["bodies"]) ++written[body["output"].get<std::string>()];
  }
  EXPECT_EQ(empty, 2);
  ASSERT_EQ(written.size(), 2u);
  for (const std::string& out : b.outputs) EXPECT_EQ(written[out], 1) << out;
}

TEST(Manifest, BadManifestOrShardNamesTheProblem) {
  const Batch b(1);
  const std::string m = b.dir.file("manifest.csv");
  test::write_text(m, "body,output\nB1.obj\n");
  auto r = run_cli(b.resize(""));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(m + ":2: expected body,output[,name], found 1 fields"), std::string::npos) << r.err;
  test::write_text(m, "B1.obj,o.obj\nB1.obj,o.obj\n");
  r = run_cli(b.resize(""));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(m + ":2: output o.obj appears twice"), std::string::npos) << r.err;
  r = run_cli(b.resize("--shard 2/2"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--shard"), std::string::npos) << r.err;
  r = run_cli(b.resize("--out x.obj"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--to-list names the bodies"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(b.dir.file("o.obj")));
}

}  // namespace
}  // namespace refit
