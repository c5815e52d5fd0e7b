#pragma once

// Pieces shared by the daemon and sim configs.

#include <array>
#include <filesystem>
#include <string>

#include "haptic/config/enums.hpp"

namespace haptic::config {

enum class LogLevel { kTrace, kDebug, kInfo, kWarn, kError };

template <>
struct EnumTraits<LogLevel> {
    static constexpr std::array<EnumEntry<LogLevel>, 5> kEntries{{
        {"trace", LogLevel::kTrace},
        {"debug", LogLevel::kDebug},
        {"info", LogLevel::kInfo},
        {"warn", LogLevel::kWarn},
        {"error", LogLevel::kError},
    }};
};

// How ConstraintSet/ContactSurface/DeviceState travel between handsim and hapticd:
// iceoryx when both run on one host, DDS when the sim runs on another machine.
enum class SimTransport { kIceoryx, kDds };

template <>
struct EnumTraits<SimTransport> {
    static constexpr std::array<EnumEntry<SimTransport>, 2> kEntries{{
        {"iceoryx", SimTransport::kIceoryx},
        {"dds", SimTransport::kDds},
    }};
};

// YAML: sim_link: {transport: iceoryx|dds}
struct SimLinkConfig {
    SimTransport transport{SimTransport::kIceoryx};
};

// YAML: dds: {domain_id, profiles_file, participant_profile}
struct DdsConfig {
    int domain_id{0};                     // 0..232, the range Fast DDS maps to valid UDP ports
    std::filesystem::path profiles_file;  // Fast DDS XML profiles, absolute
    std::string participant_profile;      // a <participant profile_name> in profiles_file
};

// YAML: iceoryx: {roudi_config}: the RouDi configuration the process's RouDi must be started
// with. hapticd and handsim check at start that its mempools carry their messages
// (haptic::ipc::checkRoudiConfig); they do not start RouDi.
struct IceoryxConfig {
    std::filesystem::path roudi_config;  // absolute
};

}  // namespace haptic::config
