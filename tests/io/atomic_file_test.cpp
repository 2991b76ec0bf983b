// Output files appear whole or not at all.
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/io/atomic_file.hpp>

#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>

namespace refit {
namespace {

TEST(AtomicFile, PartsLandInOrderWhateverTheThreads) {
  // Many parts of varied sizes (empty ones too), copied in parallel to their offsets.
  std::vector<std::string> parts;
  std::string expected;
  for (int i = 0; i < 300; ++i) {
    parts.push_back(std::string(static_cast<std::size_t>((i * 7919) % 5000), static_cast<char>('a' + i % 26)) +
                    (i % 5 == 0 ? "" : std::to_string(i) + "\n"));
    expected += parts.back();
  }
  test::TempDir dir;
  for (int threads : {1, 2}) {
    const ThreadLimit limit(threads);
    const std::string path = dir.file("parts" + std::to_string(threads) + ".txt");
    write_parts_atomically(path, parts.size(), [&](std::size_t k, std::string& out) { out += parts[k]; });
    EXPECT_EQ(test::read_text(path), expected) << threads;
  }
  // Rewriting replaces the file whole.
  write_parts_atomically(dir.file("parts1.txt"), 1, [](std::size_t, std::string& out) { out += "short\n"; });
  EXPECT_EQ(test::read_text(dir.file("parts1.txt")), "short\n");
}

TEST(AtomicFile, AFormatErrorAfterSomeBatchesLeavesNothing) {
  // Parts are written a batch at a time; a failure in a later batch must not
  // leave the earlier ones behind, nor touch an existing file of that name.
  test::TempDir dir;
  const std::string path = dir.file("out.obj");
  write_parts_atomically(path, 1, [](std::size_t, std::string& out) { out += "old\n"; });
  EXPECT_THROW(write_parts_atomically(path, 1000,
                                      [](std::size_t k, std::string& out) {
                                        if (k == 700) throw Error("format failed");
                                        out += std::string(1000, 'x');
                                      }),
               Error);
  EXPECT_EQ(test::read_text(path), "old\n");
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 1u);
}

TEST(AtomicFile, UnwritablePlaceNamesThePathAndLeavesNothing) {
  test::TempDir dir;
  const std::string path = dir.file("missing-folder") + "/out.obj";
  try {
    write_parts_atomically(path, 1, [](std::size_t, std::string& out) { out += "v 0 0 0\n"; });
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path + ": its folder", 0), 0u) << e.what();
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

}  // namespace
}  // namespace refit

namespace refit {
namespace {

namespace fs = std::filesystem;

void write_text_atomically(const std::string& path, const std::string& text) {
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

TEST(OutputBatch, OutputsAppearOnCommitAndNotBefore) {
  test::TempDir dir;
  const std::string a = dir.file("a.txt"), b = dir.file("b.txt");
  {
    OutputBatch batch;
    write_text_atomically(a, "a\n");
    write_parts_atomically(b, 1, [](std::size_t, std::string& out) { out += "b\n"; });
    EXPECT_FALSE(fs::exists(a));
    EXPECT_FALSE(fs::exists(b));
    batch.commit();
  }
  EXPECT_EQ(test::read_text(a), "a\n");
  EXPECT_EQ(test::read_text(b), "b\n");
  EXPECT_EQ(test::folder_entries(dir.path()), 2u);
}

TEST(OutputBatch, AFailureLeavesNothingNewAndTheOldFilesAlone) {
  test::TempDir dir;
  const std::string a = dir.file("a.txt"), b = dir.file("b.txt");
  write_text_atomically(a, "old\n");
  try {
    OutputBatch batch;
    write_text_atomically(a, "new\n");
    write_text_atomically(b, "new\n");
    throw Error("the third output failed");
  } catch (const Error&) {
  }
  EXPECT_EQ(test::read_text(a), "old\n");
  EXPECT_FALSE(fs::exists(b));
  EXPECT_EQ(test::folder_entries(dir.path()), 1u);
}

TEST(OutputBatch, AnInnerBatchHandsItsOutputsToTheOuterOne) {
  test::TempDir dir;
  const std::string a = dir.file("a.txt"), b = dir.file("b.txt");
  {
    OutputBatch outer;
    {
      OutputBatch inner;
      write_text_atomically(a, "a\n");
      inner.commit();
    }
    {
      OutputBatch skipped;  // not committed: its output goes
      write_text_atomically(b, "b\n");
    }
    EXPECT_FALSE(fs::exists(a));
    outer.commit();
  }
  EXPECT_TRUE(fs::exists(a));
  EXPECT_FALSE(fs::exists(b));
  EXPECT_EQ(test::folder_entries(dir.path()), 1u);
}

TEST(OutputFolder, MadeFoldersGoAgainUnlessKept) {
  test::TempDir dir;
  { const OutputFolder folder(dir.file("x/y/z")); EXPECT_TRUE(fs::is_directory(dir.file("x/y/z"))); }
  EXPECT_FALSE(fs::exists(dir.file("x")));
  {
    OutputFolder folder(dir.file("x/y"));
    folder.keep();
  }
  EXPECT_TRUE(fs::is_directory(dir.file("x/y")));
  test::write_text(dir.file("file"), "mine");
  EXPECT_THROW(OutputFolder(dir.file("file")), Error);
  EXPECT_THROW(OutputFolder(dir.file("file/below")), Error);
  EXPECT_EQ(test::read_text(dir.file("file")), "mine");
}

// A signal while a part is formatted: the process dies of it, and neither the
// temporary being written nor one waiting in a batch is left.
void die_while_writing(const std::string& folder, int sig) {
  remove_temporaries_on_signal();
  OutputBatch batch;
  write_text_atomically(folder + "/staged.txt", "waits for the batch\n");
  write_parts_atomically(folder + "/out.txt", 100, [sig](std::size_t k, std::string& out) {
    out += "part\n";
    if (k == 70) std::raise(sig);
  });
}

TEST(AtomicFileDeathTest, SigintOrSigtermLeavesNoTemporary) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  for (int sig : {SIGINT, SIGTERM}) {
    const test::DeathTestFolder dir;
    EXPECT_EXIT(die_while_writing(dir.path().string(), sig), ::testing::KilledBySignal(sig), "");
    EXPECT_EQ(test::folder_entries(dir.path()), 0u) << sig;
  }
}

}  // namespace
}  // namespace refit
