#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <string_view>

namespace haptic::msgs {

// A NUL-terminated string of fixed capacity that is trivially copyable, so it can live in
// shared memory. assign() truncates rather than fails because ids are validated at the
// configuration boundary, long before they reach a message.
template <std::size_t Capacity>
struct FixedString {
    static_assert(Capacity >= 2);
    static constexpr std::size_t kMaxLength = Capacity - 1;

    std::array<char, Capacity> chars{};

    constexpr void assign(std::string_view text) noexcept {
        const std::size_t length = std::min(text.size(), kMaxLength);
        std::copy_n(text.data(), length, chars.begin());
        std::fill(chars.begin() + static_cast<std::ptrdiff_t>(length), chars.end(), '\0');
    }
    [[nodiscard]] constexpr std::string_view view() const noexcept {
        std::size_t length = 0;
        while (length < kMaxLength && chars[length] != '\0') {
            ++length;
        }
        return {chars.data(), length};
    }
    [[nodiscard]] constexpr bool empty() const noexcept { return chars[0] == '\0'; }

    friend constexpr bool operator==(const FixedString& a, const FixedString& b) noexcept {
        return a.view() == b.view();
    }
};

}  // namespace haptic::msgs
