#include "haptic/config/reader.hpp"

#include <algorithm>
#include <cassert>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <string_view>
#include <system_error>
#include <vector>

#include "scalar.hpp"

namespace haptic::config {
namespace {

namespace fs = std::filesystem;
using detail::classify;
using detail::Kind;
using detail::sanitise;
using detail::Scalar;

// Edits (insert, delete, substitute, swap two neighbours) from a to b, or `limit` + 1 once
// the distance exceeds `limit`: enough to tell a misspelt key from another key.
std::size_t editDistance(std::string_view a, std::string_view b, std::size_t limit) {
    const std::size_t n = a.size();
    const std::size_t m = b.size();
    if ((n > m ? n - m : m - n) > limit) {
        return limit + 1;
    }
    std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1, 0));
    for (std::size_t i = 0; i <= n; ++i) {
        d[i][0] = i;
    }
    for (std::size_t j = 0; j <= m; ++j) {
        d[0][j] = j;
    }
    for (std::size_t i = 1; i <= n; ++i) {
        for (std::size_t j = 1; j <= m; ++j) {
            const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
            d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
                d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
            }
        }
    }
    return std::min(d[n][m], limit + 1);
}

}  // namespace

// --- Field -------------------------------------------------------------------------------

Field::Field(YAML::Node node, std::shared_ptr<const std::string> file, std::string key,
             YAML::Mark mark_if_null)
    : node_(std::move(node)), file_(std::move(file)), key_(std::move(key)) {
    YAML::Mark mark = node_.Mark();
    if (node_.IsNull() || mark.is_null()) {
        mark = mark_if_null;
    }
    line_ = mark.is_null() ? 0 : mark.line + 1;
    column_ = mark.is_null() ? 0 : mark.column + 1;
}

fs::path Field::directory() const {
    fs::path dir = fs::path(*file_).parent_path();
    return dir.empty() ? fs::path(".") : dir;
}

std::string Field::describe() const {
    const Scalar scalar = classify(node_);
    switch (scalar.kind) {
        case Kind::kNull:
            return "nothing (null)";
        case Kind::kMap:
            return "a map";
        case Kind::kList:
            return node_.size() == 1 ? "a list of 1 item"
                                     : "a list of " + std::to_string(node_.size()) + " items";
        case Kind::kString:
            return "the string '" + sanitise(node_.Scalar()) + "'";
        case Kind::kNonFinite:
            return sanitise(node_.Scalar()) + " (not a finite number)";
        default:
            return sanitise(node_.Scalar());
    }
}

std::optional<std::string> Field::text() const {
    if (classify(node_).kind != Kind::kString) {
        return std::nullopt;
    }
    return node_.Scalar();
}

void Field::fail(std::string_view expected) const {
    fail(expected, describe());
}

void Field::fail(std::string_view expected, std::string_view got) const {
    std::string message = key_.empty() ? std::string() : key_ + ": ";
    message += "expected ";
    message += expected;
    message += ", got ";
    message += got;
    failWith(std::move(message));
}

void Field::failWith(std::string message) const {
    throw ConfigError(*file_, line_, column_, key_, std::move(message));
}

MapReader Field::map() const {
    return MapReader(*this);
}

ListReader Field::list(std::size_t min_size, std::size_t max_size, std::string_view item) const {
    if (!node_.IsSequence() || node_.size() < min_size || node_.size() > max_size) {
        fail(describeList(min_size, max_size, item));
    }
    return ListReader(*this);
}

std::string formatNumber(double value) {
    char buffer[64];
    const auto [end, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
    return ec == std::errc{} ? std::string(buffer, end) : std::string("?");
}

std::string describeList(std::size_t min_size, std::size_t max_size, std::string_view item) {
    std::string out = "a list of ";
    if (min_size == max_size) {
        out += std::to_string(min_size);
    } else if (max_size == std::numeric_limits<std::size_t>::max()) {
        out += "at least " + std::to_string(min_size);
    } else {
        out += std::to_string(min_size) + " to " + std::to_string(max_size);
    }
    out += max_size == 1 ? " item, each " : " items, each ";
    out += item;
    return out;
}

// --- ListReader ----------------------------------------------------------------------------

ListReader::ListReader(Field self) : self_(std::move(self)) {
    if (!self_.node().IsSequence()) {
        self_.fail("a list");
    }
}

Field ListReader::at(std::size_t index) const {
    const YAML::Node& node = self_.node();
    YAML::Mark fallback;
    fallback.line = self_.line() - 1;
    fallback.column = self_.column() - 1;
    return Field(node[index], self_.fileHandle(), self_.key() + "[" + std::to_string(index) + "]",
                 fallback);
}

// --- MapReader -----------------------------------------------------------------------------

MapReader MapReader::openFile(const fs::path& path) {
    const std::string name = path.string();
    auto file = std::make_shared<const std::string>(name);

    std::error_code ec;
    if (fs::is_directory(path, ec)) {
        throw ConfigError(name, 0, 0, "", std::string("cannot read: ") + std::strerror(EISDIR));
    }
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> handle(std::fopen(name.c_str(), "rb"),
                                                           &std::fclose);
    if (!handle) {
        const int error = errno;
        throw ConfigError(name, 0, 0, "", std::string("cannot open: ") + std::strerror(error));
    }
    std::string content;
    char buffer[4096];
    std::size_t n = 0;
    while ((n = std::fread(buffer, 1, sizeof(buffer), handle.get())) > 0) {
        content.append(buffer, n);
    }
    if (std::ferror(handle.get()) != 0) {
        const int error = errno;
        throw ConfigError(name, 0, 0, "", std::string("cannot read: ") + std::strerror(error));
    }

    std::vector<YAML::Node> documents;
    try {
        documents = YAML::LoadAll(content);
    } catch (const YAML::Exception& e) {
        const int line = e.mark.is_null() ? 0 : e.mark.line + 1;
        const int column = e.mark.is_null() ? 0 : e.mark.column + 1;
        throw ConfigError(name, line, column, "", "YAML syntax error: " + e.msg);
    }
    if (documents.empty()) {
        throw ConfigError(name, 0, 0, "", "expected a map of settings, got an empty file");
    }
    if (documents.size() > 1) {
        const Field second(documents[1], file, "", documents[1].Mark());
        second.failWith("expected a single YAML document, got " + std::to_string(documents.size()));
    }
    YAML::Mark start;
    start.line = 0;
    start.column = 0;
    const Field root(documents[0], file, "", start);
    if (!root.node().IsMap()) {
        root.fail("a map of settings");
    }
    return MapReader(root);
}

MapReader::MapReader(Field self) : self_(std::move(self)) {
    const YAML::Node& node = self_.node();
    if (!node.IsMap()) {
        self_.fail("a map");
    }
    // Copies, not references: yaml-cpp's iterator hands out pairs of Nodes by value.
    for (const auto& pair : node) {
        const YAML::Node key_node = pair.first;
        const YAML::Node value_node = pair.second;
        if (!key_node.IsScalar()) {
            Field(key_node, self_.fileHandle(), self_.key(), key_node.Mark())
                .fail("a plain key", "a complex key");
        }
        const std::string& name = key_node.Scalar();
        Field key(key_node, self_.fileHandle(), childKey(name), key_node.Mark());
        if (const Entry* first = find(name)) {
            key.failWith(key.key() + ": expected each key once, got it again (first at line " +
                         std::to_string(first->key.line()) + ")");
        }
        Field value(value_node, self_.fileHandle(), childKey(name), key_node.Mark());
        entries_.push_back(Entry{name, std::move(key), std::move(value), false});
    }
}

MapReader::MapReader(MapReader&& other) noexcept
    : self_(std::move(other.self_)),
      entries_(std::move(other.entries_)),
      allowed_(std::move(other.allowed_)),
      finished_(other.finished_) {
    other.finished_ = true;
}

MapReader& MapReader::operator=(MapReader&& other) noexcept {
    self_ = std::move(other.self_);
    entries_ = std::move(other.entries_);
    allowed_ = std::move(other.allowed_);
    finished_ = other.finished_;
    other.finished_ = true;
    return *this;
}

MapReader::~MapReader() {
    // A schema that forgets finish() silently accepts typos in that map.
    assert(finished_ || std::uncaught_exceptions() > 0);
}

std::string MapReader::childKey(std::string_view key) const {
    return self_.key().empty() ? std::string(key) : self_.key() + "." + std::string(key);
}

MapReader::Entry* MapReader::find(std::string_view key) {
    const auto it = std::find_if(entries_.begin(), entries_.end(),
                                 [&](const Entry& entry) { return entry.name == key; });
    return it == entries_.end() ? nullptr : &*it;
}

void MapReader::allow(std::string_view key) {
    if (std::find(allowed_.begin(), allowed_.end(), key) == allowed_.end()) {
        allowed_.emplace_back(key);
    }
}

bool MapReader::contains(std::string_view key) {
    allow(key);
    return find(key) != nullptr;
}

std::optional<Field> MapReader::take(std::string_view key) {
    allow(key);
    Entry* entry = find(key);
    if (entry == nullptr) {
        return std::nullopt;
    }
    entry->consumed = true;
    return entry->value;
}

Field MapReader::takeRequired(std::string_view key, std::string_view expected) {
    if (auto field = take(key)) {
        return *std::move(field);
    }
    const std::string full = childKey(key);
    std::string message = "missing required key '" + full + "' (" + std::string(expected) + ")";
    // A key of this map no reader has taken yet that is one or two edits away is most likely
    // the same key misspelt: name it, or the operator hunts for a key that is "there".
    for (const Entry& entry : entries_) {
        if (!entry.consumed && editDistance(entry.name, key, 2) <= 2) {
            message += "; is '" + entry.name + "' (line " + std::to_string(entry.key.line()) +
                       ") a misspelling of it?";
            break;
        }
    }
    throw ConfigError(self_.file(), self_.line(), 0, full, message);
}

MapReader MapReader::requiredMap(std::string_view key) {
    return MapReader(takeRequired(key, "a map"));
}

std::optional<MapReader> MapReader::optionalMap(std::string_view key) {
    if (auto field = take(key)) {
        return MapReader(*std::move(field));
    }
    return std::nullopt;
}

ListReader MapReader::requiredList(std::string_view key, std::size_t min_size, std::size_t max_size,
                                   std::string_view item) {
    return takeRequired(key, describeList(min_size, max_size, item)).list(min_size, max_size, item);
}

std::vector<std::pair<Field, Field>> MapReader::takeAll() {
    std::vector<std::pair<Field, Field>> out;
    for (Entry& entry : entries_) {
        entry.consumed = true;
        out.emplace_back(entry.key, entry.value);
    }
    return out;
}

void MapReader::finish() {
    finished_ = true;
    std::vector<const Entry*> unknown;
    for (const Entry& entry : entries_) {
        if (!entry.consumed) {
            unknown.push_back(&entry);
        }
    }
    if (unknown.empty()) {
        return;
    }
    std::string allowed;
    for (const std::string& key : allowed_) {
        allowed += (allowed.empty() ? "" : ", ") + key;
    }
    const Field& first = unknown.front()->key;
    std::string message = "unknown key '" + first.key() +
                          "' (allowed: " + (allowed.empty() ? std::string("none") : allowed) + ")";
    for (std::size_t i = 1; i < unknown.size(); ++i) {
        message += (i == 1 ? "; also unknown: '" : ", '") + unknown[i]->key.key() + "' (line " +
                   std::to_string(unknown[i]->key.line()) + ")";
    }
    first.failWith(std::move(message));
}
}  // namespace haptic::config
