#pragma once

#include <cstddef>
#include <cstdint>

namespace haptic::testing {

// Counts heap allocations made by this thread while a scope is active (global operator new
// and, outside the ASan and TSan builds, malloc, calloc, realloc, aligned_alloc and
// posix_memalign are replaced in allocation_counter.cpp), as Drake's limit_malloc does. Used to
// prove that code on the RT path does not allocate after start.
class ScopedAllocationCounter {
  public:
    ScopedAllocationCounter();
    ~ScopedAllocationCounter();
    ScopedAllocationCounter(const ScopedAllocationCounter&) = delete;
    ScopedAllocationCounter& operator=(const ScopedAllocationCounter&) = delete;
    [[nodiscard]] std::uint64_t allocations() const;
};

// The same for every thread of the process, for code that hands work to threads of its own
// (the soft hand step's helper thread): what they allocate is not this thread's. One at a time.
class ScopedProcessAllocationCounter {
  public:
    ScopedProcessAllocationCounter();
    ~ScopedProcessAllocationCounter();
    ScopedProcessAllocationCounter(const ScopedProcessAllocationCounter&) = delete;
    ScopedProcessAllocationCounter& operator=(const ScopedProcessAllocationCounter&) = delete;
    [[nodiscard]] std::uint64_t allocations() const;
};

}  // namespace haptic::testing
