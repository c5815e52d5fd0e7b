#include "haptic/process/logging.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/sinks/systemd_sink.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <stdexcept>

namespace haptic::process {

bool runningUnderJournal() {
    // systemd sets JOURNAL_STREAM=<dev>:<inode> for a service whose stderr is the journal;
    // comparing it with our stderr avoids logging to the journal from a child whose stderr
    // was redirected elsewhere.
    const char* stream = std::getenv("JOURNAL_STREAM");
    if (stream == nullptr) {
        return false;
    }
    unsigned long long device = 0;
    unsigned long long inode = 0;
    if (std::sscanf(stream, "%llu:%llu", &device, &inode) != 2) {
        return false;
    }
    struct stat info {};
    return ::fstat(STDERR_FILENO, &info) == 0 && info.st_dev == device && info.st_ino == inode;
}

void setupLogging(std::string_view program_name, std::string_view level) {
    const auto parsed = spdlog::level::from_str(std::string(level));
    // from_str maps unknown names to "off"; only the literal "off" may mean off.
    if (parsed == spdlog::level::off && level != "off") {
        throw std::invalid_argument("unknown log level '" + std::string(level) + "' (expected " +
                                    std::string(kLogLevels) + ")");
    }
    std::shared_ptr<spdlog::logger> logger;
    if (runningUnderJournal()) {
        auto sink = std::make_shared<spdlog::sinks::systemd_sink_mt>();
        logger = std::make_shared<spdlog::logger>(std::string(program_name), sink);
        logger->set_pattern("%v");  // the journal stamps and tags records itself
    } else {
        logger = spdlog::stderr_color_mt(std::string(program_name));
        logger->set_pattern("%Y-%m-%d %H:%M:%S.%e %n[%P] %^%l%$: %v");
    }
    logger->set_level(parsed);
    logger->flush_on(spdlog::level::warn);
    spdlog::set_default_logger(logger);
}

}  // namespace haptic::process
