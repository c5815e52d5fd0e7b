// hapticd: the hard real-time haptic daemon. See README "Running on real hardware".

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "daemon_app.hpp"
#include "haptic/config/daemon.hpp"
#include "haptic/config/error.hpp"
#include "haptic/ipc/ipc_error.hpp"
#include "haptic/process/logging.hpp"
#include "haptic/process/shutdown.hpp"

int main(int argc, char** argv) {
    CLI::App app{"hapticd - hard real-time haptic rendering daemon (1 kHz)"};
    std::string config_path = HAPTIC_DEFAULT_CONFIG_DIR "/daemon.yaml";
    std::string realtime;
    std::string log_level;
    int dds_domain = -1;
    double duration_s = 0.0;
    app.add_option("-c,--config", config_path, "daemon configuration file")->capture_default_str();
    app.add_option("--realtime", realtime,
                   "override loop.realtime: 'enforce' refuses to run without SCHED_FIFO and "
                   "mlockall, 'ignore' runs anyway (tests, VMs)")
        ->check(CLI::IsMember({"enforce", "ignore"}));
    app.add_option("--log-level", log_level, "override log_level")
        ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
    app.add_option("--dds-domain", dds_domain, "override dds.domain_id")->check(CLI::Range(0, 232));
    std::string sim_link;
    app.add_option("--sim-link", sim_link,
                   "override sim_link.transport: iceoryx (same host) or dds (sim on any host)")
        ->check(CLI::IsMember({"iceoryx", "dds"}));
    app.add_option("--duration", duration_s,
                   "stop after this many seconds (0 = run until signalled)")
        ->check(CLI::NonNegativeNumber);
    CLI11_PARSE(app, argc, argv);

    try {
        haptic::hapticd::DaemonOptions options;
        options.config = haptic::config::loadDaemonConfig(config_path);
        options.duration_s = duration_s;
        if (!realtime.empty()) {
            options.config.loop.realtime = realtime == "enforce"
                                               ? haptic::config::RealtimeMode::kEnforce
                                               : haptic::config::RealtimeMode::kIgnore;
        }
        if (dds_domain >= 0) {
            options.config.dds.domain_id = dds_domain;
        }
        if (!sim_link.empty()) {
            options.config.sim_link.transport = sim_link == "dds"
                                                    ? haptic::config::SimTransport::kDds
                                                    : haptic::config::SimTransport::kIceoryx;
        }
        haptic::process::setupLogging(
            "hapticd",
            log_level.empty() ? haptic::config::toString(options.config.log_level) : log_level);
        haptic::process::installShutdownHandlers();
        return haptic::hapticd::runDaemon(options);
    } catch (const haptic::config::ConfigError& error) {
        std::fprintf(stderr, "hapticd: configuration error: %s\n", error.what());
    } catch (const haptic::ipc::IpcError& error) {
        std::fprintf(stderr, "hapticd: %s\n", error.what());
    } catch (const std::exception& error) {
        std::fprintf(stderr, "hapticd: %s\n", error.what());
    }
    return EXIT_FAILURE;
}
