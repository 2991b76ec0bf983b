// What a run may write (issue 17 item 1): a regular file, or the file a symbolic
// link points to; never a directory, device or FIFO, an input of the run or the
// path of another output. Every refusal comes before the work, names the path,
// exits 1 and leaves nothing new or changed.
#include "cli/cli_case.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <fcntl.h>
#include <map>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

extern char** environ;

namespace refit {
namespace {

namespace fs = std::filesystem;
using test::Case;
using test::files_in;
using test::run_cli;

// Every regular file under `dir` with its bytes: a refused run changes none of them.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    files[e.path().string()] = fs::is_regular_file(e.symlink_status()) ? test::read_text(e.path().string())
                                                                        : std::string("<not a regular file>");
  return files;
}

void expect_one_line_naming(const test::CommandResult& r, const std::string& path, const std::string& problem) {
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(r.err.rfind("refit: error: " + path + ": ", 0), 0u) << "must start with the path: " << r.err;
  EXPECT_NE(r.err.find(problem), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
}

TEST(CliOutputs, ASymlinkedOutputReplacesItsTargetAndTheLinkStays) {
  const Case c(2000);
  fs::create_directories(c.dir.path() / "real");
  const std::string target = c.dir.file("real/target.obj"), link = c.dir.file("out.obj");
  test::write_text(target, "old\n");
  fs::create_symlink("real/target.obj", link);  // relative, as `ln -s` makes them
  const std::string dangling = c.dir.file("new.obj");
  fs::create_symlink("real/new.obj", dangling);  // its target does not exist yet

  for (const std::string& out : {link, dangling}) {
    const auto r = run_cli(c.resize(out, "--stage warp"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(fs::is_symlink(fs::symlink_status(out))) << out;
  }
  EXPECT_EQ(fs::read_symlink(link), "real/target.obj");
  EXPECT_EQ(fs::read_symlink(dangling), "real/new.obj");
  EXPECT_EQ(read_garment_obj(target).vertex_count(), read_garment_obj(c.garment).vertex_count());
  EXPECT_EQ(test::read_text(target), test::read_text(c.dir.file("real/new.obj")));
  EXPECT_EQ(files_in(c.dir.path() / "real"), (std::vector<std::string>{"new.obj", "target.obj"}));
  EXPECT_EQ(files_in(c.dir.path()),
            (std::vector<std::string>{"A.obj", "B.obj", "dress.obj", "features.json", "new.obj", "out.obj", "real"}));
}

TEST(CliOutputs, DirectoriesDevicesAndFifosAreRefusedBeforeTheWork) {
  // The garment is unreadable too: an output refused before the work is
  // reported instead of the garment, and nothing is read or written.
  const Case c(2000);
  const std::string broken = c.dir.file("broken.obj");
  test::write_text(broken, "v 0 0 zero\n");
  const std::string fifo = c.dir.file("pipe.obj"), folder = c.dir.file("folder.obj"), to_device = c.dir.file("null.obj");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  fs::create_directories(folder);
  fs::create_symlink("/dev/null", to_device);
  const auto before = snapshot(c.dir.path());
  const std::string run = "resize --quiet --garment '" + broken + "' --from '" + c.a + "' --to '" + c.b + "' ";
  struct Refusal {
    std::string path, problem;
  };
  for (const Refusal& x : {Refusal{fifo, "is a FIFO"}, Refusal{"/dev/null", "is a device"},
                           Refusal{to_device, "is a device"}, Refusal{folder, "is a directory"}}) {
    SCOPED_TRACE(x.path);
    expect_one_line_naming(run_cli(run + "--out '" + x.path + "'"), x.path, x.problem);
    expect_one_line_naming(run_cli(run + "--out '" + c.dir.file("o.obj") + "' --report '" + x.path + "'"), x.path,
                           x.problem);
    struct stat st {};
    ASSERT_EQ(::stat("/dev/null", &st), 0);
    EXPECT_TRUE(S_ISCHR(st.st_mode)) << "/dev/null must stay a device";
  }
  EXPECT_EQ(snapshot(c.dir.path()), before);
  struct stat st {};
  ASSERT_EQ(::stat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
}

TEST(CliOutputs, AnOutputThatIsAnInputIsRefused) {
  const Case c(2000);
  const std::string hard = c.dir.file("hard.obj"), soft = c.dir.file("soft.obj");
  fs::create_hard_link(c.garment, hard);
  fs::create_symlink(c.b, soft);
  const auto before = snapshot(c.dir.path());
  const std::string feats = "--features '" + c.features + "' ";
  struct Clash {
    std::string option, path;
  };
  for (const Clash& x : {Clash{"--out", c.garment}, Clash{"--out", c.a}, Clash{"--out", c.b}, Clash{"--out", c.features},
                         Clash{"--out", hard}, Clash{"--out", soft}, Clash{"--report", c.garment},
                         Clash{"--curves-out", c.features}}) {
    SCOPED_TRACE(x.option + " " + x.path);
    const std::string out = x.option == "--out" ? x.path : c.dir.file("o.obj");
    const std::string extra = x.option == "--out" ? "" : x.option + " '" + x.path + "'";
    expect_one_line_naming(run_cli(c.resize(out, feats + extra)), x.path, "is an input of this run");
  }
  EXPECT_EQ(snapshot(c.dir.path()), before);
}

TEST(CliOutputs, TwoOutputsOnOneFileAreRefused) {
  const Case c(2000);
  const std::string x = c.dir.file("x.out"), feats = "--features '" + c.features + "' ";
  expect_one_line_naming(run_cli(c.resize(x, "--report '" + x + "'")), x, "is also the output");
  expect_one_line_naming(run_cli(c.resize(c.dir.file("o.obj"), feats + "--curves-out '" + x + "' --report '" + x + "'")),
                         x, "is also the output");
  EXPECT_FALSE(fs::exists(x));
  EXPECT_FALSE(fs::exists(c.dir.file("o.obj")));
}

TEST(CliOutputs, OutDirBodiesOfOneNameAreRefusedAndNoFolderIsLeft) {
  const Case c(2000);
  for (const char* sub : {"a", "b"}) {
    fs::create_directories(c.dir.path() / sub);
    fs::copy_file(c.b, c.dir.path() / sub / "F.obj");
  }
  const std::string out_dir = c.dir.file("out");
  const auto r = run_cli("resize --quiet --garment '" + c.garment + "' --from '" + c.a + "' --to '" + c.dir.file("a/F.obj") +
                         "' '" + c.dir.file("b/F.obj") + "' --out-dir '" + out_dir + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--out-dir"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("F.obj"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out_dir));
}

TEST(CliOutputs, OutDirThatIsAFileIsRefused) {
  const Case c(2000);
  const std::string file = c.dir.file("file");
  test::write_text(file, "mine\n");
  const auto r = run_cli("resize --quiet --garment '" + c.garment + "' --from '" + c.a + "' --to '" + c.b + "' '" + c.a +
                         "' --out-dir '" + file + "'");
  expect_one_line_naming(r, file, "is not a folder");
  EXPECT_EQ(test::read_text(file), "mine\n");
}

TEST(CliOutputs, AnUnwritableReportOrCurvesFileLeavesNoGarment) {
  // Found before the work, so no OBJ is written and no --out-dir folder is left.
  const Case c(2000);
  const std::string missing = c.dir.file("missing/r.json"), out = c.dir.file("o.obj"), feats = "--features '" + c.features + "' ";
  expect_one_line_naming(run_cli(c.resize(out, "--report '" + missing + "'")), missing, "does not exist");
  expect_one_line_naming(run_cli(c.resize(out, feats + "--curves-out '" + missing + "'")), missing, "does not exist");
  EXPECT_FALSE(fs::exists(out));
  const std::string out_dir = c.dir.file("new/deeper");
  const auto r = run_cli("resize --quiet --garment '" + c.garment + "' --from '" + c.a + "' --to '" + c.b + "' '" + c.a +
                         "' --out-dir '" + out_dir + "' --report '" + missing + "'");
  expect_one_line_naming(r, missing, "does not exist");
  EXPECT_FALSE(fs::exists(c.dir.file("new")));
}

TEST(CliOutputs, ABatchWritesEveryBodyAndTheReportAtTheEnd) {
  const Case c(2000);
  const std::string out_dir = c.dir.file("out"), report = c.dir.file("r.json");
  const auto r = run_cli("resize --quiet --stage warp --garment '" + c.garment + "' --from '" + c.a + "' --to '" + c.b +
                         "' '" + c.a + "' --out-dir '" + out_dir + "' --report '" + report + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(files_in(out_dir), (std::vector<std::string>{"A.obj", "B.obj"}));
  EXPECT_TRUE(fs::exists(report));
}

TEST(CliOutputs, OtherCommandsCheckTheirOutputsToo) {
  const Case c(2000);
  const auto before = snapshot(c.dir.path());
  const std::string g = c.garment, f = c.features;
  // render: the picture over the garment; features: the curves over the feature
  // file; compare: the report over the result; generate: two outputs on one file.
  expect_one_line_naming(run_cli("render --body '" + c.b + "' --garment '" + g + "' --out '" + g + "'"), g,
                         "is an input of this run");
  expect_one_line_naming(run_cli("render --body '" + c.b + "' --garment '" + g + "' --out /dev/null"), "/dev/null",
                         "is a device");
  expect_one_line_naming(run_cli("features --garment '" + g + "' --features '" + f + "' --out '" + f + "'"), f,
                         "is an input of this run");
  expect_one_line_naming(run_cli("compare --garment '" + g + "' --from '" + c.a + "' --to '" + c.b + "' --result '" + g +
                                 "' --report '" + c.a + "'"),
                         c.a, "is an input of this run");
  const std::string same = c.dir.file("same.obj");
  expect_one_line_naming(run_cli("generate --body-out '" + same + "' --garment-out '" + same + "'"), same,
                         "is also the output");
  expect_one_line_naming(run_cli("demo --quiet --vertices 2000 --out-dir '" + c.a + "'"), c.a, "is not a folder");
  EXPECT_EQ(snapshot(c.dir.path()), before);
}

// Starts `refit args...` without a shell, so that the signal reaches it.
pid_t spawn_cli(const std::vector<std::string>& args) {
  std::vector<std::string> argv_text = {REFIT_CLI_PATH};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& s : argv_text) argv.push_back(s.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  const int failed = posix_spawn(&pid, REFIT_CLI_PATH, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  return failed == 0 ? pid : -1;
}

bool has_temporary(const fs::path& dir) {
  for (const auto& name : files_in(dir))
    if (name.size() > 4 && name.compare(name.size() - 4, 4, ".tmp") == 0) return true;
  return false;
}

TEST(CliOutputs, SigintOrSigtermWhileWritingLeavesNoTemporary) {
  // `generate` writes the body, then makes and writes a large garment; both
  // appear together, so the body's temporary waits while the garment is made.
  // The signal comes once a temporary exists: afterwards none is left, and no output.
  for (int sig : {SIGINT, SIGTERM}) {
    SCOPED_TRACE(sig);
    test::TempDir dir;
    const pid_t pid = spawn_cli({"generate", "--body-out", dir.file("body.obj"), "--garment-out", dir.file("garment.obj"),
                                 "--vertices", "400000"});
    ASSERT_GT(pid, 0);
    const auto start = std::chrono::steady_clock::now();
    while (!has_temporary(dir.path()) && std::chrono::steady_clock::now() - start < std::chrono::seconds(20))
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    const bool caught = has_temporary(dir.path());
    ::kill(pid, sig);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(caught) << "no temporary appeared";
    ASSERT_TRUE(WIFSIGNALED(status)) << "exited with " << WEXITSTATUS(status) << " before the signal";
    EXPECT_EQ(WTERMSIG(status), sig);
    EXPECT_TRUE(files_in(dir.path()).empty()) << files_in(dir.path()).front();
  }
}

}  // namespace
}  // namespace refit
