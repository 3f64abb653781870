// Counts heap allocations while armed, to prove that real-time code never allocates.
// Include in exactly one translation unit of a test executable: it replaces the global
// operator new/delete of that executable.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

namespace selfsense::test {

inline std::atomic<bool> g_allocation_armed{false};
inline std::atomic<std::size_t> g_allocations{0};

// Counts the allocations made while this object lives.
class AllocationCounter final {
 public:
  AllocationCounter() noexcept {
    g_allocations = 0;
    g_allocation_armed = true;
  }
  AllocationCounter(const AllocationCounter&) = delete;
  AllocationCounter& operator=(const AllocationCounter&) = delete;
  AllocationCounter(AllocationCounter&&) = delete;
  AllocationCounter& operator=(AllocationCounter&&) = delete;
  ~AllocationCounter() { g_allocation_armed = false; }
  [[nodiscard]] std::size_t count() const noexcept { return g_allocations; }
};

}  // namespace selfsense::test

// NOLINTBEGIN(cppcoreguidelines-no-malloc, readability-inconsistent-declaration-parameter-name)
void* operator new(std::size_t size) {
  if (selfsense::test::g_allocation_armed) ++selfsense::test::g_allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t /*size*/) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t /*size*/) noexcept { std::free(p); }
// NOLINTEND(cppcoreguidelines-no-malloc, readability-inconsistent-declaration-parameter-name)
