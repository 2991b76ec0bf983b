// Lists built in parallel blocks come out as a serial walk makes them.
#include <refit/core/parallel.hpp>

#include <gtest/gtest.h>

namespace refit {
namespace {

// Index i appends i % 7 copies of i: uneven lists, some blocks empty.
std::vector<std::size_t> listed(std::size_t n, std::size_t block) {
  return gather_in_blocks<std::size_t>(n, block, [&](std::size_t first, std::size_t last, std::vector<std::size_t>& out) {
    for (std::size_t i = first; i < last; ++i)
      if (i % 1000 >= 300) out.insert(out.end(), i % 7, i);
  });
}

std::vector<std::size_t> walked(std::size_t n) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < n; ++i)
    if (i % 1000 >= 300) out.insert(out.end(), i % 7, i);
  return out;
}

TEST(GatherInBlocks, JoinsTheBlocksInOrderWhateverTheThreads) {
  const std::size_t n = 100'003;  // not a multiple of the block
  std::vector<std::size_t> one, two;
  {
    const ThreadLimit limit(1);
    one = listed(n, 97);
  }
  {
    const ThreadLimit limit(2);
    two = listed(n, 97);
  }
  EXPECT_EQ(one, walked(n));
  EXPECT_EQ(two, walked(n));
}

TEST(GatherInBlocks, CoversEveryIndexOnceInBlocksOfTheSize) {
  std::vector<std::pair<std::size_t, std::size_t>> seen = gather_in_blocks<std::pair<std::size_t, std::size_t>>(
      10, 4, [](std::size_t first, std::size_t last, std::vector<std::pair<std::size_t, std::size_t>>& out) {
        out.emplace_back(first, last);
      });
  EXPECT_EQ(seen, (std::vector<std::pair<std::size_t, std::size_t>>{{0, 4}, {4, 8}, {8, 10}}));
  EXPECT_TRUE(listed(0, 16).empty());
}

}  // namespace
}  // namespace refit
