// Output files appear whole or not at all.
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/io/atomic_file.hpp>

#include "support/test_support.hpp"

#include <gtest/gtest.h>

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
