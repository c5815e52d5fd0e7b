#include "scalar.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <regex>
#include <system_error>

namespace haptic::config::detail {
namespace {

bool isPlain(const YAML::Node& node) {
    // yaml-cpp tags plain scalars "?", quoted ones "!", and keeps explicit tags verbatim.
    const std::string& tag = node.Tag();
    return tag != "!" && tag != "tag:yaml.org,2002:str";
}

std::optional<std::int64_t> parseIntegerText(std::string_view text, bool& overflow) {
    overflow = false;
    int base = 10;
    std::string_view digits = text;
    bool negative = false;
    if (text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'o')) {
        base = text[1] == 'x' ? 16 : 8;
        digits = text.substr(2);
    } else {
        if (!digits.empty() && (digits[0] == '+' || digits[0] == '-')) {
            negative = digits[0] == '-';
            digits.remove_prefix(1);
        }
    }
    if (digits.empty()) {
        return std::nullopt;
    }
    for (const char c : digits) {
        const bool ok = base == 16 ? std::isxdigit(static_cast<unsigned char>(c)) != 0
                                   : (c >= '0' && c < static_cast<char>('0' + base));
        if (!ok) {
            return std::nullopt;
        }
    }
    std::uint64_t magnitude = 0;
    const auto [end, ec] =
        std::from_chars(digits.data(), digits.data() + digits.size(), magnitude, base);
    if (ec == std::errc::result_out_of_range ||
        magnitude > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
        overflow = true;
        return std::int64_t{0};
    }
    if (ec != std::errc{} || end != digits.data() + digits.size()) {
        return std::nullopt;
    }
    const auto value = static_cast<std::int64_t>(magnitude);
    return negative ? -value : value;
}

}  // namespace

Scalar classify(const YAML::Node& node) {
    Scalar out;
    if (node.IsNull()) {
        out.kind = Kind::kNull;
        return out;
    }
    if (node.IsMap()) {
        out.kind = Kind::kMap;
        return out;
    }
    if (node.IsSequence()) {
        out.kind = Kind::kList;
        return out;
    }
    if (!node.IsScalar() || !isPlain(node)) {
        return out;  // a quoted or !!str scalar is a string whatever it looks like
    }
    const std::string& text = node.Scalar();
    if (text == "true" || text == "True" || text == "TRUE") {
        out.kind = Kind::kBool;
        out.boolean = true;
        return out;
    }
    if (text == "false" || text == "False" || text == "FALSE") {
        out.kind = Kind::kBool;
        return out;
    }
    if (const auto integer = parseIntegerText(text, out.integer_overflow)) {
        out.kind = Kind::kInt;
        out.integer = *integer;
        return out;
    }
    static const std::regex kFloat(R"([-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?)");
    static const std::regex kNonFinite(R"([-+]?\.(inf|Inf|INF)|\.(nan|NaN|NAN))");
    if (std::regex_match(text, kNonFinite)) {
        out.kind = Kind::kNonFinite;
        return out;
    }
    if (std::regex_match(text, kFloat)) {
        const char* first = text.data() + (text[0] == '+' ? 1 : 0);
        const auto [end, ec] = std::from_chars(first, text.data() + text.size(), out.real);
        out.kind = (ec == std::errc{} && std::isfinite(out.real)) ? Kind::kFloat : Kind::kNonFinite;
        return out;
    }
    return out;
}

std::string formatInteger(std::int64_t value, bool hex) {
    if (!hex || value < 0) {
        return std::to_string(value);
    }
    char buffer[32];
    const auto [end, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value, 16);
    return "0x" + std::string(buffer, end);
}

std::string sanitise(std::string_view text) {
    constexpr std::size_t kMaxShown = 80;
    std::string out;
    for (const char c : text.substr(0, kMaxShown)) {
        out += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? '?' : c;
    }
    if (text.size() > kMaxShown) {
        out += "...";
    }
    return out;
}

}  // namespace haptic::config::detail
