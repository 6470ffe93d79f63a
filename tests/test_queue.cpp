// The collapse queue: a sorted first batch plus a heap must pop in exactly the order one heap would,
// through pushes, pops and filters interleaved.
#include <gtest/gtest.h>

#include <functional>
#include <random>

#include "simplify/queue.h"

namespace lodkit::detail {
namespace {

TEST(Queue, BatchQueuePopsInTheOrderOfOneHeap) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> value(0, 999);  // many ties, as zero-cost collapses have
  std::vector<int> first(5000);
  for (int& x : first) x = value(rng);

  QuadHeap<int, std::less<int>> heap;
  for (int x : first) heap.push(x);
  BatchQueue<int, std::less<int>> queue;
  queue.load(first);
  ASSERT_EQ(queue.size(), heap.size());

  for (int step = 0; step < 20000 && !heap.empty(); ++step) {
    const int action = value(rng);
    if (action < 400) {
      const int x = value(rng);
      heap.push(x), queue.push(x);
    } else if (action < 402) {
      const int cut = value(rng);  // drop a band of values, as the stale-entry sweep does
      auto keep = [&](int x) { return x < cut || x > cut + 50; };
      heap.filter(keep), queue.filter(keep);
    } else {
      ASSERT_EQ(queue.top(), heap.top()) << "step " << step;
      ASSERT_EQ(queue.pop(), heap.pop()) << "step " << step;
    }
    ASSERT_EQ(queue.size(), heap.size());
  }
  while (!heap.empty()) ASSERT_EQ(queue.pop(), heap.pop());
  EXPECT_TRUE(queue.empty());
}

TEST(Queue, TakeHandsOverWhatIsLeftAndEmptiesTheQueue) {
  // The lanes hand their queues to the last part this way: nothing lost, nothing popped twice.
  BatchQueue<int, std::less<int>> queue;
  queue.load({5, 3, 9, 1, 7});
  queue.push(4);
  queue.push(0);
  EXPECT_EQ(queue.pop(), 0);
  EXPECT_EQ(queue.pop(), 1);
  std::vector<int> rest = queue.take();
  std::sort(rest.begin(), rest.end());
  EXPECT_EQ(rest, (std::vector<int>{3, 4, 5, 7, 9}));
  EXPECT_TRUE(queue.empty());
  queue.push(2);
  EXPECT_EQ(queue.pop(), 2);
}

}  // namespace
}  // namespace lodkit::detail
