#pragma once

// How a YAML scalar reads under YAML 1.2's core schema, for the reader and the specs.
// Private to the library.

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace haptic::config::detail {

// yaml-cpp keeps scalar text and converts on demand, leniently; the error messages need to
// say what was found, so the classification is done here once.
enum class Kind { kNull, kBool, kInt, kFloat, kNonFinite, kString, kMap, kList };

struct Scalar {
    Kind kind{Kind::kString};
    bool boolean{false};
    std::int64_t integer{0};
    bool integer_overflow{false};
    double real{0.0};
};

[[nodiscard]] Scalar classify(const YAML::Node& node);

// Decimal, or hex in messages about CAN ids.
[[nodiscard]] std::string formatInteger(std::int64_t value, bool hex);

// Values echoed into messages must keep what() on one line and reasonably short.
[[nodiscard]] std::string sanitise(std::string_view text);

}  // namespace haptic::config::detail
