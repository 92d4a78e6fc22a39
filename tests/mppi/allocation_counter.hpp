#pragma once
// The counting global operator new of the test program (tests/mppi/test_no_allocation.cpp):
// while counting_allocations is set, every allocation adds one to allocations_counted.
#include <atomic>

namespace mppi::test {
extern std::atomic<bool> counting_allocations;
extern std::atomic<long> allocations_counted;

// Allocations made by f().
template <class F>
long allocations_in(F&& f) {
  allocations_counted = 0;
  counting_allocations = true;
  f();
  counting_allocations = false;
  return allocations_counted.load();
}
}  // namespace mppi::test
