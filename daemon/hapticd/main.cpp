// hapticd: the hard real-time haptic daemon. See docs/hapticd.md.

#include <CLI/CLI.hpp>
#include <string>

#include "daemon_app.hpp"
#include "haptic/config/command_line.hpp"
#include "haptic/config/daemon.hpp"

int main(int argc, char** argv) {
    using haptic::config::DaemonConfig;
    std::string realtime;
    return haptic::config::runConfiguredProgram<DaemonConfig>(
        argc, argv,
        {"hapticd", "hapticd - hard real-time haptic rendering daemon (1 kHz)",
         HAPTIC_DEFAULT_CONFIG_DIR "/daemon.yaml", "daemon configuration file"},
        haptic::config::loadDaemonConfig,
        [&](CLI::App& app) {
            app.add_option("--realtime", realtime,
                           "override loop.realtime: 'enforce' refuses to run without SCHED_FIFO "
                           "and mlockall, 'ignore' runs anyway (tests, VMs)")
                ->check(CLI::IsMember({"enforce", "ignore"}));
        },
        [&](DaemonConfig& config) {
            if (!realtime.empty()) {
                config.loop.realtime = realtime == "enforce"
                                           ? haptic::config::RealtimeMode::kEnforce
                                           : haptic::config::RealtimeMode::kIgnore;
            }
        },
        haptic::hapticd::runDaemon);
}
