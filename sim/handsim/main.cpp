// handsim: the soft real-time hand simulation. See README.

#include <malloc.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "haptic/config/error.hpp"
#include "haptic/config/sim.hpp"
#include "haptic/ipc/ipc_error.hpp"
#include "haptic/process/logging.hpp"
#include "haptic/process/shutdown.hpp"
#include "sim_app.hpp"

int main(int argc, char** argv) {
    // Each soft-hand step builds sparse matrices of several MB. With glibc's defaults they are
    // mmap'ed and unmapped every step, and the page faults cost more than the solve (6 ms
    // instead of 14 ms of CPU per default-scene step, sim/softhand/BENCHMARK.md). Keep freed
    // memory in the heap instead.
    mallopt(M_MMAP_THRESHOLD, 256 << 20);
    mallopt(M_TRIM_THRESHOLD, 512 << 20);
    mallopt(M_TOP_PAD, 64 << 20);
    CLI::App app{"handsim - hand simulation publishing proxy targets and contact surfaces"};
    std::string config_path = HAPTIC_DEFAULT_CONFIG_DIR "/sim.yaml";
    std::string log_level;
    int dds_domain = -1;
    double duration_s = 0.0;
    app.add_option("-c,--config", config_path, "sim configuration file")->capture_default_str();
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
        haptic::handsim::SimOptions options;
        options.config = haptic::config::loadSimConfig(config_path);
        options.duration_s = duration_s;
        if (dds_domain >= 0) {
            options.config.dds.domain_id = dds_domain;
        }
        if (!sim_link.empty()) {
            options.config.sim_link.transport = sim_link == "dds"
                                                    ? haptic::config::SimTransport::kDds
                                                    : haptic::config::SimTransport::kIceoryx;
        }
        haptic::process::setupLogging(
            "handsim",
            log_level.empty() ? haptic::config::toString(options.config.log_level) : log_level);
        haptic::process::installShutdownHandlers();
        return haptic::handsim::runSim(options);
    } catch (const haptic::config::ConfigError& error) {
        std::fprintf(stderr, "handsim: configuration error: %s\n", error.what());
    } catch (const haptic::ipc::IpcError& error) {
        std::fprintf(stderr, "handsim: %s\n", error.what());
    } catch (const std::exception& error) {
        std::fprintf(stderr, "handsim: %s\n", error.what());
    }
    return EXIT_FAILURE;
}
