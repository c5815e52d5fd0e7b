#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace haptic::config {

// Every enum that appears in a config file has exactly one name table, specialised next to
// the enum. The loader, error messages, hapticctl and status messages all use it, so the
// spelling in YAML and on the wire cannot drift apart.
template <typename E>
struct EnumEntry {
    std::string_view name;
    E value;
};

template <typename E>
struct EnumTraits;  // specialisations define: static constexpr std::array<EnumEntry<E>, N> kEntries

template <typename E>
concept NamedEnum = requires {
    EnumTraits<E>::kEntries;
};

template <NamedEnum E>
[[nodiscard]] constexpr std::string_view toString(E value) noexcept {
    for (const auto& entry : EnumTraits<E>::kEntries) {
        if (entry.value == value) {
            return entry.name;
        }
    }
    return "?";
}

template <NamedEnum E>
[[nodiscard]] constexpr std::optional<E> enumFromString(std::string_view name) noexcept {
    for (const auto& entry : EnumTraits<E>::kEntries) {
        if (entry.name == name) {
            return entry.value;
        }
    }
    return std::nullopt;
}

// "a|b|c", as shown in error messages.
template <NamedEnum E>
[[nodiscard]] std::string enumChoices() {
    std::string out;
    for (const auto& entry : EnumTraits<E>::kEntries) {
        if (!out.empty()) {
            out += '|';
        }
        out += entry.name;
    }
    return out;
}

}  // namespace haptic::config
