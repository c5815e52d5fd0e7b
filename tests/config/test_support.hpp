#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "haptic/config/error.hpp"

namespace haptic::config::test {

inline const std::filesystem::path kDataDir = HAPTIC_TEST_DATA_DIR;
inline const std::filesystem::path kConfigDir = HAPTIC_CONFIG_DIR;

// The name a referenced file has in errors and structs: absolute and normalised.
std::string resolved(const std::filesystem::path& path);

// 1-based number of the first line of `file` containing `needle`. Tests locate expected
// error lines this way so they stay exact when a data file gains a line.
int lineOf(const std::filesystem::path& file, std::string_view needle);

// Runs `load` and returns the ConfigError it throws, or nullopt (and a test failure) when it
// throws nothing or something else.
std::optional<ConfigError> configErrorOf(const std::function<void()>& load);

}  // namespace haptic::config::test
