#include "allocation_counter.hpp"

#include <cstdlib>
#include <new>

namespace {

thread_local bool t_counting = false;
thread_local std::uint64_t t_allocations = 0;

void* countedAllocate(std::size_t size) {
    if (t_counting) {
        ++t_allocations;
    }
    if (void* p = std::malloc(size == 0 ? 1 : size)) {
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

}  // namespace haptic::testing
