#include "allocation_counter.hpp"

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <new>

#include "allocation_counter_config.hpp"

namespace {

thread_local bool t_counting = false;
thread_local std::uint64_t t_allocations = 0;
// Lock-free, so counting inside malloc allocates nothing and takes no lock.
std::atomic<bool> g_counting{false};
std::atomic<std::uint64_t> g_allocations{0};

void count() noexcept {
    if (t_counting) {
        ++t_allocations;
    }
    if (g_counting.load(std::memory_order_relaxed)) {
        g_allocations.fetch_add(1, std::memory_order_relaxed);
    }
}

}  // namespace

// The C allocator is counted too (glibc's own entry points behind it), so that a malloc
// reached without operator new (snprintf's buffers, Eigen's aligned_malloc, a library's
// internals) is seen. Not under a sanitizer that replaces the same functions.
#if HAPTIC_COUNTS_MALLOC
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* p, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void* __libc_valloc(std::size_t size);
void* __libc_pvalloc(std::size_t size);

void* malloc(std::size_t size) {
    count();
    return __libc_malloc(size);
}
void* calloc(std::size_t n, std::size_t size) {
    count();
    return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) {
    count();
    return __libc_realloc(p, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
    count();
    return __libc_memalign(alignment, size);
}
void* reallocarray(void* p, std::size_t count_of, std::size_t size) {
    count();
    if (size != 0 && count_of > static_cast<std::size_t>(-1) / size) {
        errno = ENOMEM;
        return nullptr;
    }
    return __libc_realloc(p, count_of * size);
}
void* memalign(std::size_t alignment, std::size_t size) {
    count();
    return __libc_memalign(alignment, size);
}
void* valloc(std::size_t size) {
    count();
    return __libc_valloc(size);
}
void* pvalloc(std::size_t size) {
    count();
    return __libc_pvalloc(size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
    count();
    // What glibc refuses: not a power of two, or not a multiple of a pointer's size.
    if (alignment % sizeof(void*) != 0 || (alignment & (alignment - 1)) != 0 || alignment == 0) {
        return EINVAL;
    }
    void* p = __libc_memalign(alignment, size);
    if (p == nullptr) {
        return ENOMEM;
    }
    *out = p;
    return 0;
}
}
#endif

namespace {

// operator new below counts once, the malloc it calls not again.
void* uncountedMalloc(std::size_t size) noexcept {
#if HAPTIC_COUNTS_MALLOC
    return __libc_malloc(size);
#else
    return std::malloc(size);
#endif
}

void* countedAllocate(std::size_t size) {
    count();
    if (void* p = uncountedMalloc(size == 0 ? 1 : size)) {
        return p;
    }
    throw std::bad_alloc();
}

}  // namespace

void* operator new(std::size_t size) {
    return countedAllocate(size);
}
void* operator new[](std::size_t size) {
    return countedAllocate(size);
}
// The nothrow forms too (Fast DDS's foonathan allocator uses them): otherwise ASan's own
// nothrow new pairs with the free() below and reports an alloc-dealloc mismatch.
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
    count();
    return uncountedMalloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
    return operator new(size, tag);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
    std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
    std::free(p);
}
void operator delete(void* p) noexcept {
    std::free(p);
}
void operator delete[](void* p) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
    std::free(p);
}

namespace haptic::testing {

ScopedAllocationCounter::ScopedAllocationCounter() {
    t_allocations = 0;
    t_counting = true;
}
ScopedAllocationCounter::~ScopedAllocationCounter() {
    t_counting = false;
}
std::uint64_t ScopedAllocationCounter::allocations() const {
    return t_allocations;
}

ScopedProcessAllocationCounter::ScopedProcessAllocationCounter() {
    g_allocations.store(0);
    g_counting.store(true);
}
ScopedProcessAllocationCounter::~ScopedProcessAllocationCounter() {
    g_counting.store(false);
}
std::uint64_t ScopedProcessAllocationCounter::allocations() const {
    return g_allocations.load();
}

}  // namespace haptic::testing
