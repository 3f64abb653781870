// The allocation counter sees each way of allocating and locking that real-time code could
// hide: the C functions (Eigen allocates through malloc), every operator new form, and locks.
// Each allocation is handed to keep() so that the compiler cannot elide it.
#include "support/allocation_counter.hpp"

#include <gtest/gtest.h>
#include <malloc.h>

#include <Eigen/Dense>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <new>
#include <shared_mutex>
#include <vector>

namespace selfsense::test {
namespace {

// NOLINTBEGIN(cppcoreguidelines-no-malloc,cppcoreguidelines-owning-memory)

TEST(AllocationCounter, SeesMalloc) {
  AllocationCounter counter;
  void* p = std::malloc(64);
  keep(p);
  std::free(p);
  EXPECT_EQ(counter.c_allocations(), 1U);
  EXPECT_EQ(counter.count(), 1U);
  EXPECT_EQ(counter.deallocations(), 1U);
}

TEST(AllocationCounter, SeesCalloc) {
  AllocationCounter counter;
  void* p = std::calloc(8, 8);
  keep(p);
  std::free(p);
  EXPECT_EQ(counter.c_allocations(), 1U);
}

TEST(AllocationCounter, SeesRealloc) {
  void* p = std::malloc(16);
  keep(p);
  AllocationCounter counter;
  p = std::realloc(p, 1U << 20U);  // too large to grow in place
  keep(p);
  EXPECT_EQ(counter.c_allocations(), 1U);
  std::free(p);
}

TEST(AllocationCounter, SeesPosixMemalignAndTheOtherAlignedCFunctions) {
  AllocationCounter counter;
  void* p = nullptr;
  ASSERT_EQ(posix_memalign(&p, 64, 256), 0);
  keep(p);
  std::free(p);
  EXPECT_EQ(counter.c_allocations(), 1U);
  void* q = std::aligned_alloc(64, 256);
  keep(q);
  std::free(q);
  EXPECT_EQ(counter.c_allocations(), 2U);
  void* r = memalign(64, 100);
  keep(r);
  std::free(r);
  void* s = valloc(100);
  keep(s);
  std::free(s);
  EXPECT_EQ(counter.c_allocations(), 4U);
  EXPECT_EQ(counter.deallocations(), 4U);
  EXPECT_EQ(counter.new_allocations(), 0U);
}

struct alignas(64) CacheLine {
  double v[8]{};
};

TEST(AllocationCounter, SeesEveryOperatorNewFormOnce) {
  AllocationCounter counter;
  auto* a = new CacheLine;  // aligned new
  keep(a);
  delete a;
  auto* b = new CacheLine[3];  // aligned new[]
  keep(b);
  delete[] b;
  auto* c = new (std::nothrow) CacheLine;  // aligned nothrow new
  keep(c);
  delete c;
  auto* d = new (std::nothrow) double[4];  // nothrow new[]
  keep(d);
  delete[] d;
  auto v = std::make_unique<std::vector<double>>(10);  // plain new, twice
  keep(v->data());
  v.reset();
  EXPECT_EQ(counter.new_allocations(), 6U);
  EXPECT_EQ(counter.c_allocations(), 0U);  // operator new's own malloc is not counted again
  EXPECT_EQ(counter.deallocations(), 6U);
}

TEST(AllocationCounter, SeesEigenAllocations) {
  AllocationCounter counter;
  Eigen::VectorXd x = Eigen::VectorXd::Constant(1000, 1.0);
  keep(x.data());
  EXPECT_GE(counter.count(), 1U);
  EXPECT_EQ(counter.new_allocations(), 0U);  // Eigen calls malloc, not new
}

TEST(AllocationCounter, SeesMutexAndReaderWriterLocks) {
  std::mutex m;
  std::shared_mutex rw;
  AllocationCounter counter;
  m.lock();
  m.unlock();
  EXPECT_EQ(counter.locks(), 1U);
  ASSERT_TRUE(m.try_lock());
  m.unlock();
  EXPECT_EQ(counter.locks(), 2U);
  rw.lock_shared();
  rw.unlock_shared();
  rw.lock();
  rw.unlock();
  EXPECT_EQ(counter.locks(), 4U);
  EXPECT_EQ(counter.count(), 0U);
}

TEST(AllocationCounter, ArithmeticCountsNothing) {
  std::vector<double> v(100, 1.0);
  AllocationCounter counter;
  double sum = 0.0;
  for (const double x : v)
    sum += x;
  keep(&sum);
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_EQ(counter.deallocations(), 0U);
  EXPECT_EQ(counter.locks(), 0U);
}

TEST(AllocationCounter, StartsFromZero) {
  {
    AllocationCounter first;
    keep(std::make_unique<int>(1).get());
  }
  AllocationCounter counter;
  EXPECT_EQ(counter.count(), 0U);
}

// NOLINTEND(cppcoreguidelines-no-malloc,cppcoreguidelines-owning-memory)

}  // namespace
}  // namespace selfsense::test
