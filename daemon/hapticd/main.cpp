// hapticd: the hard real-time haptic daemon. See docs/hapticd.md.

#include <CLI/CLI.hpp>
#include <string>

#include "daemon_app.hpp"
#include "haptic/config/command_line.hpp"
#include "haptic/config/daemon.hpp"
#include "haptic/process/logging.hpp"
#include "haptic/process/main_skeleton.hpp"
#include "haptic/process/shutdown.hpp"

int main(int argc, char** argv) {
    CLI::App app{"hapticd - hard real-time haptic rendering daemon (1 kHz)"};
    haptic::config::CommonOverrides overrides;
    overrides.config_path = HAPTIC_DEFAULT_CONFIG_DIR "/daemon.yaml";
    haptic::config::addCommonOptions(app, overrides, "daemon configuration file");
    std::string realtime;
    app.add_option("--realtime", realtime,
                   "override loop.realtime: 'enforce' refuses to run without SCHED_FIFO and "
                   "mlockall, 'ignore' runs anyway (tests, VMs)")
        ->check(CLI::IsMember({"enforce", "ignore"}));
    CLI11_PARSE(app, argc, argv);

    return haptic::process::runMain("hapticd", [&] {
        haptic::hapticd::DaemonOptions options;
        options.config = haptic::config::loadDaemonConfig(overrides.config_path);
        options.duration_s = overrides.duration_s;
        const std::string log_level = applyCommonOverrides(overrides, options.config);
        if (!realtime.empty()) {
            options.config.loop.realtime = realtime == "enforce"
                                               ? haptic::config::RealtimeMode::kEnforce
                                               : haptic::config::RealtimeMode::kIgnore;
        }
        haptic::process::setupLogging("hapticd", log_level);
        haptic::process::installShutdownHandlers();
        return haptic::hapticd::runDaemon(options);
    });
}
