#include <algorithm>
#include <cstdio>
#include <string>

#include "haptic/config/daemon.hpp"
#include "schema.hpp"

namespace haptic::config {
namespace {

LoopConfig readLoop(MapReader map) {
    using spec::Integer;
    LoopConfig out;
    out.rate_hz = map.required("rate_hz", Integer<int>::closed(100, 4000));
    out.realtime = map.optional("realtime", RealtimeMode::kEnforce, spec::Enum<RealtimeMode>{});
    out.priority = map.optional("priority", 80, Integer<int>::closed(1, 99));
    out.cpu_affinity = map.optional("cpu_affinity", -1, Integer<int>::closed(-1, 1023));
    out.cpu_latency_us = map.optional("cpu_latency_us", -1, Integer<int>::closed(-1, 10'000));
    out.sim_timeout_ms = map.required("sim_timeout_ms", Integer<int>::closed(1, 1000));
    if (auto field = map.take("sim_rearm_after_ms")) {
        // Shorter than the timeout would demand an enable after every fade.
        out.sim_rearm_after_ms = Integer<int>::closed(out.sim_timeout_ms, 60'000).parse(*field);
    } else {
        out.sim_rearm_after_ms = std::max(out.sim_rearm_after_ms, out.sim_timeout_ms);
    }
    out.status_rate_hz = map.optional("status_rate_hz", 20, Integer<int>::closed(1, 100));
    out.telemetry_decimation =
        map.optional("telemetry_decimation", 1, Integer<int>::closed(1, 1000));
    out.overrun_limit =
        map.optional("overrun_limit", out.overrun_limit, Integer<int>::closed(0, 1000));
    out.overrun_window_ms =
        map.optional("overrun_window_ms", out.overrun_window_ms, Integer<int>::closed(1, 60'000));
    map.finish();
    return out;
}

// The relay's id must not be one a device on the same bus uses, and it must sit on a bus
// hapticd opens, so it names one of the devices.
EstopRelayConfig readEstopRelay(MapReader map, const std::vector<DeviceConfig>& devices) {
    EstopRelayConfig out;
    out.enabled = map.required("enabled", spec::Boolean{});
    auto [bus_device, bus_field] = map.requiredWithField("bus_device", spec::Text{});
    const auto bus = std::find_if(devices.begin(), devices.end(),
                                  [&](const DeviceConfig& d) { return d.name == bus_device; });
    if (bus == devices.end()) {
        std::string names;
        for (const auto& device : devices) {
            names += (names.empty() ? "'" : ", '") + device.name + "'";
        }
        bus_field.fail("the name of a device in devices (" + names + ")", "'" + bus_device + "'");
    }
    out.bus_device = bus_device;
    auto [status_id, id_field] =
        map.requiredWithField("status_id", spec::Integer<std::uint32_t>::hexClosed(0, 0x7FF));
    for (const auto& device : devices) {
        if (device.can.bus() != bus->can.bus()) {
            continue;
        }
        for (const std::uint32_t id : {device.can.command_id, device.can.state_id,
                                       device.can.heartbeat_id, device.can.fault_id}) {
            if (id == status_id) {
                char text[96];
                std::snprintf(text, sizeof(text), "0x%03x, a CAN id of device '%s'", id,
                              device.name.c_str());
                id_field.fail("a CAN id no device on the relay's bus uses", text);
            }
        }
    }
    out.status_id = status_id;
    // The relay sends every 10 ms: at least two periods, so one lost frame never trips it.
    out.timeout_ms = map.required("timeout_ms", spec::Integer<int>::closed(20, 1000));
    map.finish();
    return out;
}

ControlConfig readControl(MapReader map) {
    ControlConfig out;
    auto [dir, dir_field] = map.requiredWithField("socket_dir", spec::Text{});
    if (dir.empty() || dir.front() != '/') {
        dir_field.fail("an absolute directory path", "'" + dir + "'");
    }
    out.socket_dir = dir;
    out.operator_group = map.required("operator_group", spec::Text{});
    map.finish();
    return out;
}

}  // namespace

std::filesystem::path controlSocketPath(const DaemonConfig& config) {
    return config.control.socket_dir /
           ("control-" + std::to_string(config.dds.domain_id) + ".sock");
}

DaemonConfig loadDaemonConfig(const std::filesystem::path& path) {
    MapReader root = MapReader::openFile(path);
    DaemonConfig out;
    out.source = path;
    out.log_level = detail::readLogLevel(root);
    out.loop = readLoop(root.requiredMap("loop"));
    out.devices = detail::readDeviceList(detail::requiredDeviceList(root), out.loop.rate_hz);
    if (auto relay = root.optionalMap("estop_relay")) {
        out.estop_relay = readEstopRelay(std::move(*relay), out.devices);
    }
    if (auto control = root.optionalMap("control")) {
        out.control = readControl(std::move(*control));
    }
    detail::readTransports(root, out);
    root.finish();
    return out;
}

}  // namespace haptic::config
