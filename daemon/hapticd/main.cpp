// hapticd: the hard real-time haptic daemon. See docs/hapticd.md.

#include <CLI/CLI.hpp>
#include <string>

#include "daemon_app.hpp"
#include "haptic/config/command_line.hpp"
#include "haptic/config/daemon.hpp"
#include "haptic/process/main_skeleton.hpp"

int main(int argc, char** argv) {
    CLI::App app{"hapticd - hard real-time haptic rendering daemon (1 kHz)"};
    app.set_version_flag("--version", "hapticd " HAPTIC_VERSION);
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
        using haptic::config::DaemonConfig;
        if (overrides.check_only) {
            return haptic::config::checkConfig("hapticd", overrides,
                                               haptic::config::loadDaemonConfig);
        }
        return haptic::hapticd::runDaemon(haptic::config::startWithConfig<DaemonConfig>(
            "hapticd", overrides, haptic::config::loadDaemonConfig, [&](DaemonConfig& config) {
                if (!realtime.empty()) {
                    config.loop.realtime = realtime == "enforce"
                                               ? haptic::config::RealtimeMode::kEnforce
                                               : haptic::config::RealtimeMode::kIgnore;
                }
            }));
    });
}
