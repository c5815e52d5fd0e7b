// The counter the RT-path allocation tests rely on counts what it claims to.

#include "allocation_counter.hpp"

#include <gtest/gtest.h>
#include <malloc.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include "allocation_counter_config.hpp"

namespace haptic::testing {
namespace {

TEST(AllocationCounter, CountsOperatorNewOnceAndNothingOutsideItsScope) {
    auto outside = std::make_unique<int>(1);
    const ScopedAllocationCounter counter;
    EXPECT_EQ(counter.allocations(), 0U);
    std::vector<double> grown;
    grown.resize(100);
    EXPECT_EQ(counter.allocations(), 1U);
}

#if HAPTIC_COUNTS_MALLOC
// Keeps the compiler from pairing an allocation with its free() and removing both.
void* kept(void* p) {
    asm volatile("" : : "r"(p) : "memory");
    return p;
}

TEST(AllocationCounter, CountsTheCAllocatorToo) {
    const ScopedAllocationCounter counter;
    void* a = kept(std::malloc(64));
    void* b = kept(std::calloc(4, 16));
    a = kept(std::realloc(a, 4096));
    void* c = nullptr;
    ASSERT_EQ(::posix_memalign(&c, 64, 128), 0);
    void* d = kept(std::aligned_alloc(64, 128));
    void* e = kept(::memalign(64, 128));
    void* f = kept(::valloc(128));
    void* g = kept(::pvalloc(128));
    b = kept(::reallocarray(b, 8, 16));
    void* refused = nullptr;
    EXPECT_EQ(::posix_memalign(&refused, 24, 128), EINVAL) << "not a power of two";
    const std::uint64_t counted = counter.allocations();
    for (void* p : {a, b, c, d, e, f, g}) {
        std::free(p);
    }
    EXPECT_EQ(counted, 10U);
}
#endif

}  // namespace
}  // namespace haptic::testing
