// The size of the CUDA backend's canonical sorts (cuda/sort_size.h), host arithmetic checked
// without a device: a blocking query sorts only the pairs it found (a caller's large capacity
// costs nothing), none when they did not fit; a stream-ordered one sorts its whole capacity.
#include <gtest/gtest.h>

#include <cstdint>

#include "cuda/sort_size.h"

namespace minkq::cuda {
namespace {

TEST(SortSize, a_blocking_sort_covers_the_count_not_the_capacity) {
  EXPECT_EQ(blocking_sort_keys(10000, 1000000), 10000u);  // 1M reserved for 10k contacts
  EXPECT_EQ(blocking_sort_keys(0, 1000000), 0u);
  EXPECT_EQ(blocking_sort_keys(7, 7), 7u);  // exactly enough room
  EXPECT_EQ(blocking_sort_keys(uint64_t(1) << 40, ~uint64_t(0)), uint64_t(1) << 40);
}

TEST(SortSize, a_blocking_sort_of_pairs_that_did_not_fit_sorts_nothing) {
  EXPECT_EQ(blocking_sort_keys(8, 7), 0u);  // nothing was written: the caller learns the count
  EXPECT_EQ(blocking_sort_keys(1000000, 0), 0u);
}

TEST(SortSize, a_stream_ordered_sort_covers_the_capacity) {
  EXPECT_EQ(async_sort_keys(1000000), 1000000u);  // the count is on the device only
  EXPECT_EQ(async_sort_keys(0), 0u);
}

}  // namespace
}  // namespace minkq::cuda
