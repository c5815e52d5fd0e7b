#include "open_files.hpp"

#include <filesystem>
#include <fstream>

namespace haptic::testing {

int openCount(pid_t pid, const std::string& file) {
    namespace fs = std::filesystem;
    int count = 0;
    std::error_code error;
    // A process can end, and its descriptors go, during the walk: the error_code forms never
    // throw, and the count stops there.
    for (fs::directory_iterator fd(fs::path("/proc") / std::to_string(pid) / "fd", error);
         !error && fd != fs::directory_iterator(); fd.increment(error)) {
        std::error_code link_error;
        if (fs::read_symlink(fd->path(), link_error) == fs::path(file)) {
            ++count;
        }
    }
    return count;
}

bool holdsOpen(pid_t pid, const std::string& file) {
    return openCount(pid, file) > 0;
}

std::optional<std::int32_t> readCpuLatencyUs(const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    std::int32_t value = 0;
    in.read(reinterpret_cast<char*>(&value), sizeof(value));
    if (in.gcount() != static_cast<std::streamsize>(sizeof(value))) {
        return std::nullopt;
    }
    return value;
}

}  // namespace haptic::testing
