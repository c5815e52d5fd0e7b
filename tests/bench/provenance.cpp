#include "provenance.hpp"

#include <sys/utsname.h>
#include <unistd.h>

#include <cstdio>
#include <ctime>
#include <fstream>
#include <string>

namespace haptic::bench {
namespace {

std::string cpuModel() {
    std::ifstream cpuinfo("/proc/cpuinfo");
    std::string line;
    while (std::getline(cpuinfo, line)) {
        if (line.rfind("model name", 0) == 0) {
            const auto colon = line.find(':');
            return colon == std::string::npos ? line : line.substr(colon + 2);
        }
    }
    return "unknown CPU";
}

// Quotes an argument when a shell would split or expand it, so the line can be pasted back.
std::string shellQuoted(const std::string& arg) {
    if (!arg.empty() && arg.find_first_of(" \t\"'$`\\*?[]{}();&|<>") == std::string::npos) {
        return arg;
    }
    std::string quoted = "'";
    for (const char c : arg) {
        quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    }
    return quoted + "'";
}

}  // namespace

void printProvenance(int argc, char** argv) {
    std::string command;
    for (int i = 0; i < argc; ++i) {
        command += (i == 0 ? "" : " ") + shellQuoted(argv[i]);
    }
    char date[32] = "unknown";
    const std::time_t now = std::time(nullptr);
    std::tm utc{};
    if (gmtime_r(&now, &utc) != nullptr) {
        std::strftime(date, sizeof(date), "%Y-%m-%d %H:%M UTC", &utc);
    }
    utsname host{};
    ::uname(&host);
    std::printf("# command: %s\n# date: %s\n# machine: %s, Linux %s, %ld CPUs, %s\n",
                command.c_str(), date, host.nodename, host.release, ::sysconf(_SC_NPROCESSORS_ONLN),
                cpuModel().c_str());
    std::fflush(stdout);
}

}  // namespace haptic::bench
