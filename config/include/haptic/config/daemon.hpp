#pragma once

// hapticd's configuration (config/daemon.yaml). Loading it also loads and validates every
// device file it lists, so a daemon that starts has a complete, checked set of devices.

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "haptic/config/common.hpp"
#include "haptic/config/device.hpp"
#include "haptic/config/enums.hpp"

namespace haptic::config {

// libfranka's kEnforce/kIgnore: production refuses to start without SCHED_FIFO, mlockall and
// affinity; tests and CI opt out explicitly.
enum class RealtimeMode { kEnforce, kIgnore };

template <>
struct EnumTraits<RealtimeMode> {
    static constexpr std::array<EnumEntry<RealtimeMode>, 2> kEntries{{
        {"enforce", RealtimeMode::kEnforce},
        {"ignore", RealtimeMode::kIgnore},
    }};
};

// YAML: loop: {...}
struct LoopConfig {
    int rate_hz{1000};  // 100..4000
    RealtimeMode realtime{RealtimeMode::kEnforce};
    int priority{80};      // SCHED_FIFO priority, 1..99
    int cpu_affinity{-1};  // core index for the RT thread, -1 = no pinning
    // The CPUs' wake-up latency hapticd holds while it runs (/dev/cpu_dma_latency), -1: none.
    int cpu_latency_us{-1};
    int sim_timeout_ms{20};  // older sim input fades the force out
    // Sim input lost this long while RENDERING: the device renders again only after a new
    // `enable`, not by itself when the input returns.
    int sim_rearm_after_ms{1000};
    int status_rate_hz{20};       // haptic/status publication rate, 1..100
    int telemetry_decimation{1};  // haptic/telemetry every N ticks
    // This many overruns within overrun_window_ms are hapticd's fault 111; 0: off.
    int overrun_limit{100};
    int overrun_window_ms{1000};
};

// YAML: estop_relay: {...}. A safety relay's E-stop button on one of the devices' CAN buses
// (frame layout: haptic/protocol/estop_relay_protocol.hpp). Enabled, hapticd goes to E-STOP
// within a tick of a status saying "pressed" or of timeout_ms without a valid status, and
// `clear` is refused until the relay reports released again.
struct EstopRelayConfig {
    bool enabled{false};
    std::string bus_device;  // the device (by name) whose CAN bus carries the relay's status
    std::uint32_t status_id{0x0E0};
    int timeout_ms{30};
};

// hapticd's local control socket (docs/hapticctl.md): status and commands for this host's
// operators, each caller's rights from its peer credentials.
struct ControlConfig {
    // The socket is <socket_dir>/control-<dds.domain_id>.sock: hapticctl finds it from the
    // same file and domain, and daemons on other domains never share one.
    std::filesystem::path socket_dir{"/run/hapticd"};
    // Members (and root) may enable, disable, clear and choose the method; any local user
    // may read the status and send an E-stop.
    std::string operator_group{"haptic"};
};

struct DaemonConfig {
    std::filesystem::path source;
    LogLevel log_level{LogLevel::kInfo};
    LoopConfig loop;
    std::vector<DeviceConfig> devices;  // 1..4, names unique, CAN ids disjoint per interface
    EstopRelayConfig estop_relay;
    ControlConfig control;
    SimLinkConfig sim_link;
    DdsConfig dds;
    std::optional<IceoryxConfig> iceoryx;
};

// <control.socket_dir>/control-<dds.domain_id>.sock
[[nodiscard]] std::filesystem::path controlSocketPath(const DaemonConfig& config);

// Loads daemon.yaml and every device file it names. Throws ConfigError.
[[nodiscard]] DaemonConfig loadDaemonConfig(const std::filesystem::path& path);

// "sha256:<64 hex digits>" over the bytes of every file the configuration was loaded from:
// daemon.yaml, the DDS profiles file, then each device file in order. It names what a daemon
// runs with (status, recordings). Throws ConfigError when a file can no longer be read.
[[nodiscard]] std::string configurationDigest(const DaemonConfig& config);

}  // namespace haptic::config
