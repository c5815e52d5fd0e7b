#include <algorithm>

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

}  // namespace

DaemonConfig loadDaemonConfig(const std::filesystem::path& path) {
    MapReader root = MapReader::openFile(path);
    DaemonConfig out;
    out.source = path;
    out.log_level = detail::readLogLevel(root);
    out.loop = readLoop(root.requiredMap("loop"));
    out.devices = detail::readDeviceList(detail::requiredDeviceList(root), out.loop.rate_hz);
    detail::readTransports(root, out);
    root.finish();
    return out;
}

}  // namespace haptic::config
