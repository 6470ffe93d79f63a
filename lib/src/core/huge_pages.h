#pragma once
// Large arrays backed by transparent huge pages where the system offers them.
//
// A 1M-face run touches about 400 MiB of fresh memory. With 4 KiB pages that is over 100,000 page
// faults, and on a virtual machine each costs microseconds: a quarter of the run's wall time on the CI
// machines, where transparent huge pages are given only to memory that asks (THP mode "madvise").
// Asking for them on the arrays of 2 MiB or more cuts their faults 512-fold, and the TLB misses
// with them (docs/benchmarks-log.md, session 60). Allocation itself is unchanged: std::vector and
// Eigen's storage as ever, advised before their first touch.
#include <cstddef>
#include <iterator>
#include <vector>

namespace lodkit::detail {

constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;

/// The capacity to ask for when at least n elements of T are needed: for an array of two huge pages or
/// more, as many as fill its last huge page (less what the allocator keeps in front of a block), so
/// that no page of it is left to ordinary pages; n itself below that.
template <typename T>
std::size_t huge_capacity(std::size_t n) {
  constexpr std::size_t kAllocatorHeader = 64;  // glibc keeps 16 bytes: a margin over that
  const std::size_t bytes = n * sizeof(T);
  if (bytes < 2 * kHugePageBytes) return n;
  const std::size_t whole = (bytes + kAllocatorHeader + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
  return (whole - kAllocatorHeader) / sizeof(T);
}

/// Asks the kernel for transparent huge pages over the 2 MiB pages that [data, data + bytes) touches.
/// Only a hint: nothing happens below 2 MiB, where THP is off, or off Linux; contents are untouched.
void advise_huge_pages(const void* data, std::size_t bytes);

/// v.reserve(n), with the new storage advised for huge pages before anything touches it (what v held
/// is moved there after the advice). Call it before the assign(), resize() or push_back()s that fill a
/// large array.
template <typename T, typename A>
void reserve_huge(std::vector<T, A>& v, std::size_t n) {
  if (n <= v.capacity()) return;
  std::vector<T, A> grown(v.get_allocator());
  grown.reserve(huge_capacity<T>(n));
  advise_huge_pages(grown.data(), grown.capacity() * sizeof(T));
  grown.insert(grown.end(), std::make_move_iterator(v.begin()), std::make_move_iterator(v.end()));
  v.swap(grown);
}

/// v.assign(n, value) into storage advised for huge pages.
template <typename T, typename A>
void assign_huge(std::vector<T, A>& v, std::size_t n, const T& value) {
  if (n > v.capacity()) v.clear();  // nothing to carry over into the new block
  reserve_huge(v, n);
  v.assign(n, value);
}

/// n copies of value in storage advised for huge pages.
template <typename T>
std::vector<T> huge_vector(std::size_t n, const T& value) {
  std::vector<T> v;
  assign_huge(v, n, value);
  return v;
}

/// v.resize(n) into storage advised for huge pages (new elements value-initialised).
template <typename T, typename A>
void resize_huge(std::vector<T, A>& v, std::size_t n) {
  reserve_huge(v, n);
  v.resize(n);
}

/// n value-initialised elements in storage advised for huge pages.
template <typename T>
std::vector<T> huge_vector(std::size_t n) {
  std::vector<T> v;
  resize_huge(v, n);
  return v;
}

}  // namespace lodkit::detail
