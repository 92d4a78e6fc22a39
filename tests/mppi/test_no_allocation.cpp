// Controller::step() must not allocate: a counting replacement of the global operator new
// (in force for the whole test program; it only counts while `counting` is set).
#include <atomic>
#include <catch2/catch.hpp>
#include <cstddef>
#include <cstdlib>
#include <new>

#include "mppi/controller.hpp"
#include "tests/mppi/linear_system.hpp"

#include "tests/mppi/allocation_counter.hpp"

namespace mppi::test {
std::atomic<bool> counting_allocations{false};
std::atomic<long> allocations_counted{0};
}  // namespace mppi::test

namespace {
std::atomic<bool>& counting = mppi::test::counting_allocations;
std::atomic<long>& allocations = mppi::test::allocations_counted;
}  // namespace

// Every replaceable allocation function is replaced (plain, array, nothrow, aligned, sized), all
// on malloc/aligned_alloc and free, so that any new/delete pair matches under AddressSanitizer.
namespace {
void* counted_alloc(std::size_t size, std::size_t alignment) noexcept {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1);
  if (size == 0) size = 1;
  if (alignment <= alignof(std::max_align_t)) return std::malloc(size);
  // aligned_alloc wants a size that is a multiple of the alignment
  return std::aligned_alloc(alignment, (size + alignment - 1) / alignment * alignment);
}
void* counted_alloc_or_throw(std::size_t size, std::size_t alignment) {
  if (void* p = counted_alloc(size, alignment)) return p;
  throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t size) { return counted_alloc_or_throw(size, 0); }
void* operator new[](std::size_t size) { return counted_alloc_or_throw(size, 0); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return counted_alloc(size, 0); }
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return counted_alloc(size, 0); }
void* operator new(std::size_t size, std::align_val_t a) {
  return counted_alloc_or_throw(size, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t size, std::align_val_t a) {
  return counted_alloc_or_throw(size, static_cast<std::size_t>(a));
}
void* operator new(std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept {
  return counted_alloc(size, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept {
  return counted_alloc(size, static_cast<std::size_t>(a));
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }

TEST_CASE("Controller::step allocates nothing", "[core][mppi]") {
  mppi::ControllerOptions o;
  o.num_samples = 500;
  o.horizon = 30;
  o.iterations = 2;
  o.smoothing_window = 5;
  o.noise_std = {0.5f};
  o.control_min = {-5.f};
  o.control_max = {5.f};
  o.safe_control = {0.f};
  o.num_threads = 2;
  auto controller =
      mppi::make_cpu_controller(mppi::test::DoubleIntegrator{}, mppi::test::QuadraticCost{}, o);
  const float x0[2] = {1.f, 0.f};
  mppi::StepSummary summary;
  controller.step(x0, &summary);  // warm-up: the OpenMP runtime sets up its threads
  allocations = 0;
  counting = true;
  for (int i = 0; i < 20; ++i) controller.step(x0, &summary);
  const float bad[2] = {NAN, 0.f};
  controller.step(bad, &summary);
  counting = false;
  CHECK(allocations.load() == 0);
  // The same with Robust MPPI and its augmented sampling (measured state off the nominal one).
  o.variant = mppi::ControllerVariant::kRobust;
  o.robust_augmented_sampling = true;
  auto robust = mppi::make_cpu_controller(mppi::test::DoubleIntegrator{}, mppi::test::QuadraticCost{}, o);
  robust.step(x0, &summary);
  const float off[2] = {1.2f, 0.3f};
  robust.step(off, &summary);
  allocations = 0;
  counting = true;
  for (int i = 0; i < 10; ++i) robust.step(i % 2 ? x0 : off, &summary);
  counting = false;
  CHECK(summary.augmented_sampling);
  CHECK(allocations.load() == 0);
  // The counter works: a vector allocation is seen.
  counting = true;
  std::vector<float> v(10);
  counting = false;
  CHECK(allocations.load() >= 1);
}
