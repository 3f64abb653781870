#include "support/allocation_counter.hpp"

#include <atomic>
#include <cstdlib>
#include <new>

namespace selfsense::test {
namespace {

std::atomic<bool> g_armed{false};
std::atomic<std::size_t> g_allocations{0};

}  // namespace

AllocationCounter::AllocationCounter() noexcept {
  g_allocations = 0;
  g_armed = true;
}

AllocationCounter::~AllocationCounter() {
  g_armed = false;
}

std::size_t AllocationCounter::count() const noexcept {
  return g_allocations;
}

void note_allocation() noexcept {
  if (g_armed) ++g_allocations;
}

}  // namespace selfsense::test

// NOLINTBEGIN(cppcoreguidelines-no-malloc)
void* operator new(std::size_t size) {
  selfsense::test::note_allocation();
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  return operator new(size);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t /*size*/) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t /*size*/) noexcept {
  std::free(p);
}
// NOLINTEND(cppcoreguidelines-no-malloc)
