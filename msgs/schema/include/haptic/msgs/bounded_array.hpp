#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace haptic::msgs {

// A variable-length list with a fixed capacity, trivially copyable so it can be loaned from
// a RouDi mempool and filled in place. Equality looks only at the used prefix, which is what
// survives a trip through a DDS bounded sequence.
template <typename T, std::size_t Capacity>
struct BoundedArray {
    static constexpr std::size_t kCapacity = Capacity;

    std::uint32_t count{0};
    std::array<T, Capacity> items{};

    [[nodiscard]] constexpr std::size_t size() const noexcept { return count; }
    [[nodiscard]] constexpr bool empty() const noexcept { return count == 0; }
    [[nodiscard]] constexpr bool full() const noexcept { return count >= Capacity; }
    constexpr void clear() noexcept { count = 0; }

    // Returns false instead of growing past the capacity: callers on the RT path must not
    // allocate or throw, and a dropped entry is reported by the caller.
    constexpr bool push_back(const T& value) noexcept {
        if (full()) {
            return false;
        }
        items[count++] = value;
        return true;
    }

    [[nodiscard]] constexpr T& operator[](std::size_t i) noexcept { return items[i]; }
    [[nodiscard]] constexpr const T& operator[](std::size_t i) const noexcept { return items[i]; }
    [[nodiscard]] std::span<T> used() noexcept {
        return {items.data(), std::min<std::size_t>(count, Capacity)};
    }
    [[nodiscard]] std::span<const T> used() const noexcept {
        return {items.data(), std::min<std::size_t>(count, Capacity)};
    }
    [[nodiscard]] auto begin() noexcept { return used().begin(); }
    [[nodiscard]] auto end() noexcept { return used().end(); }
    [[nodiscard]] auto begin() const noexcept { return used().begin(); }
    [[nodiscard]] auto end() const noexcept { return used().end(); }

    friend constexpr bool operator==(const BoundedArray& a, const BoundedArray& b) noexcept {
        return a.count == b.count && a.count <= Capacity &&
               std::equal(a.items.begin(), a.items.begin() + a.count, b.items.begin());
    }
};

}  // namespace haptic::msgs
