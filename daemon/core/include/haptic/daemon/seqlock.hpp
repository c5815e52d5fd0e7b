#pragma once

#include <atomic>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace haptic::daemon {

// Single-writer, many-reader snapshot exchange. The RT thread writes without ever waiting;
// readers (status, telemetry threads) retry if they raced a write. T must be trivially
// copyable because a torn copy is taken and then discarded.
//
// The payload is copied with relaxed atomic byte-wise semantics via std::memcpy between
// fences, the standard seqlock pattern (Boehm, "Can seqlocks get along with programming
// language memory models?", 2012).
template <typename T>
class SeqLock {
    static_assert(std::is_trivially_copyable_v<T>);

  public:
    void store(const T& value) noexcept {
        const std::uint64_t seq = sequence_.load(std::memory_order_relaxed);
        sequence_.store(seq + 1, std::memory_order_relaxed);  // odd: write in progress
        std::atomic_thread_fence(std::memory_order_release);
        std::memcpy(&value_, &value, sizeof(T));
        std::atomic_thread_fence(std::memory_order_release);
        sequence_.store(seq + 2, std::memory_order_relaxed);
    }

    // Returns false (and leaves `out` untouched) until the first store.
    bool load(T& out) const noexcept {
        T copy;
        for (;;) {
            const std::uint64_t before = sequence_.load(std::memory_order_acquire);
            if (before == 0) {
                return false;
            }
            if ((before & 1U) != 0) {
                continue;
            }
            std::memcpy(&copy, &value_, sizeof(T));
            std::atomic_thread_fence(std::memory_order_acquire);
            if (sequence_.load(std::memory_order_relaxed) == before) {
                out = copy;
                return true;
            }
        }
    }

    // One bounded attempt, for a reader that must never spin (the RT thread: a writer
    // preempted mid-store on its CPU would never finish while it spins). Returns the version
    // it copied, or 0 if nothing was stored yet or it raced a write; `out` is then
    // unspecified and must be ignored.
    std::uint64_t tryLoad(T& out) const noexcept {
        const std::uint64_t before = sequence_.load(std::memory_order_acquire);
        if (before == 0 || (before & 1U) != 0) {
            return 0;
        }
        std::memcpy(&out, &value_, sizeof(T));
        std::atomic_thread_fence(std::memory_order_acquire);
        return sequence_.load(std::memory_order_relaxed) == before ? before / 2 : 0;
    }

    [[nodiscard]] std::uint64_t version() const noexcept {
        return sequence_.load(std::memory_order_acquire) / 2;
    }

  private:
    std::atomic<std::uint64_t> sequence_{0};
    T value_{};
};

}  // namespace haptic::daemon
