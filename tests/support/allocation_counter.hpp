// Counts heap allocations while armed, to prove that real-time code never allocates.
// Link tests/support/allocation_counter.cpp into the test executable: it replaces the global
// operator new/delete of that executable.
#pragma once

#include <cstddef>

namespace selfsense::test {

// Counts the allocations made while this object lives.
class AllocationCounter final {
 public:
  AllocationCounter() noexcept;
  AllocationCounter(const AllocationCounter&) = delete;
  AllocationCounter& operator=(const AllocationCounter&) = delete;
  AllocationCounter(AllocationCounter&&) = delete;
  AllocationCounter& operator=(AllocationCounter&&) = delete;
  ~AllocationCounter();
  [[nodiscard]] std::size_t count() const noexcept;
};

// Called by the replaced operator new.
void note_allocation() noexcept;

}  // namespace selfsense::test
