#pragma once

// A small validating reader on top of yaml-cpp. yaml-cpp alone converts leniently ("yes" is
// a bool, 1.5 truncates to an int through some paths, duplicate keys are silently accepted)
// and its errors carry no key path, so every schema goes through these classes instead:
//
//   MapReader loop = root.requiredMap("loop");
//   cfg.rate_hz = loop.required("rate_hz", spec::Integer<int>::closed(100, 4000));
//   cfg.realtime = loop.optional("realtime", RealtimeMode::kEnforce, spec::Enum<RealtimeMode>{});
//   loop.finish();  // any key not asked for above is reported as unknown
//
// Each spec:: type says what a value must be (describe()) and converts a Field into a C++
// value or throws ConfigError (parse()). Adding a new kind of value means adding a spec.

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "haptic/config/enums.hpp"
#include "haptic/config/error.hpp"
#include "haptic/config/types.hpp"

namespace haptic::config {

class MapReader;
class ListReader;

// One YAML node together with the file it came from and its dotted key path, so anything
// wrong with it can be reported as "<file>:<line>:<col>: <key>: expected ..., got ...".
class Field {
  public:
    // mark_if_null is used when the node is null: yaml-cpp puts the mark of an empty value
    // on the next line, so the key's own mark is the useful one.
    Field(YAML::Node node, std::shared_ptr<const std::string> file, std::string key,
          YAML::Mark mark_if_null);

    [[nodiscard]] const YAML::Node& node() const noexcept { return node_; }
    [[nodiscard]] const std::string& file() const noexcept { return *file_; }
    [[nodiscard]] const std::shared_ptr<const std::string>& fileHandle() const noexcept {
        return file_;
    }
    [[nodiscard]] const std::string& key() const noexcept { return key_; }
    [[nodiscard]] int line() const noexcept { return line_; }      // 1-based
    [[nodiscard]] int column() const noexcept { return column_; }  // 1-based
    // Base directory for relative paths written in this file.
    [[nodiscard]] std::filesystem::path directory() const;

    // How the value reads in an error message: 1.5, .nan, true, the string 'fast', a map,
    // a list of 2 items, nothing (null).
    [[nodiscard]] std::string describe() const;
    // The text of a string scalar; nullopt for numbers, booleans, null, maps and lists
    // (a quoted "42" is a string, a plain 42 is not).
    [[nodiscard]] std::optional<std::string> text() const;

    // Throw "<key>: expected <expected>, got <describe() or got>".
    [[noreturn]] void fail(std::string_view expected) const;
    [[noreturn]] void fail(std::string_view expected, std::string_view got) const;
    // Throw with a message of the caller's own wording, located at this field.
    [[noreturn]] void failWith(std::string message) const;

    template <typename Spec>
    [[nodiscard]] typename Spec::Value as(const Spec& spec) const {
        return spec.parse(*this);
    }
    [[nodiscard]] MapReader map() const;
    // item describes one element for the error message, e.g. "a path to a device file".
    [[nodiscard]] ListReader list(std::size_t min_size, std::size_t max_size,
                                  std::string_view item) const;

  private:
    YAML::Node node_;
    std::shared_ptr<const std::string> file_;
    std::string key_;
    int line_;
    int column_;
};

// Shortest text that reads back as the same double (0.1, not 0.10000000000000001).
[[nodiscard]] std::string formatNumber(double value);

// "a list of 3 items, each <item>", "a list of 1 to 4 items, each <item>".
[[nodiscard]] std::string describeList(std::size_t min_size, std::size_t max_size,
                                       std::string_view item);

namespace spec {

// A finite number within [min, max]; either end may be open. Integers are accepted.
struct Real {
    using Value = double;

    double min = std::numeric_limits<double>::lowest();
    double max = std::numeric_limits<double>::max();
    bool min_open = false;
    bool max_open = false;

    static constexpr Real closed(double lo, double hi) { return Real{lo, hi, false, false}; }
    // (0, hi]: lengths, masses, stiffnesses, anything where zero is meaningless.
    static constexpr Real positive(double hi) { return Real{0.0, hi, true, false}; }

    [[nodiscard]] bool contains(double value) const noexcept;
    [[nodiscard]] std::string describe() const;
    [[nodiscard]] double parse(const Field& field) const;
};

// Shared, non-template part of Integer<T>.
std::int64_t parseInteger(const Field& field, std::int64_t min, std::int64_t max,
                          const std::string& expected);
std::string describeInteger(std::int64_t min, std::int64_t max, bool hex);

// An integer within [min, max], written in decimal or as 0x hex / 0o octal. A float such
// as 1000.0 is rejected: an integer key holding a fraction is almost always a mistake.
template <typename T = int>
struct Integer {
    using Value = T;

    T min;
    T max;
    bool hex = false;  // show the range in hex in messages (CAN ids)

    static constexpr Integer closed(T lo, T hi) { return Integer{lo, hi, false}; }
    static constexpr Integer hexClosed(T lo, T hi) { return Integer{lo, hi, true}; }

    [[nodiscard]] std::string describe() const {
        return describeInteger(static_cast<std::int64_t>(min), static_cast<std::int64_t>(max), hex);
    }
    [[nodiscard]] T parse(const Field& field) const {
        return static_cast<T>(parseInteger(field, static_cast<std::int64_t>(min),
                                           static_cast<std::int64_t>(max), describe()));
    }
};

// true or false only: YAML 1.1's yes/no/on/off are rejected rather than guessed at.
struct Boolean {
    using Value = bool;
    [[nodiscard]] std::string describe() const;
    [[nodiscard]] bool parse(const Field& field) const;
};

// A non-empty string scalar without control characters.
struct Text {
    using Value = std::string;
    std::size_t max_length = 255;
    [[nodiscard]] std::string describe() const;
    [[nodiscard]] std::string parse(const Field& field) const;
};

// A device, object or scene name: [a-z0-9_], 1 to 31 characters, so it fits the 32-byte id
// fields of the messages and is safe in topic names and log lines.
struct Identifier {
    using Value = std::string;
    static constexpr std::size_t kMaxLength = 31;
    [[nodiscard]] std::string describe() const;
    [[nodiscard]] std::string parse(const Field& field) const;
};

// A path to a readable regular file. A relative path starts at the directory of the file
// that names it, not at the working directory, so configs can be moved as a tree.
// The value is absolute and lexically normalised.
struct File {
    using Value = std::filesystem::path;
    [[nodiscard]] std::string describe() const;
    [[nodiscard]] std::filesystem::path parse(const Field& field) const;
};

// One of the names in EnumTraits<E>.
template <NamedEnum E>
struct Enum {
    using Value = E;
    [[nodiscard]] std::string describe() const { return "one of " + enumChoices<E>(); }
    [[nodiscard]] E parse(const Field& field) const {
        if (const auto name = field.text()) {
            if (const auto value = enumFromString<E>(*name)) {
                return *value;
            }
        }
        field.fail(describe());
    }
};

// Exactly N elements, each validated by `element`: [x, y, z] vectors and the like.
template <typename Element, std::size_t N>
struct Array {
    using Value = std::array<typename Element::Value, N>;

    Element element;

    [[nodiscard]] std::string describe() const { return describeList(N, N, element.describe()); }
    [[nodiscard]] Value parse(const Field& field) const;
};

template <std::size_t N>
using Reals = Array<Real, N>;

// A [min, max] pair of numbers within `bounds`, with min < max.
struct Range {
    using Value = Interval;
    Real bounds;
    [[nodiscard]] std::string describe() const;
    [[nodiscard]] Interval parse(const Field& field) const;
};

}  // namespace spec

// Iterates a YAML sequence; elements are Fields with keys like "devices[2]".
class ListReader {
  public:
    explicit ListReader(Field self);

    [[nodiscard]] std::size_t size() const noexcept { return self_.node().size(); }
    [[nodiscard]] Field at(std::size_t index) const;
    [[nodiscard]] const Field& self() const noexcept { return self_; }

  private:
    Field self_;
};

// Reads one YAML map. Every key the schema asks for (present or not) is remembered, and
// finish() reports any key in the file that was never asked for, together with the list of
// keys that are allowed there. Duplicate keys are rejected on construction.
class MapReader {
  public:
    // Reads `path` as a single YAML document whose root is a map. Throws ConfigError with
    // strerror() when the file cannot be read and with yaml-cpp's message on a syntax error.
    static MapReader openFile(const std::filesystem::path& path);

    explicit MapReader(Field self);
    MapReader(const MapReader&) = delete;
    MapReader& operator=(const MapReader&) = delete;
    MapReader(MapReader&& other) noexcept;
    MapReader& operator=(MapReader&& other) noexcept;
    ~MapReader();

    [[nodiscard]] const Field& self() const noexcept { return self_; }
    [[nodiscard]] std::string childKey(std::string_view key) const;

    // Whether `key` is present. Registers it as allowed but does not consume it.
    [[nodiscard]] bool contains(std::string_view key);
    // The value of `key`, consumed, or nullopt when absent.
    [[nodiscard]] std::optional<Field> take(std::string_view key);
    // The value of `key`, consumed; throws "missing required key" naming `expected`.
    [[nodiscard]] Field takeRequired(std::string_view key, std::string_view expected);

    template <typename Spec>
    [[nodiscard]] typename Spec::Value required(std::string_view key, const Spec& spec) {
        return spec.parse(takeRequired(key, spec.describe()));
    }
    // For cross-field checks that need to point at the value afterwards.
    template <typename Spec>
    [[nodiscard]] std::pair<typename Spec::Value, Field> requiredWithField(std::string_view key,
                                                                           const Spec& spec) {
        Field field = takeRequired(key, spec.describe());
        auto value = spec.parse(field);
        return {std::move(value), std::move(field)};
    }
    template <typename Spec>
    [[nodiscard]] typename Spec::Value optional(std::string_view key, typename Spec::Value fallback,
                                                const Spec& spec) {
        if (auto field = take(key)) {
            return spec.parse(*field);
        }
        return fallback;
    }

    [[nodiscard]] MapReader requiredMap(std::string_view key);
    [[nodiscard]] std::optional<MapReader> optionalMap(std::string_view key);
    [[nodiscard]] ListReader requiredList(std::string_view key, std::size_t min_size,
                                          std::size_t max_size, std::string_view item);

    // For maps whose keys are data rather than schema (device bindings by device name):
    // consumes every entry and returns (key, value) pairs in file order.
    [[nodiscard]] std::vector<std::pair<Field, Field>> takeAll();

    // Throws on the first key that was never asked for. Call it once all keys are read.
    void finish();

  private:
    struct Entry {
        std::string name;
        Field key;
        Field value;
        bool consumed;
    };

    Entry* find(std::string_view key);
    void allow(std::string_view key);

    Field self_;
    std::vector<Entry> entries_;
    std::vector<std::string> allowed_;
    bool finished_ = false;
};

template <typename Element, std::size_t N>
typename spec::Array<Element, N>::Value spec::Array<Element, N>::parse(const Field& field) const {
    const ListReader list = field.list(N, N, element.describe());
    Value out{};
    for (std::size_t i = 0; i < N; ++i) {
        out[i] = element.parse(list.at(i));
    }
    return out;
}

}  // namespace haptic::config
