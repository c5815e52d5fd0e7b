#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace haptic::daemon {

// Single-writer, many-reader snapshot exchange. The RT thread writes without ever waiting;
// readers (status, telemetry threads) retry if they raced a write. T must be trivially
// copyable because a torn copy is taken and then discarded.
//
// The payload lives in atomic 64-bit words: the writer marks the sequence odd, stores every
// word with release order and marks it even again with release; a reader loads the sequence
// with acquire, every word with acquire, and the sequence again. A reader that saw any word of
// a newer write is ordered after that write's odd mark, so its second sequence load differs
// and the copy is discarded (Boehm, "Can seqlocks get along with programming language memory
// models?", 2012, the variant without fences). Every access is an atomic operation, so
// ThreadSanitizer checks the exchange (it does not model std::atomic_thread_fence); on x86-64
// release stores and acquire loads are plain moves, so the RT writer pays nothing for it.
template <typename T>
class SeqLock {
    static_assert(std::is_trivially_copyable_v<T>);
    static constexpr std::size_t kWordBytes = sizeof(std::uint64_t);
    static constexpr std::size_t kWords = (sizeof(T) + kWordBytes - 1) / kWordBytes;

  public:
    void store(const T& value) noexcept {
        const std::uint64_t seq = sequence_.load(std::memory_order_relaxed);
        sequence_.store(seq + 1, std::memory_order_relaxed);  // odd: write in progress
        const auto* bytes = reinterpret_cast<const unsigned char*>(&value);
        for (std::size_t i = 0; i < kWords; ++i) {
            std::uint64_t word = 0;
            std::memcpy(&word, bytes + i * kWordBytes, bytesOfWord(i));
            words_[i].store(word, std::memory_order_release);
        }
        sequence_.store(seq + 2, std::memory_order_release);
    }

    // Returns false (and leaves `out` untouched) until the first store.
    bool load(T& out) const noexcept {
        T copy;
        for (;;) {
            const std::uint64_t version = tryLoad(copy);
            if (version != 0) {
                out = copy;
                return true;
            }
            if (sequence_.load(std::memory_order_acquire) == 0) {
                return false;
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
        auto* bytes = reinterpret_cast<unsigned char*>(&out);
        for (std::size_t i = 0; i < kWords; ++i) {
            const std::uint64_t word = words_[i].load(std::memory_order_acquire);
            std::memcpy(bytes + i * kWordBytes, &word, bytesOfWord(i));
        }
        return sequence_.load(std::memory_order_relaxed) == before ? before / 2 : 0;
    }

    [[nodiscard]] std::uint64_t version() const noexcept {
        return sequence_.load(std::memory_order_acquire) / 2;
    }

  private:
    // Every word is full except possibly the last.
    static constexpr std::size_t bytesOfWord(std::size_t i) noexcept {
        return i + 1 < kWords ? kWordBytes : sizeof(T) - i * kWordBytes;
    }

    std::atomic<std::uint64_t> sequence_{0};
    std::array<std::atomic<std::uint64_t>, kWords> words_{};
};

}  // namespace haptic::daemon
