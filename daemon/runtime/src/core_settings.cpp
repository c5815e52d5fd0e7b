#include "haptic/runtime/core_settings.hpp"

#include <string>
#include <utility>

namespace haptic::runtime {

daemon::CoreSettings coreSettings(const config::DaemonConfig& cfg, std::string_view version) {
    daemon::CoreSettings settings;
    settings.version = std::string(version);
    settings.config_digest = config::configurationDigest(cfg);
    settings.rate_hz = cfg.loop.rate_hz;
    settings.telemetry_decimation = static_cast<std::uint32_t>(cfg.loop.telemetry_decimation);
    settings.overrun_limit = static_cast<std::uint32_t>(cfg.loop.overrun_limit);
    settings.overrun_window_ns = static_cast<std::int64_t>(cfg.loop.overrun_window_ms) * 1'000'000;
    settings.sim_timeout_ns = static_cast<std::int64_t>(cfg.loop.sim_timeout_ms) * 1'000'000;
    settings.sim_rearm_after_ns =
        static_cast<std::int64_t>(cfg.loop.sim_rearm_after_ms) * 1'000'000;
    settings.status_period_ns = 1'000'000'000LL / cfg.loop.status_rate_hz;
    settings.sim_transport = cfg.sim_link.transport == config::SimTransport::kDds
                                 ? msgs::SimTransport::kDds
                                 : msgs::SimTransport::kIceoryx;
    for (const auto& entry : config::EnumTraits<config::RenderingMethod>::kEntries) {
        settings.known_methods.emplace_back(entry.name);
    }
    for (const auto& device : cfg.devices) {
        const std::int64_t command_timeout_ns =
            static_cast<std::int64_t>(device.can.command_timeout_ms) * 1'000'000;
        if (settings.stall_limit_ns == 0 || command_timeout_ns < settings.stall_limit_ns) {
            settings.stall_limit_ns = command_timeout_ns;
        }
    }
    for (const auto& device : cfg.devices) {
        if (device.isExoskeleton()) {
            settings.rendering_method =
                std::string(config::toString(device.exoskeleton().rendering.method));
            break;
        }
    }
    return settings;
}

std::vector<daemon::DeviceDescriptor> deviceDescriptors(const config::DaemonConfig& cfg) {
    std::vector<daemon::DeviceDescriptor> devices;
    for (const auto& device : cfg.devices) {
        daemon::DeviceDescriptor descriptor;
        descriptor.name = device.name;
        if (device.isExoskeleton()) {
            descriptor.kind = msgs::DeviceKind::kExoskeleton;
            descriptor.joint_count = 3;  // MCP, PIP, DIP of the planar finger
            descriptor.actuator_count = 1;
        } else {
            descriptor.kind = msgs::DeviceKind::kThimble;
            descriptor.joint_count = 3;  // three servo angles
            descriptor.actuator_count = 3;
        }
        devices.push_back(std::move(descriptor));
    }
    return devices;
}

}  // namespace haptic::runtime
