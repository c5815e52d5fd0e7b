// hapticctl: the status CLI. It only listens to published DDS topics and never calls into
// the daemon's RT thread (a status query must not be able to cause an overrun).

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <iostream>

#include "HapticStatusPubSubTypes.h"
#include "haptic/config/daemon.hpp"
#include "haptic/config/error.hpp"
#include "haptic/ipc/dds_participant.hpp"
#include "haptic/ipc/topics.hpp"
#include "haptic/msgs/conversions.hpp"
#include "haptic/process/logging.hpp"
#include "status_format.hpp"

namespace {

// Exit codes, so scripts can tell a daemon that is down from a broken installation.
constexpr int kExitNoDaemon = 3;
constexpr int kExitError = 1;

int printStatus(const haptic::config::DaemonConfig& cfg, double timeout_s) {
    haptic::ipc::DdsParticipant participant(
        haptic::ipc::DdsSettings{static_cast<std::uint32_t>(cfg.dds.domain_id),
                                 cfg.dds.profiles_file.string(), cfg.dds.participant_profile},
        "hapticctl");
    auto reader = participant.createReader<haptic::idl::HapticStatusPubSubType>(
        haptic::ipc::kStatusTopic, haptic::ipc::TopicKind::kLatestState);
    haptic::idl::HapticStatus sample;
    const auto timeout = std::chrono::milliseconds(static_cast<long>(timeout_s * 1000.0));
    if (!reader.waitAndTake(sample, timeout)) {
        std::fprintf(stderr,
                     "hapticctl: no hapticd status on DDS topic '%s' (domain %d) within %.1f s; is "
                     "hapticd running?\n",
                     haptic::ipc::kStatusTopic, cfg.dds.domain_id, timeout_s);
        return kExitNoDaemon;
    }
    haptic::msgs::HapticStatus status;
    if (const auto result = haptic::msgs::fromIdl(sample, status); !result.ok()) {
        std::fprintf(stderr, "hapticctl: malformed status sample: %s\n", result.error.c_str());
        return kExitError;
    }
    // Stamps are CLOCK_MONOTONIC of the daemon's host; over DDS from another host the age is
    // meaningless, so it is shown only when it is plausible.
    timespec now{};
    ::clock_gettime(CLOCK_MONOTONIC, &now);
    const double age_s =
        static_cast<double>(now.tv_sec * 1'000'000'000LL + now.tv_nsec - status.header.stamp_ns) *
        1e-9;
    std::cout << haptic::ctl::formatStatus(status, age_s >= 0.0 && age_s < 3600.0 ? age_s : -1.0)
              << std::flush;
    return EXIT_SUCCESS;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"hapticctl - status of the haptic runtime (listens to hapticd's DDS topics)"};
    app.require_subcommand(1);
    std::string config_path = HAPTIC_DEFAULT_CONFIG_DIR "/daemon.yaml";
    int dds_domain = -1;
    app.add_option("-c,--config", config_path,
                   "daemon configuration file (for the DDS domain and profile)")
        ->capture_default_str();
    app.add_option("--dds-domain", dds_domain, "override dds.domain_id")->check(CLI::Range(0, 232));

    double timeout_s = 2.0;
    auto* status = app.add_subcommand("status", "print the daemon's state and loop statistics");
    status->add_option("--timeout", timeout_s, "seconds to wait for a status sample")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    CLI11_PARSE(app, argc, argv);

    try {
        auto cfg = haptic::config::loadDaemonConfig(config_path);
        if (dds_domain >= 0) {
            cfg.dds.domain_id = dds_domain;
        }
        haptic::process::setupLogging("hapticctl", "warn");
        if (status->parsed()) {
            return printStatus(cfg, timeout_s);
        }
    } catch (const haptic::config::ConfigError& error) {
        std::fprintf(stderr, "hapticctl: configuration error: %s\n", error.what());
    } catch (const std::exception& error) {
        std::fprintf(stderr, "hapticctl: %s\n", error.what());
    }
    return kExitError;
}
