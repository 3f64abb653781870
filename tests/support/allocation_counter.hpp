// Counts heap allocations, frees and lock acquisitions while armed, to prove that real-time
// code never allocates and never locks.
//
// Link tests/support/allocation_counter.cpp into the test executable. It replaces, for that
// executable only:
//   - every global operator new/new[] and delete/delete[] form (plain, sized, std::align_val_t,
//     std::nothrow_t);
//   - the C allocation functions malloc, calloc, realloc, reallocarray, free, posix_memalign,
//     aligned_alloc, memalign, valloc and pvalloc, by defining them and forwarding to glibc's
//     __libc_malloc & co (Eigen, std::aligned_alloc and C libraries allocate through these);
//   - pthread_mutex_lock/trylock/timedlock/clocklock and pthread_rwlock_{rd,wr}lock with their
//     try/timed/clock forms (std::mutex, std::shared_mutex, std::timed_mutex), forwarding to the
//     next definition found by dlsym(RTLD_NEXT).
//
// Under AddressSanitizer the C allocation functions are not defined here: ASan's own malloc
// must serve every block it later checks and frees. They are counted instead through ASan's
// malloc/free hooks (__sanitizer_install_malloc_and_free_hooks), which see every allocation
// ASan serves, so the counts are the same in both builds. Each allocation is counted once:
// operator new counts itself and the malloc it calls is not counted again.
//
// Not seen: locks taken inside glibc through its internal lock (stdio, dlopen), futex waits
// (std::atomic::wait, std::counting_semaphore), and mmap.
#pragma once

#include <cstddef>

namespace selfsense::test {

// Counts what happens in any thread between construction and destruction. One counter at a
// time (the counts are process-wide).
class AllocationCounter final {
 public:
  AllocationCounter() noexcept;
  AllocationCounter(const AllocationCounter&) = delete;
  AllocationCounter& operator=(const AllocationCounter&) = delete;
  AllocationCounter(AllocationCounter&&) = delete;
  AllocationCounter& operator=(AllocationCounter&&) = delete;
  ~AllocationCounter();

  // Every allocation: new_allocations() + c_allocations().
  [[nodiscard]] std::size_t count() const noexcept;
  // Calls of any operator new / new[].
  [[nodiscard]] std::size_t new_allocations() const noexcept;
  // Calls of the C allocation functions (realloc counts as one allocation).
  [[nodiscard]] std::size_t c_allocations() const noexcept;
  // Calls of operator delete / delete[] and free with a non-null pointer.
  [[nodiscard]] std::size_t deallocations() const noexcept;
  // Mutex and reader-writer lock acquisitions, successful or not.
  [[nodiscard]] std::size_t locks() const noexcept;
};

// Keeps the compiler from removing an allocation whose result is otherwise unused (it may
// elide new/delete and malloc/free pairs). Non-const: GCC assumes a const pointer argument is read.
void keep(void* p) noexcept;

}  // namespace selfsense::test
