#include "haptic/config/error.hpp"

#include <string>
#include <utility>

namespace haptic::config {
namespace {

std::string formatWhat(const std::string& file, int line, int column, const std::string& message) {
    std::string out = file;
    if (line > 0) {
        out += ':' + std::to_string(line);
        if (column > 0) {
            out += ':' + std::to_string(column);
        }
    }
    out += ": ";
    out += message;
    return out;
}

}  // namespace

ConfigError::ConfigError(std::string file, int line, int column, std::string key,
                         std::string message)
    : process::LabelledError("configuration error", formatWhat(file, line, column, message)),
      file_(std::move(file)),
      line_(line),
      column_(column),
      key_(std::move(key)),
      message_(std::move(message)) {}

}  // namespace haptic::config
