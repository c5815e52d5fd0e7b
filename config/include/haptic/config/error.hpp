#pragma once

#include <string>

#include "haptic/process/main_skeleton.hpp"

namespace haptic::config {

// The one exception every loader throws. what() is a single line that starts with
// "<file>:<line>:<col>: " so editors and CI logs can jump straight to the offending key;
// the accessors let tests and tools inspect the parts without parsing that line. The main
// skeleton reports it as "<program>: configuration error: <what()>".
class ConfigError : public process::LabelledError {
  public:
    // line and column are 1-based; 0 means "not known" and is left out of what().
    ConfigError(std::string file, int line, int column, std::string key, std::string message);

    // The path the loader opened: as given for the top-level file, resolved and absolute for
    // files that another file references.
    [[nodiscard]] const std::string& file() const noexcept { return file_; }
    [[nodiscard]] int line() const noexcept { return line_; }
    [[nodiscard]] int column() const noexcept { return column_; }
    // Dotted key path such as "loop.rate_hz" or "objects[1].radius_m"; empty for errors
    // about the file as a whole (unreadable, YAML syntax).
    [[nodiscard]] const std::string& key() const noexcept { return key_; }
    // what() without the "<file>:<line>:<col>: " prefix.
    [[nodiscard]] const std::string& message() const noexcept { return message_; }

  private:
    std::string file_;
    int line_;
    int column_;
    std::string key_;
    std::string message_;
};

}  // namespace haptic::config
