// Large arrays advised for transparent huge pages: the helpers fill and keep a vector exactly as the
// plain calls do, and the kernel marks the advised range for huge pages where the system offers them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <memory>
#include <numeric>
#include <sstream>
#include <string>

#include "core/huge_pages.h"

namespace lodkit::detail {
namespace {

constexpr std::size_t kMiB = std::size_t{1} << 20;

TEST(HugePages, ReserveKeepsTheContentsAndTheOrder) {
  std::vector<std::int64_t> v(1000);
  std::iota(v.begin(), v.end(), -7);
  const std::vector<std::int64_t> before = v;
  reserve_huge(v, 8 * kMiB / sizeof(std::int64_t));
  EXPECT_EQ(v, before);
  EXPECT_GE(v.capacity(), 8 * kMiB / sizeof(std::int64_t));
  // Smaller than the capacity: nothing moves.
  const std::int64_t* data = v.data();
  reserve_huge(v, 10);
  EXPECT_EQ(v.data(), data);
  EXPECT_EQ(v, before);
}

TEST(HugePages, ReserveMovesMoveOnlyElements) {
  std::vector<std::unique_ptr<int>> v;
  for (int i = 0; i < 5; ++i) v.push_back(std::make_unique<int>(i));
  reserve_huge(v, 4 * kMiB / sizeof(void*));
  ASSERT_EQ(v.size(), 5u);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(*v[i], i);
}

TEST(HugePages, AssignAndResizeMatchThePlainCalls) {
  for (const std::size_t n : {std::size_t{0}, std::size_t{3}, 5 * kMiB / sizeof(int) + 17}) {
    std::vector<int> ours{1, 2, 3, 4, 5, 6, 7, 8, 9}, plain = ours;
    assign_huge(ours, n, -1), plain.assign(n, -1);
    EXPECT_EQ(ours, plain) << n;
    std::vector<double> grown{0.5, 1.5}, plain_grown = grown;
    resize_huge(grown, n), plain_grown.resize(n);
    EXPECT_EQ(grown, plain_grown) << n;
    EXPECT_EQ(huge_vector<int>(n, -1), std::vector<int>(n, -1)) << n;
    EXPECT_EQ(huge_vector<double>(n), std::vector<double>(n)) << n;
  }
}

TEST(HugePages, AdviceOnOddRangesIsHarmless) {
  advise_huge_pages(nullptr, 64 * kMiB);
  std::vector<char> small(100, 'x');
  advise_huge_pages(small.data(), small.size());
  advise_huge_pages(small.data() + 1, small.size() - 1);
  EXPECT_EQ(std::count(small.begin(), small.end(), 'x'), 100);
}

// The flags of the mapping that holds address `at`, from /proc/self/smaps ("" if not found).
std::string mapping_flags(const void* at) {
  std::ifstream smaps("/proc/self/smaps");
  const auto address = reinterpret_cast<std::uintptr_t>(at);
  bool inside = false;
  for (std::string line; std::getline(smaps, line);) {
    std::uintptr_t lo = 0, hi = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> lo >> dash >> hi && dash == '-') {
      inside = lo <= address && address < hi;
      continue;
    }
    if (inside && line.rfind("VmFlags:", 0) == 0) return line;
  }
  return "";
}

TEST(HugePages, TheKernelMarksTheAdvisedRange) {
  std::ifstream mode("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string modes;
  std::getline(mode, modes);
  if (modes.find("[madvise]") == std::string::npos && modes.find("[always]") == std::string::npos)
    GTEST_SKIP() << "transparent huge pages are off here: " << modes;
  if (!std::ifstream("/proc/self/smaps")) GTEST_SKIP() << "no /proc/self/smaps to read the mappings from";
  std::vector<std::uint8_t> v;
  resize_huge(v, 16 * kMiB);
  // The first whole 2 MiB page inside the array lies in a mapping flagged "hg" (MADV_HUGEPAGE).
  const auto first = (reinterpret_cast<std::uintptr_t>(v.data()) + 2 * kMiB - 1) & ~(2 * kMiB - 1);
  const std::string flags = mapping_flags(reinterpret_cast<const void*>(first));
  ASSERT_FALSE(flags.empty());
  EXPECT_NE(flags.find(" hg"), std::string::npos) << flags;
  // An array never advised is not.
  std::vector<std::uint8_t> plain(16 * kMiB);
  const auto plain_first = (reinterpret_cast<std::uintptr_t>(plain.data()) + 2 * kMiB - 1) & ~(2 * kMiB - 1);
  EXPECT_EQ(mapping_flags(reinterpret_cast<const void*>(plain_first)).find(" hg"), std::string::npos);
}

}  // namespace
}  // namespace lodkit::detail
