#pragma once
// Counts heap allocations made by the current thread while counting is on (after Drake's
// LimitMalloc). Linking tests/support/allocation_counter.cpp replaces the global operator new.

#include <cstdint>

namespace haptic::test {

/// Allocations counted on this thread since the last reset.
std::uint64_t allocations();
void reset_allocations();

/// Counts allocations on this thread while alive.
class CountAllocations {
 public:
  CountAllocations();
  ~CountAllocations();
  CountAllocations(const CountAllocations&) = delete;
  CountAllocations& operator=(const CountAllocations&) = delete;
};

}  // namespace haptic::test
