#include "test_support.hpp"

#include <fstream>
#include <string>

namespace haptic::config::test {

std::string resolved(const std::filesystem::path& path) {
    return std::filesystem::absolute(path).lexically_normal().string();
}

int lineOf(const std::filesystem::path& file, std::string_view needle) {
    std::ifstream in(file);
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
        if (line.find(needle) != std::string::npos) {
            return number;
        }
    }
    ADD_FAILURE() << "'" << needle << "' not found in " << file;
    return -1;
}

std::optional<ConfigError> configErrorOf(const std::function<void()>& load) {
    try {
        load();
    } catch (const ConfigError& e) {
        return e;
    } catch (const std::exception& e) {
        ADD_FAILURE() << "expected ConfigError, got another exception: " << e.what();
        return std::nullopt;
    }
    ADD_FAILURE() << "expected ConfigError, nothing was thrown";
    return std::nullopt;
}

}  // namespace haptic::config::test
