#pragma once

// The command-line overrides shared by the executables that read daemon.yaml or sim.yaml
// (hapticd, handsim): one definition of each flag, its check and how it maps onto the loaded
// configuration, so the two cannot drift apart. Header only; the executables link CLI11.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <string>

#include "haptic/config/common.hpp"
#include "haptic/config/enums.hpp"
#include "haptic/process/logging.hpp"
#include "haptic/process/main_skeleton.hpp"
#include "haptic/process/shutdown.hpp"

namespace haptic::config {

struct CommonOverrides {
    std::string config_path;              // the default is the caller's
    std::string log_level;                // empty: the file's log_level
    int dds_domain{-1};                   // negative: the file's dds.domain_id
    std::string dds_profiles_file;        // empty: the file's dds.profiles_file
    std::string dds_participant_profile;  // empty: the file's dds.participant_profile
    std::string sim_link;                 // empty: the file's sim_link.transport
    double duration_s{0.0};               // 0 = run until SIGINT/SIGTERM
    bool check_only{false};               // --check: validate the files, print a summary, exit
};

inline void addCommonOptions(CLI::App& app, CommonOverrides& overrides,
                             const std::string& config_description) {
    app.add_option("-c,--config", overrides.config_path, config_description)->capture_default_str();
    app.add_option("--log-level", overrides.log_level, "override log_level")
        ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
    app.add_option("--dds-domain", overrides.dds_domain, "override dds.domain_id")
        ->check(CLI::Range(0, 232));
    app.add_option("--dds-profiles-file", overrides.dds_profiles_file,
                   "override dds.profiles_file (for example the DDS Security profiles that "
                   "scripts/dds-security-pki.sh writes)")
        ->check(CLI::ExistingFile);
    app.add_option("--dds-participant-profile", overrides.dds_participant_profile,
                   "override dds.participant_profile (hapticd_secure, handsim_secure, ...)");
    app.add_option("--sim-link", overrides.sim_link,
                   "override sim_link.transport: iceoryx (same host) or dds (sim on any host)")
        ->check(CLI::IsMember({"iceoryx", "dds"}));
    app.add_option("--duration", overrides.duration_s,
                   "stop after this many seconds (0 = run until signalled)")
        ->check(CLI::NonNegativeNumber);
    app.add_flag("--check", overrides.check_only,
                 "validate the configuration and every file it names, print what it holds and "
                 "exit (0 valid; 1 with file, line and key of the first error); starts nothing");
}

// What hapticd and handsim run with: the loaded configuration, overrides applied.
template <class Config>
struct RunOptions {
    Config config;
    double duration_s{0.0};  // 0 = until SIGINT/SIGTERM
};

// Applies the overrides to a loaded DaemonConfig or SimConfig (both have log_level, dds and
// sim_link) and returns the log level to set up.
template <class Config>
[[nodiscard]] std::string applyCommonOverrides(const CommonOverrides& overrides, Config& config) {
    if (overrides.dds_domain >= 0) {
        config.dds.domain_id = overrides.dds_domain;
    }
    if (!overrides.dds_profiles_file.empty()) {
        config.dds.profiles_file = std::filesystem::absolute(overrides.dds_profiles_file);
    }
    if (!overrides.dds_participant_profile.empty()) {
        config.dds.participant_profile = overrides.dds_participant_profile;
    }
    if (!overrides.sim_link.empty()) {
        config.sim_link.transport =
            overrides.sim_link == "dds" ? SimTransport::kDds : SimTransport::kIceoryx;
    }
    return overrides.log_level.empty() ? std::string(toString(config.log_level))
                                       : overrides.log_level;
}

// --check: loads the file as a start would (`load` throws ConfigError on the first error),
// prints one line per file it read and returns the exit status. Nothing is started.
template <class Load>
[[nodiscard]] int checkConfig(const char* program, const CommonOverrides& overrides, Load&& load) {
    const auto config = load(overrides.config_path);
    std::printf("%s: %s: configuration OK\n", program, config.source.string().c_str());
    for (const auto& device : config.devices) {
        std::printf("  device '%s' (%s): %s\n", device.name.c_str(),
                    device.isExoskeleton() ? "exoskeleton" : "thimble",
                    device.source.string().c_str());
    }
    return 0;
}

// The start hapticd and handsim share once their command line is parsed: load the file
// (`load`, which throws ConfigError), apply the common overrides and the program's own
// (`adjust`), then set up logging and the SIGINT/SIGTERM handlers.
template <class Config, class Load, class Adjust>
[[nodiscard]] RunOptions<Config> startWithConfig(const char* program,
                                                 const CommonOverrides& overrides, Load&& load,
                                                 Adjust&& adjust) {
    RunOptions<Config> options;
    options.config = load(overrides.config_path);
    options.duration_s = overrides.duration_s;
    adjust(options.config);
    process::setupLogging(program, applyCommonOverrides(overrides, options.config));
    process::installShutdownHandlers();
    return options;
}

// What tells hapticd and handsim apart on the command line.
struct ProgramIdentity {
    const char* name;                // "hapticd"
    const char* description;         // the first line of --help
    std::string default_config;      // the -c default
    const char* config_description;  // -c's help text
};

// The whole main() of hapticd and handsim, so the two cannot drift apart: the common options
// plus the program's own (`add_own_options(CLI::App&)`), then either --check, or a start as
// startWithConfig describes (`adjust(Config&)` applies the program's own overrides) and
// `run(RunOptions<Config>)`, whose status is the exit status. Errors end as process::runMain
// reports them.
template <class Config, class Load, class AddOwnOptions, class Adjust, class Run>
[[nodiscard]] int runConfiguredProgram(int argc, char** argv, const ProgramIdentity& program,
                                       Load&& load, AddOwnOptions&& add_own_options,
                                       Adjust&& adjust, Run&& run) {
    CLI::App app{program.description};
    app.set_version_flag("--version", std::string(program.name) + " " + HAPTIC_VERSION);
    CommonOverrides overrides;
    overrides.config_path = program.default_config;
    addCommonOptions(app, overrides, program.config_description);
    add_own_options(app);
    CLI11_PARSE(app, argc, argv);

    return process::runMain(program.name, [&] {
        if (overrides.check_only) {
            return checkConfig(program.name, overrides, load);
        }
        return run(startWithConfig<Config>(program.name, overrides, load, adjust));
    });
}

}  // namespace haptic::config
