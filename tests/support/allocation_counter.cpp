#include "support/allocation_counter.hpp"

#include <dlfcn.h>
#include <malloc.h>
#include <pthread.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <ctime>
#include <new>

// ASan and TSan serve malloc themselves; defining malloc here would take blocks away from them.
// Both count C allocations through the sanitizer's hooks instead. TSan also intercepts the
// pthread locks it tracks, so under TSan locks are not counted (the Release and ASan runs do).
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define SELFSENSE_COUNTER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define SELFSENSE_COUNTER_ASAN 1
#endif
#endif
#if defined(__SANITIZE_THREAD__)
#define SELFSENSE_COUNTER_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define SELFSENSE_COUNTER_TSAN 1
#endif
#endif

#ifdef SELFSENSE_COUNTER_ASAN
// From <sanitizer/allocator_interface.h>, which GCC does not ship (its libasan has the function).
// NOLINTNEXTLINE(bugprone-reserved-identifier,cert-dcl37-c,cert-dcl51-cpp)
extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*malloc_hook)(const volatile void*,
                                                                             std::size_t),
                                                         void (*free_hook)(const volatile void*));
#endif

namespace {

std::atomic<bool> g_armed{false};
std::atomic<std::size_t> g_new{0};
std::atomic<std::size_t> g_c{0};
std::atomic<std::size_t> g_free{0};
std::atomic<std::size_t> g_locks{0};
std::atomic<void*> g_kept{nullptr};

// Set while operator new/delete call malloc/free, so that one allocation is counted once.
// Constant-initialised and internal: reading it needs no allocation and no lock.
thread_local bool t_inside_new = false;

void note(std::atomic<std::size_t>& n) noexcept {
  if (g_armed.load(std::memory_order_relaxed)) n.fetch_add(1, std::memory_order_relaxed);
}

void note_c_allocation() noexcept {
  if (!t_inside_new) note(g_c);
}

void note_c_free(const volatile void* p) noexcept {
  if (p != nullptr && !t_inside_new) note(g_free);
}

class InsideNew final {
 public:
  InsideNew() noexcept { t_inside_new = true; }
  InsideNew(const InsideNew&) = delete;
  InsideNew& operator=(const InsideNew&) = delete;
  InsideNew(InsideNew&&) = delete;
  InsideNew& operator=(InsideNew&&) = delete;
  ~InsideNew() { t_inside_new = false; }
};

#ifdef SELFSENSE_COUNTER_ASAN
void on_asan_malloc(const volatile void* /*p*/, std::size_t /*size*/) {
  note_c_allocation();
}
void on_asan_free(const volatile void* p) {
  note_c_free(p);
}
[[maybe_unused]] const int kAsanHooksInstalled =
    __sanitizer_install_malloc_and_free_hooks(on_asan_malloc, on_asan_free);
#endif

// NOLINTBEGIN(cppcoreguidelines-no-malloc)
void* allocate(std::size_t size, std::size_t align) noexcept {
  const InsideNew guard;
  if (size == 0) size = 1;
  if (align <= __STDCPP_DEFAULT_NEW_ALIGNMENT__) return std::malloc(size);
  // aligned_alloc wants the size to be a multiple of the alignment.
  return std::aligned_alloc(align, (size + align - 1) / align * align);
}

void release(void* p) noexcept {
  if (p == nullptr) return;
  note(g_free);
  const InsideNew guard;
  std::free(p);
}
// NOLINTEND(cppcoreguidelines-no-malloc)

void* allocate_or_throw(std::size_t size, std::size_t align) {
  note(g_new);
  for (;;) {
    if (void* p = allocate(size, align)) return p;
    const std::new_handler handler = std::get_new_handler();
    if (handler == nullptr) throw std::bad_alloc();
    handler();
  }
}

void* allocate_or_null(std::size_t size, std::size_t align) noexcept {
  try {
    return allocate_or_throw(size, align);
  } catch (...) {
    return nullptr;
  }
}

constexpr std::size_t kPlain = __STDCPP_DEFAULT_NEW_ALIGNMENT__;

std::size_t to_size(std::align_val_t align) noexcept {
  return static_cast<std::size_t>(align);
}

// The definition after this executable's (libc's, or the sanitizer's interceptor), found once.
template <typename Fn>
Fn* next(std::atomic<Fn*>& cache, const char* name) noexcept {
  Fn* fn = cache.load(std::memory_order_acquire);
  if (fn == nullptr) {
    // dlsym returns functions as void*; POSIX guarantees the conversion.
    fn = reinterpret_cast<Fn*>(dlsym(RTLD_NEXT, name));
    if (fn == nullptr) std::abort();
    cache.store(fn, std::memory_order_release);
  }
  return fn;
}

}  // namespace

namespace selfsense::test {

AllocationCounter::AllocationCounter() noexcept {
  g_new = 0;
  g_c = 0;
  g_free = 0;
  g_locks = 0;
  g_armed = true;
}

AllocationCounter::~AllocationCounter() {
  g_armed = false;
}

std::size_t AllocationCounter::count() const noexcept {
  return g_new + g_c;
}
std::size_t AllocationCounter::new_allocations() const noexcept {
  return g_new;
}
std::size_t AllocationCounter::c_allocations() const noexcept {
  return g_c;
}
std::size_t AllocationCounter::deallocations() const noexcept {
  return g_free;
}
std::size_t AllocationCounter::locks() const noexcept {
  return g_locks;
}

void keep(void* p) noexcept {
  g_kept.store(p, std::memory_order_relaxed);
}

}  // namespace selfsense::test

// ---- operator new and delete, every form ------------------------------------------------------

void* operator new(std::size_t size) {
  return allocate_or_throw(size, kPlain);
}
void* operator new[](std::size_t size) {
  return allocate_or_throw(size, kPlain);
}
void* operator new(std::size_t size, const std::nothrow_t& /*tag*/) noexcept {
  return allocate_or_null(size, kPlain);
}
void* operator new[](std::size_t size, const std::nothrow_t& /*tag*/) noexcept {
  return allocate_or_null(size, kPlain);
}
void* operator new(std::size_t size, std::align_val_t align) {
  return allocate_or_throw(size, to_size(align));
}
void* operator new[](std::size_t size, std::align_val_t align) {
  return allocate_or_throw(size, to_size(align));
}
void* operator new(std::size_t size, std::align_val_t align,
                   const std::nothrow_t& /*tag*/) noexcept {
  return allocate_or_null(size, to_size(align));
}
void* operator new[](std::size_t size, std::align_val_t align,
                     const std::nothrow_t& /*tag*/) noexcept {
  return allocate_or_null(size, to_size(align));
}

void operator delete(void* p) noexcept {
  release(p);
}
void operator delete[](void* p) noexcept {
  release(p);
}
void operator delete(void* p, std::size_t /*size*/) noexcept {
  release(p);
}
void operator delete[](void* p, std::size_t /*size*/) noexcept {
  release(p);
}
void operator delete(void* p, const std::nothrow_t& /*tag*/) noexcept {
  release(p);
}
void operator delete[](void* p, const std::nothrow_t& /*tag*/) noexcept {
  release(p);
}
void operator delete(void* p, std::align_val_t /*align*/) noexcept {
  release(p);
}
void operator delete[](void* p, std::align_val_t /*align*/) noexcept {
  release(p);
}
void operator delete(void* p, std::size_t /*size*/, std::align_val_t /*align*/) noexcept {
  release(p);
}
void operator delete[](void* p, std::size_t /*size*/, std::align_val_t /*align*/) noexcept {
  release(p);
}
void operator delete(void* p, std::align_val_t /*align*/, const std::nothrow_t& /*tag*/) noexcept {
  release(p);
}
void operator delete[](void* p, std::align_val_t /*align*/,
                       const std::nothrow_t& /*tag*/) noexcept {
  release(p);
}

// ---- the C allocation functions (not under ASan: counted by its hooks above) ------------------

#ifndef SELFSENSE_COUNTER_ASAN
// glibc's allocator under its internal names, the documented way to wrap malloc.
// NOLINTBEGIN(bugprone-reserved-identifier,cert-dcl37-c,cert-dcl51-cpp,readability-identifier-naming)
extern "C" {
void* __libc_malloc(std::size_t size) noexcept;
void* __libc_calloc(std::size_t n, std::size_t size) noexcept;
void* __libc_realloc(void* p, std::size_t size) noexcept;
void __libc_free(void* p) noexcept;
void* __libc_memalign(std::size_t align, std::size_t size) noexcept;
void* __libc_valloc(std::size_t size) noexcept;
void* __libc_pvalloc(std::size_t size) noexcept;
}
// NOLINTEND(bugprone-reserved-identifier,cert-dcl37-c,cert-dcl51-cpp,readability-identifier-naming)

// Parameter names as in glibc's declarations, without the underscores.
extern "C" {

void* malloc(std::size_t size) noexcept {
  note_c_allocation();
  return __libc_malloc(size);
}

void* calloc(std::size_t nmemb, std::size_t size) noexcept {
  note_c_allocation();
  return __libc_calloc(nmemb, size);
}

// A realloc of a block is a new block and a free, as ASan's hooks see it.
void* realloc(void* ptr, std::size_t size) noexcept {
  note_c_allocation();
  note_c_free(ptr);
  return __libc_realloc(ptr, size);
}

void* reallocarray(void* ptr, std::size_t nmemb, std::size_t size) noexcept {
  if (size != 0 && nmemb > static_cast<std::size_t>(-1) / size) {
    errno = ENOMEM;
    return nullptr;
  }
  return realloc(ptr, nmemb * size);
}

void free(void* ptr) noexcept {
  note_c_free(ptr);
  __libc_free(ptr);
}

int posix_memalign(void** memptr, std::size_t alignment, std::size_t size) noexcept {
  if (alignment == 0 || alignment % sizeof(void*) != 0 || (alignment & (alignment - 1)) != 0)
    return EINVAL;
  note_c_allocation();
  void* p = __libc_memalign(alignment, size);
  if (p == nullptr) return ENOMEM;
  *memptr = p;
  return 0;
}

void* aligned_alloc(std::size_t alignment, std::size_t size) noexcept {
  note_c_allocation();
  return __libc_memalign(alignment, size);
}

void* memalign(std::size_t alignment, std::size_t size) noexcept {
  note_c_allocation();
  return __libc_memalign(alignment, size);
}

void* valloc(std::size_t size) noexcept {
  note_c_allocation();
  return __libc_valloc(size);
}

void* pvalloc(std::size_t size) noexcept {
  note_c_allocation();
  return __libc_pvalloc(size);
}

}  // extern "C"
#endif

#ifndef SELFSENSE_COUNTER_TSAN
// ---- locks ------------------------------------------------------------------------------------

namespace {

using MutexFn = int(pthread_mutex_t*);
using MutexTimedFn = int(pthread_mutex_t*, const timespec*);
using MutexClockFn = int(pthread_mutex_t*, clockid_t, const timespec*);
using RwFn = int(pthread_rwlock_t*);
using RwTimedFn = int(pthread_rwlock_t*, const timespec*);
using RwClockFn = int(pthread_rwlock_t*, clockid_t, const timespec*);

std::atomic<MutexFn*> g_mutex_lock{nullptr};
std::atomic<MutexFn*> g_mutex_trylock{nullptr};
std::atomic<MutexTimedFn*> g_mutex_timedlock{nullptr};
std::atomic<MutexClockFn*> g_mutex_clocklock{nullptr};
std::atomic<RwFn*> g_rw_rdlock{nullptr};
std::atomic<RwFn*> g_rw_wrlock{nullptr};
std::atomic<RwFn*> g_rw_tryrdlock{nullptr};
std::atomic<RwFn*> g_rw_trywrlock{nullptr};
std::atomic<RwTimedFn*> g_rw_timedrdlock{nullptr};
std::atomic<RwTimedFn*> g_rw_timedwrlock{nullptr};
std::atomic<RwClockFn*> g_rw_clockrdlock{nullptr};
std::atomic<RwClockFn*> g_rw_clockwrlock{nullptr};

}  // namespace

extern "C" {

int pthread_mutex_lock(pthread_mutex_t* mutex) noexcept {
  note(g_locks);
  return next(g_mutex_lock, "pthread_mutex_lock")(mutex);
}

int pthread_mutex_trylock(pthread_mutex_t* mutex) noexcept {
  note(g_locks);
  return next(g_mutex_trylock, "pthread_mutex_trylock")(mutex);
}

int pthread_mutex_timedlock(pthread_mutex_t* mutex, const timespec* abstime) noexcept {
  note(g_locks);
  return next(g_mutex_timedlock, "pthread_mutex_timedlock")(mutex, abstime);
}

int pthread_mutex_clocklock(pthread_mutex_t* mutex, clockid_t clockid,
                            const timespec* abstime) noexcept {
  note(g_locks);
  return next(g_mutex_clocklock, "pthread_mutex_clocklock")(mutex, clockid, abstime);
}

int pthread_rwlock_rdlock(pthread_rwlock_t* rwlock) noexcept {
  note(g_locks);
  return next(g_rw_rdlock, "pthread_rwlock_rdlock")(rwlock);
}

int pthread_rwlock_wrlock(pthread_rwlock_t* rwlock) noexcept {
  note(g_locks);
  return next(g_rw_wrlock, "pthread_rwlock_wrlock")(rwlock);
}

int pthread_rwlock_tryrdlock(pthread_rwlock_t* rwlock) noexcept {
  note(g_locks);
  return next(g_rw_tryrdlock, "pthread_rwlock_tryrdlock")(rwlock);
}

int pthread_rwlock_trywrlock(pthread_rwlock_t* rwlock) noexcept {
  note(g_locks);
  return next(g_rw_trywrlock, "pthread_rwlock_trywrlock")(rwlock);
}

int pthread_rwlock_timedrdlock(pthread_rwlock_t* rwlock, const timespec* abstime) noexcept {
  note(g_locks);
  return next(g_rw_timedrdlock, "pthread_rwlock_timedrdlock")(rwlock, abstime);
}

int pthread_rwlock_timedwrlock(pthread_rwlock_t* rwlock, const timespec* abstime) noexcept {
  note(g_locks);
  return next(g_rw_timedwrlock, "pthread_rwlock_timedwrlock")(rwlock, abstime);
}

int pthread_rwlock_clockrdlock(pthread_rwlock_t* rwlock, clockid_t clockid,
                               const timespec* abstime) noexcept {
  note(g_locks);
  return next(g_rw_clockrdlock, "pthread_rwlock_clockrdlock")(rwlock, clockid, abstime);
}

int pthread_rwlock_clockwrlock(pthread_rwlock_t* rwlock, clockid_t clockid,
                               const timespec* abstime) noexcept {
  note(g_locks);
  return next(g_rw_clockwrlock, "pthread_rwlock_clockwrlock")(rwlock, clockid, abstime);
}

}  // extern "C"
#endif  // SELFSENSE_COUNTER_TSAN
