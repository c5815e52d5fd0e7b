#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <system_error>

#include "haptic/config/reader.hpp"
#include "scalar.hpp"

namespace haptic::config {
namespace {

namespace fs = std::filesystem;
using detail::classify;
using detail::formatInteger;
using detail::Kind;
using detail::sanitise;
using detail::Scalar;

}  // namespace

namespace spec {

bool Real::contains(double value) const noexcept {
    const bool above = min_open ? value > min : value >= min;
    const bool below = max_open ? value < max : value <= max;
    return above && below;
}

std::string Real::describe() const {
    const bool has_min = min != std::numeric_limits<double>::lowest();
    const bool has_max = max != std::numeric_limits<double>::max();
    if (has_min && has_max) {
        return std::string("a number in ") + (min_open ? "(" : "[") + formatNumber(min) + ", " +
               formatNumber(max) + (max_open ? ")" : "]");
    }
    if (has_min) {
        return std::string("a number ") + (min_open ? "> " : ">= ") + formatNumber(min);
    }
    if (has_max) {
        return std::string("a number ") + (max_open ? "< " : "<= ") + formatNumber(max);
    }
    return "a finite number";
}

double Real::parse(const Field& field) const {
    const Scalar scalar = classify(field.node());
    double value = 0.0;
    if (scalar.kind == Kind::kInt && !scalar.integer_overflow) {
        value = static_cast<double>(scalar.integer);
    } else if (scalar.kind == Kind::kFloat) {
        value = scalar.real;
    } else {
        field.fail(describe());
    }
    if (!contains(value)) {
        field.fail(describe());
    }
    return value;
}

std::int64_t parseInteger(const Field& field, std::int64_t min, std::int64_t max,
                          const std::string& expected) {
    const Scalar scalar = classify(field.node());
    if (scalar.kind != Kind::kInt || scalar.integer_overflow || scalar.integer < min ||
        scalar.integer > max) {
        field.fail(expected);
    }
    return scalar.integer;
}

std::string describeInteger(std::int64_t min, std::int64_t max, bool hex) {
    return "an integer in [" + formatInteger(min, hex) + ", " + formatInteger(max, hex) + "]";
}

std::string Boolean::describe() const {
    return "true or false";
}

bool Boolean::parse(const Field& field) const {
    const Scalar scalar = classify(field.node());
    if (scalar.kind != Kind::kBool) {
        field.fail(describe());
    }
    return scalar.boolean;
}

std::string Text::describe() const {
    return "a non-empty string of at most " + std::to_string(max_length) + " characters";
}

std::string Text::parse(const Field& field) const {
    const auto value = field.text();
    if (!value || value->empty() || value->size() > max_length ||
        std::any_of(value->begin(), value->end(),
                    [](char c) { return static_cast<unsigned char>(c) < 0x20; })) {
        field.fail(describe());
    }
    return *value;
}

std::string Identifier::describe() const {
    return "a name of 1 to " + std::to_string(kMaxLength) + " characters from [a-z0-9_]";
}

std::string Identifier::parse(const Field& field) const {
    // Names are text by nature, so a plain `7` or `true` is taken as written.
    const YAML::Node& node = field.node();
    if (!node.IsScalar()) {
        field.fail(describe());
    }
    const std::string& value = node.Scalar();
    const bool valid = !value.empty() && value.size() <= kMaxLength &&
                       std::all_of(value.begin(), value.end(), [](char c) {
                           return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
                       });
    if (!valid) {
        field.fail(describe(), "'" + sanitise(value) + "'");
    }
    return value;
}

std::string File::describe() const {
    return "a path to a readable file, relative to this file's directory";
}

fs::path File::parse(const Field& field) const {
    const std::string written = Text{4096}.parse(field);
    fs::path path(written);
    if (path.is_relative()) {
        path = field.directory() / path;
    }
    std::error_code ec;
    fs::path absolute = fs::absolute(path, ec);
    if (!ec) {
        path = absolute;
    }
    path = path.lexically_normal();

    int error = 0;
    if (fs::is_directory(path, ec)) {
        error = EISDIR;
    } else if (std::FILE* probe = std::fopen(path.c_str(), "rb")) {
        std::fclose(probe);
    } else {
        error = errno;
    }
    if (error != 0) {
        field.fail(describe(), "'" + sanitise(written) + "' (" + path.string() + ": " +
                                   std::strerror(error) + ")");
    }
    return path;
}

std::string Range::describe() const {
    return "a [min, max] pair with min < max, each " + bounds.describe();
}

Interval Range::parse(const Field& field) const {
    const ListReader list = field.list(2, 2, bounds.describe() + ", min < max");
    const Interval out{bounds.parse(list.at(0)), bounds.parse(list.at(1))};
    if (!(out.min < out.max)) {
        field.fail(describe(), "[" + formatNumber(out.min) + ", " + formatNumber(out.max) + "]");
    }
    return out;
}

}  // namespace spec

}  // namespace haptic::config
