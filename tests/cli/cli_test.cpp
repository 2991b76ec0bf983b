// The command line is a contract scripts depend on: outputs, reports, exit
// codes, and bad input that leaves nothing behind.
#include "cli/cli_case.hpp"
#include "mannequin/mannequin.hpp"
#include "support/test_support.hpp"

#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace refit {
namespace {

namespace fs = std::filesystem;
using test::Case;
using test::files_in;
using test::run_cli;

TEST(Cli, ResizeWritesOutputAndReport) {
  const Case c;
  const std::string out = c.dir.file("out.obj"), rep = c.dir.file("r.json");
  const auto r = run_cli(c.resize(out, "--features '" + c.features + "' --report '" + rep + "'"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Garment g = read_garment_obj(out);
  EXPECT_EQ(g.vertex_count(), read_garment_obj(c.garment).vertex_count());
  const auto j = nlohmann::json::parse(test::read_text(rep));
  for (const char* key : {"version", "garment", "timings_ms", "peak_memory_mb", "warnings", "features", "surface"})
    EXPECT_TRUE(j.contains(key)) << key;
  for (const char* key : {"vertices", "faces", "lines", "points"}) EXPECT_TRUE(j["garment"].contains(key)) << key;
  for (const char* key : {"load", "warp", "write", "total", "features", "surface"})
    EXPECT_TRUE(j["timings_ms"].contains(key)) << key;
  EXPECT_EQ(j["features"].size(), 5u);
  for (const char* key : {"agents", "layers", "voxel", "fixed_body", "fixed_feature", "anchored", "anchored_followed",
                          "iterations", "final_update"})
    EXPECT_TRUE(j["surface"].contains(key)) << key;
}

// main.cpp runs the command again with glibc's malloc on huge pages when
// REFIT_HUGE_PAGES=1 asks for it (off by default: on a virtual machine that hands
// free memory back to its host they cost more than they save), once, keeping what
// GLIBC_TUNABLES held. The report says which.
TEST(Cli, RunsOnHugePagesOnlyWhenAsked) {
  const Case c(1500);
  const std::string out = c.dir.file("out.obj"), rep = c.dir.file("r.json");
  const char* saved = std::getenv("GLIBC_TUNABLES");
  const std::string saved_value = saved ? saved : "";
  const auto run = [&](const char* tunables, const char* asked) {
    if (tunables) setenv("GLIBC_TUNABLES", tunables, 1);
    else unsetenv("GLIBC_TUNABLES");
    if (asked) setenv("REFIT_HUGE_PAGES", asked, 1);
    else unsetenv("REFIT_HUGE_PAGES");
    const auto r = run_cli(c.resize(out, "--report '" + rep + "'"));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(test::read_text(rep)).at("huge_pages").get<bool>();
  };
  EXPECT_FALSE(run(nullptr, nullptr));
  EXPECT_FALSE(run(nullptr, "0"));
  EXPECT_TRUE(run(nullptr, "1"));
  EXPECT_TRUE(run("glibc.malloc.check=0", "1"));  // appended to what was there
  EXPECT_FALSE(run("glibc.malloc.check=0", nullptr));
  unsetenv("REFIT_HUGE_PAGES");
  if (saved) setenv("GLIBC_TUNABLES", saved_value.c_str(), 1);
  else unsetenv("GLIBC_TUNABLES");
}

TEST(Cli, TheReportSpeaksOfTheWrittenGarment) {
  // The feature figures of the report are those of the file written (after the
  // collision step), so `refit compare` on that file gives the same numbers.
  const Case c;
  const std::string out = c.dir.file("out.obj"), rep = c.dir.file("r.json"), scored = c.dir.file("c.json");
  ASSERT_EQ(run_cli(c.resize(out, "--features '" + c.features + "' --report '" + rep + "'")).exit_code, 0);
  const auto cmp = run_cli("compare --garment '" + c.garment + "' --from '" + c.a + "' --to '" + c.b + "' --result '" + out +
                           "' --features '" + c.features + "' --report '" + scored + "'");
  ASSERT_EQ(cmp.exit_code, 0) << cmp.err;
  const auto j = nlohmann::json::parse(test::read_text(rep));
  const auto k = nlohmann::json::parse(test::read_text(scored));
  ASSERT_TRUE(j["surface"].contains("feature_gap_written"));
  std::size_t matched = 0;
  for (const auto& f : j["features"])
    for (const auto& g : k["features"])
      if (g["name"] == f["name"]) {
        ++matched;
        const double written = f["shape_error_output"], compared = g["result"]["shape_error"];
        EXPECT_NEAR(written, compared, 1e-9 * (1.0 + compared)) << f["name"];
        EXPECT_TRUE(f.contains("shape_error_output_before_collision")) << f["name"];
        EXPECT_LE(double(f["gap_output"]), double(j["surface"]["feature_gap_written"])) << f["name"];
      }
  EXPECT_EQ(matched, k["features"].size());
}

TEST(Cli, LayersAreReportedAndNoLayersGivesThePapersSampling) {
  const Case c(8000, true);  // the dress over a slip
  const std::string feats = "--features '" + c.features + "' ";
  const std::string with = c.dir.file("with.obj"), without = c.dir.file("without.obj");
  const std::string rw = c.dir.file("with.json"), rn = c.dir.file("without.json");
  ASSERT_EQ(run_cli(c.resize(with, feats + "--report '" + rw + "'")).exit_code, 0);
  ASSERT_EQ(run_cli(c.resize(without, feats + "--no-layers --report '" + rn + "'")).exit_code, 0);
  const auto jw = nlohmann::json::parse(test::read_text(rw)), jn = nlohmann::json::parse(test::read_text(rn));
  EXPECT_EQ(jw["surface"]["layers"], 2);
  EXPECT_EQ(jn["surface"]["layers"], 0);
  EXPECT_GT(jw["surface"]["agents"].get<std::size_t>(), jn["surface"]["agents"].get<std::size_t>());
  EXPECT_GT((read_garment_obj(with).positions - read_garment_obj(without).positions).cwiseAbs().maxCoeff(), 1e-3);
}

TEST(Cli, OneAndTwoThreadsWriteIdenticalBytes) {
  const Case c;
  const std::string one = c.dir.file("one.obj"), two = c.dir.file("two.obj");
  const std::string feats = "--features '" + c.features + "' ";
  ASSERT_EQ(run_cli(c.resize(one, feats + "--threads 1")).exit_code, 0);
  ASSERT_EQ(run_cli(c.resize(two, feats + "--threads 2")).exit_code, 0);
  EXPECT_EQ(test::read_text(one), test::read_text(two));
}

TEST(Cli, PaperVariantsRunAndChangeTheResult) {
  // The paper's own choices, kept as options beside ours: each runs, writes every
  // vertex, and gives a different garment than the default.
  const Case c;
  const std::string feats = "--features '" + c.features + "' ";
  const std::string ours = c.dir.file("ours.obj");
  ASSERT_EQ(run_cli(c.resize(ours, feats)).exit_code, 0);
  const Garment base = read_garment_obj(ours);
  for (const char* flag : {"--method paper", "--paper-surface", "--paper-closeness", "--encode-on-warped", "--plain-sweeps",
                           "--feature-zone 0"}) {
    std::string name = flag + 2;
    std::replace(name.begin(), name.end(), ' ', '_');
    const std::string out = c.dir.file(name + ".obj");
    const auto r = run_cli(c.resize(out, feats + flag));
    ASSERT_EQ(r.exit_code, 0) << flag << ": " << r.err;
    const Garment g = read_garment_obj(out);
    ASSERT_EQ(g.vertex_count(), base.vertex_count()) << flag;
    EXPECT_TRUE(g.positions.allFinite()) << flag;
    EXPECT_GT((g.positions - base.positions).cwiseAbs().maxCoeff(), 1e-3) << flag;
  }
}

TEST(Cli, SnapRemainderReachesTheSnap) {
  // The demo dress's faces are fine against the snap's kernel, so the later
  // passes' narrowed kernel (the default, 0.5) gives another garment than the
  // whole kernel (1); both pass through the curves.
  const Case c;
  const std::string feats = "--features '" + c.features + "' ";
  const std::string half = c.dir.file("half.obj"), whole = c.dir.file("whole.obj");
  const std::string half_report = c.dir.file("half.json"), whole_report = c.dir.file("whole.json");
  ASSERT_EQ(run_cli(c.resize(half, feats + "--report '" + half_report + "'")).exit_code, 0);
  ASSERT_EQ(run_cli(c.resize(whole, feats + "--snap-remainder 1 --report '" + whole_report + "'")).exit_code, 0);
  EXPECT_NE(test::read_text(half), test::read_text(whole));
  for (const std::string& r : {half_report, whole_report}) {
    const auto report = nlohmann::json::parse(test::read_text(r));
    EXPECT_LT(report.at("surface").at("feature_gap").get<double>(), 0.05) << r;
  }
}

TEST(Cli, MethodPaperIsEveryPaperSwitchAtOnce) {
  // The profile is a name for the switches, not a code path of its own: the same
  // bytes as all of them given one by one, and an explicit --symmetry still wins.
  const Case c;
  const std::string feats = "--features '" + c.features + "' ";
  const std::string profile = c.dir.file("profile.obj"), switches = c.dir.file("switches.obj");
  const std::string mirrored = c.dir.file("mirrored.obj");
  ASSERT_EQ(run_cli(c.resize(profile, feats + "--method paper")).exit_code, 0);
  ASSERT_EQ(run_cli(c.resize(switches, feats + "--paper-closeness --ordered-features --paper-surface --encode-on-warped "
                                               "--plain-sweeps --symmetry none --no-collision")).exit_code, 0);
  EXPECT_EQ(test::read_text(profile), test::read_text(switches));
  ASSERT_EQ(run_cli(c.resize(mirrored, feats + "--method paper --symmetry x")).exit_code, 0);
  EXPECT_NE(test::read_text(profile), test::read_text(mirrored));
  const auto bad = run_cli(c.resize(c.dir.file("bad.obj"), "--method papr"));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--method"), std::string::npos) << bad.err;
}

TEST(Cli, SameBodyGivesTheSameGarment) {
  const Case c;
  const std::string out = c.dir.file("out.obj");
  const auto r = run_cli("resize --quiet --no-collision --garment '" + c.garment + "' --from '" + c.a + "' --to '" + c.a +
                         "' --out '" + out + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Garment in = read_garment_obj(c.garment), res = read_garment_obj(out);
  EXPECT_LE((res.positions - in.positions).cwiseAbs().maxCoeff(), 1e-6 * in.positions.cwiseAbs().maxCoeff());
}

TEST(Cli, ManyBodiesSkipTheBadOneAndWriteTheOthers) {
  const Case c;
  const std::string bad = c.dir.file("bad.obj");
  test::write_text(bad, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const std::string dir = c.dir.file("out");
  const auto r = run_cli("resize --quiet --stage warp --garment '" + c.garment + "' --from '" + c.a + "' --to '" + c.b +
                         "' '" + bad + "' '" + c.a + "' --out-dir '" + dir + "' --report '" + c.dir.file("r.json") + "'");
  EXPECT_EQ(r.exit_code, 4);
  EXPECT_NE(r.err.find("bad.obj"), std::string::npos) << r.err;
  EXPECT_EQ(files_in(dir), (std::vector<std::string>{"A.obj", "B.obj"}));
  const auto j = nlohmann::json::parse(test::read_text(c.dir.file("r.json")));
  EXPECT_EQ(j["bodies"].size(), 3u);
}

// Each body's timings are what its total spent: the binding, made once, is in
// the first body's report only, and a later body's load is reading its body.
TEST(Cli, ManyBodiesReportTheBindingOnce) {
  const Case c;
  const std::string dir = c.dir.file("out");
  const auto r = run_cli("resize --quiet --no-collision --garment '" + c.garment + "' --from '" + c.a + "' --to '" +
                         c.b + "' '" + c.a + "' --out-dir '" + dir + "' --report '" + c.dir.file("r.json") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(test::read_text(c.dir.file("r.json")));
  ASSERT_EQ(j["bodies"].size(), 2u);
  const auto& first = j["bodies"][0]["timings_ms"];
  const auto& second = j["bodies"][1]["timings_ms"];
  EXPECT_TRUE(first.contains("bind"));
  EXPECT_FALSE(second.contains("bind"));
  for (const auto* t : {&first, &second}) {
    double stages = 0.0;  // the stages a body spent add up to no more than its total
    for (const char* key : {"load", "warp", "features", "surface", "write"}) stages += t->value(key, 0.0);
    if (t->contains("bind"))
      for (const auto& [name, ms] : t->at("bind").items()) stages += ms.get<double>();
    EXPECT_LE(stages, t->value("total", 0.0) * 1.01 + 1.0) << t->dump();
  }
}

struct BadInput {
  std::string name, file_text, which, expect;  // which: garment, from, to, features
};

void PrintTo(const BadInput& p, std::ostream* os) { *os << p.name; }

class CliBadInput : public ::testing::TestWithParam<BadInput> {};

TEST_P(CliBadInput, OneClearLineNonZeroExitNoOutput) {
  const BadInput& p = GetParam();
  const Case c(2000);
  std::string garment = c.garment, from = c.a, to = c.b, features = c.features;
  const std::string bad = c.dir.file("bad_" + p.which + (p.which == "features" ? ".json" : ".obj"));
  if (p.file_text != "<missing>") test::write_text(bad, p.file_text);
  (p.which == "garment" ? garment : p.which == "from" ? from : p.which == "to" ? to : features) = bad;
  const fs::path out_dir = c.dir.path() / "out";
  fs::create_directories(out_dir);
  const std::string out = (out_dir / "out.obj").string();
  const auto r = run_cli("resize --quiet --garment '" + garment + "' --from '" + from + "' --to '" + to + "' --features '" +
                         features + "' --out '" + out + "' --report '" + (out_dir / "r.json").string() + "'");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(bad), std::string::npos) << "message must name the file: " << r.err;
  EXPECT_NE(r.err.find(p.expect), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
  EXPECT_TRUE(files_in(out_dir).empty()) << "no output may be left behind";
}

INSTANTIATE_TEST_SUITE_P(
    Cases, CliBadInput,
    ::testing::Values(
        BadInput{"missing_garment", "<missing>", "garment", "cannot"},
        BadInput{"malformed_line", "v 0 0 0\nv 1 0 0\nv 0 1 zero\nf 1 2 3\n", "garment", ":3:"},
        BadInput{"index_out_of_range", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "garment", ":4:"},
        BadInput{"nan_vertex", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "garment", ":2:"},
        BadInput{"inf_vertex", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n", "garment", ":3:"},
        BadInput{"empty_garment", "# nothing here\n", "garment", "empty"},
        BadInput{"body_other_connectivity", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "to", "correspond"},
        BadInput{"body_malformed", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "from", ":4:"},
        BadInput{"features_not_json", "{ \"features\": [ ", "features", "bad_features.json"},
        BadInput{"features_unknown_kind",
                 R"({"units":"cm","features":[{"name":"x","plane":{"point":[0,0,0],"normal":[0,0,1]},"curve":{"kind":"spiral"},"samples":20}]})",
                 "features", "spiral"},
        BadInput{"features_miss_garment",
                 R"({"units":"cm","features":[{"name":"far","plane":{"point":[0,0,5000],"normal":[0,0,1]},"curve":{"kind":"slice","near":[0,0,5000]},"samples":20}]})",
                 "features", "far"},
        BadInput{"features_bspline_far_in_its_plane",
                 R"({"units":"cm","features":[{"name":"far","plane":{"point":[0,100,0],"normal":[0,1,0]},"curve":{"kind":"bspline","degree":3,"closed":false,"control_points":[[1000,100,0],[1010,100,0],[1020,100,0],[1030,100,5]]},"samples":20}]})",
                 "features", "outside the garment's box"}),
    [](const auto& info) { return info.param.name; });

TEST(Cli, UsageErrorsExitTwoAndHelpDocumentsExitCodes) {
  for (const std::string args : {"", "resize", "resize --no-such-option", "inspect a b c d",
                                 "resize --garment g.obj --from a.obj --to b.obj --out o.obj --threads -1",
                                 "resize --garment g.obj --from a.obj --to b.obj --out o.obj --units furlong",
                                 "resize --garment g.obj --from a.obj --to b.obj --out o.obj --clearance nan",
                                 "resize --garment g.obj --from a.obj --to b.obj --out o.obj --clearance inf",
                                 "resize --garment g.obj --from a.obj --to b.obj --out o.obj --clearance 1e6",
                                 "resize --garment g.obj --from a.obj --to b.obj --out o.obj --snap-remainder 0",
                                 "resize --garment g.obj --from a.obj --to b.obj --out o.obj --snap-remainder 1.5",
                                 "resize --garment g.obj --from a.obj --to b.obj --out o.obj --feature-slide 65",
                                 "resize --garment g.obj --from a.obj --to b.obj --out o.obj --feature-slide -1",
                                 // Number options take finite values only (CLI11's ranges let NaN through).
                                 "resize --garment g.obj --from a.obj --to b.obj --out o.obj --feature-bend nan",
                                 "resize --garment g.obj --from a.obj --to b.obj --out o.obj --near-body-band nan",
                                 "resize --garment g.obj --from a.obj --to b.obj --out o.obj --zone-edge-blend nan",
                                 "resize --garment g.obj --from a.obj --to b.obj --out o.obj --epsilon inf",
                                 "resize --garment g.obj --from a.obj --to b.obj --out o.obj --snap-radius 1e400",
                                 "flatten --garment g.obj --out-dir p --dart-target nan",
                                 "flatten --garment g.obj --out-dir p --seam-tolerance nan",
                                 "flatten --garment g.obj --out-dir p --seam-tolerance -0.1",
                                 "flatten --garment g.obj --out-dir p --seam-tolerance 2"}) {
    SCOPED_TRACE(args);
    EXPECT_EQ(run_cli(args).exit_code, 2);
  }
  const auto help = run_cli("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("Exit codes: 0 ok, 1 bad input, 2 usage, 3 out of resources, 4 some bodies"),
            std::string::npos)
      << help.out;
}

TEST(Cli, InspectCountsTheSoup) {
  test::TempDir dir;
  mannequin::GarmentParams g;
  g.target_vertices = 3000;
  g.soup = true;
  const std::string path = dir.file("soup.obj");
  write_garment_obj(path, mannequin::make_garment({}, g));
  const auto r = run_cli("inspect '" + path + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_GT(j["non_manifold_edges"].get<int>(), 0);
  EXPECT_EQ(j["unreferenced_vertices"].get<int>(), 1);
  EXPECT_EQ(j["lines"].get<int>(), 2);
}

TEST(Cli, DemoWritesItsFiles) {
  test::TempDir dir;
  const auto r = run_cli("demo --quiet --vertices 4000 --out-dir '" + dir.file("demo") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* f : {"body_A.obj", "body_B.obj", "dress_on_A.obj", "dress_features.json", "dress_on_B.obj",
                        "dress_on_B_warp_only.obj", "dress_curves.obj", "report.json"})
    EXPECT_TRUE(fs::exists(dir.path() / "demo" / f)) << f;
  EXPECT_NE(r.out.find("demo output") == std::string::npos ? r.out.find("output:") : 0, std::string::npos);
}

}  // namespace
}  // namespace refit

namespace refit {
namespace {

// Every line that is not `v` or `vn` must come back byte for byte.
std::vector<std::string> non_position_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(start, end - start);
    if (line.rfind("v ", 0) != 0 && line.rfind("vn ", 0) != 0) lines.push_back(line);
    start = end + 1;
  }
  return lines;
}

TEST(CliRoundTrip, SoupKeepsEverythingButPositions) {
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent: real soup round trip skipped";
  test::TempDir dir;
  const std::string in = data + "/garments/dress_soup_on_A_female.obj", out = dir.file("out.obj");
  const auto r = run_cli("resize --quiet --garment '" + in + "' --from '" + data + "/bodies/A_female.obj' --to '" + data +
                         "/bodies/F_heavier.obj' --out '" + out + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string a = test::read_text(in), b = test::read_text(out);
  EXPECT_EQ(non_position_lines(a), non_position_lines(b));
  EXPECT_NE(a, b);
  const Garment g = read_garment_obj(out);
  EXPECT_EQ(g.vertex_count(), 3656u);
  EXPECT_EQ(g.lines.rows(), 3u);
  EXPECT_EQ(g.points.rows(), 2u);
  EXPECT_TRUE(g.positions.allFinite());
}

TEST(CliRoundTrip, ProceduralSoupKeepsLinesPointsAndLooseVertices) {
  const Case c;
  mannequin::GarmentParams g;
  g.target_vertices = 5000;
  g.soup = true;
  const std::string soup = c.dir.file("soup.obj"), out = c.dir.file("out.obj");
  write_garment_obj(soup, mannequin::make_garment({}, g));
  const auto r = run_cli("resize --quiet --garment '" + soup + "' --from '" + c.a + "' --to '" + c.b + "' --out '" + out + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(non_position_lines(test::read_text(soup)), non_position_lines(test::read_text(out)));
}

}  // namespace
}  // namespace refit
