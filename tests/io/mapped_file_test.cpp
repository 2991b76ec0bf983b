// Garment files mapped instead of copied (map_input_files): the same garment,
// a file changed in place refused, a file that shrinks ends the process with one
// line and no temporary left.
#include <refit/core/error.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/file_bytes.hpp>
#include <refit/io/mapped_file.hpp>
#include <refit/io/obj_garment.hpp>

#include "support/test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <string>

namespace refit {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

std::string numbered_strip(int n) {
  std::string text = "# strip\n";
  for (int i = 0; i < n; ++i) text += "v " + std::to_string(i) + " 0.25 " + std::to_string(i % 7) + ".5\n";
  for (int i = 1; i + 2 <= n; i += 2) text += "f " + std::to_string(i) + " " + std::to_string(i + 1) + " " + std::to_string(i + 2) + "\n";
  return text;
}

TEST(MappedFile, AReleasedGarmentIsReadAsFromACopy) {
  ASSERT_TRUE(map_input_files());
  ASSERT_TRUE(input_files_mapped());
  const std::string text = numbered_strip(50000);
  test::TempDir dir;
  const std::string in = dir.file("in.obj");
  test::write_text(in, text);
  EXPECT_TRUE(read_file_bytes(in, true).view() == text);
  EXPECT_TRUE(read_file_bytes(in, false).view() == text);
  const Garment kept = read_garment_obj(in), released = read_garment_obj(in, SourceText::released);
  EXPECT_TRUE((released.positions.array() == kept.positions.array()).all());
  EXPECT_EQ(released.faces.indices.size(), kept.faces.indices.size());
  Points moved = kept.positions;
  moved.col(2).array() += 0.125;
  write_garment_obj(dir.file("a.obj"), kept, moved);
  write_garment_obj(dir.file("b.obj"), released, moved);
  EXPECT_TRUE(test::read_text(dir.file("a.obj")) == test::read_text(dir.file("b.obj")));
  // An empty file cannot be mapped: read, and refused as a garment as ever.
  test::write_text(dir.file("empty.obj"), "");
  EXPECT_EQ(read_file_bytes(dir.file("empty.obj"), true).size(), 0u);
  EXPECT_THROW(read_garment_obj(dir.file("empty.obj"), SourceText::released), Error);
}

TEST(MappedFile, AFileChangedInPlaceSinceItWasMappedIsRefused) {
  ASSERT_TRUE(map_input_files());
  test::TempDir dir;
  const std::string in = dir.file("in.obj");
  test::write_text(in, numbered_strip(1000));
  TextBytes bytes = read_file_bytes(in, true);
  EXPECT_NO_THROW(bytes.check_unchanged());
  // The same size, one digit written over, stamped a second later (a write
  // within the clock's tick of the last one keeps its time).
  const int fd = ::open(in.c_str(), O_WRONLY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::pwrite(fd, "9", 1, 12), 1);
  struct stat st {};
  ASSERT_EQ(::fstat(fd, &st), 0);
  struct timespec times[2] = {st.st_atim, st.st_mtim};
  times[1].tv_sec += 1;
  ASSERT_EQ(::futimens(fd, times), 0);
  ::close(fd);
  EXPECT_EQ(bytes.view()[12], '9') << "a mapping shows the change";
  try {
    bytes.check_unchanged();
    ADD_FAILURE() << "no error for a file changed in place";
  } catch (const Error& e) {
    EXPECT_THAT(std::string(e.what()), StartsWith(in + ": "));
    EXPECT_THAT(std::string(e.what()), HasSubstr("changed"));
  }
  // Longer: the size says so.
  TextBytes again = read_file_bytes(in, true);
  test::write_text(in, numbered_strip(1001));
  EXPECT_THROW(again.check_unchanged(), Error);
  // A copy is what was read, whatever the file does after.
  TextBytes copy = read_file_bytes(in, false);
  test::write_text(in, "v 1 2 3\n");
  EXPECT_NO_THROW(copy.check_unchanged());
}

// A mapped input cut short while a part of an output is formatted from it.
void read_past_a_truncated_end(const std::string& folder) {
  map_input_files();
  const std::string in = folder + "/in.obj";
  TextBytes bytes = read_file_bytes(in, true);
  OutputBatch batch;
  write_text_atomically(folder + "/staged.txt", "waits for the batch\n");
  write_parts_atomically(folder + "/out.txt", 100, [&](std::size_t k, std::string& out) {
    out += "part\n";
    if (k != 70) return;
    if (::truncate(in.c_str(), 0) != 0) return;
    out += bytes.view()[bytes.size() - 1];  // past the file's end now
  });
}

TEST(MappedFileDeathTest, AMappedInputThatShrinksEndsTheRunWithOneLineAndNoTemporary) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const test::DeathTestFolder dir;
  const std::string in = dir.file("in.obj");
  test::write_text(in, numbered_strip(20000));
  EXPECT_EXIT(read_past_a_truncated_end(dir.path().string()), ::testing::ExitedWithCode(1),
              "refit: error: .*in.obj: cannot read: the file got shorter while it was being read; nothing written");
  EXPECT_EQ(test::folder_entries(dir.path()), 1u) << "only the input: no output, no temporary";
}

TEST(MappedFileDeathTest, AnotherBusErrorKeepsItsDefaultAction) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        map_input_files();
        ::raise(SIGBUS);
      },
      ::testing::KilledBySignal(SIGBUS), "");
}

}  // namespace
}  // namespace refit
