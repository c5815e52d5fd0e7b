// hapticd_loop_bench: the daemon's 1 kHz loop against Debian's cyclictest on the same
// machine in one run. Results and commands in docs/benchmarks.md.
//
// Phases, with the same SCHED_FIFO priority and CPU affinity (both read from the daemon
// config), and RouDi, handsim and any --with processes running throughout:
//   1. cyclictest -m -p <prio> [-a <cpu>] -i 1000 -h 20000 -q --latency=<loop.cpu_latency_us>
//      (--laptop where the config makes no request), and
//   2. the real hapticd process; its per-tick wake-up latency and compute time come from
//      haptic/telemetry over DDS (every tick carries them), so hapticemu for both devices can
//      be added with --with and a daemon config that binds them, without code changes.
//      1 and 2 take turns in --rounds rounds of equal length, and each side's rounds are
//      added up: on a VM the host's noise comes in bursts of seconds, and one long window
//      each compared two different stretches of it;
//   3. the sim -> daemon message latency over iceoryx and over DDS (sim_link_probe.hpp).

#include <sys/utsname.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "HapticTelemetryPubSubTypes.h"
#include "child_process.hpp"
#include "haptic/config/daemon.hpp"
#include "haptic/config/error.hpp"
#include "haptic/ipc/dds_participant.hpp"
#include "haptic/ipc/iceoryx_runtime.hpp"
#include "haptic/ipc/ipc_error.hpp"
#include "haptic/ipc/topics.hpp"
#include "latency_stats.hpp"
#include "provenance.hpp"
#include "sim_link_probe.hpp"

namespace haptic::bench {
namespace {

using testing::ChildProcess;
using namespace std::chrono_literals;

struct BenchOptions {
    double duration_s{30.0};
    double latency_duration_s{10.0};
    int rounds{5};
    std::string daemon_config{HAPTIC_DEFAULT_CONFIG_DIR "/daemon.yaml"};
    std::string sim_config{HAPTIC_DEFAULT_CONFIG_DIR "/sim.yaml"};
    std::string realtime;  // hapticd --realtime override; empty = the config's
    std::string sim_link;  // hapticd/handsim --sim-link override; empty = the config's
    std::vector<std::string> with;
    std::string output;
    std::string command_line;
};

// hapticd's per-tick telemetry, added up over the rounds.
struct DaemonLoopSamples {
    std::vector<double> wakeup_us;
    std::vector<double> tick_work_us;  // the whole tick: read + compute + write
    std::vector<double> read_us;
    std::vector<double> compute_us;  // the compute phase: tick work - read - write
    std::vector<double> write_us;
    std::uint64_t ticks_spanned{0};  // per round, last - first counted tick + 1
    std::string error;
};

std::vector<std::string> splitWords(const std::string& command) {
    std::istringstream words(command);
    std::vector<std::string> argv;
    for (std::string word; words >> word;) {
        argv.push_back(word);
    }
    return argv;
}

std::string fixed(double value) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.1f", value);
    return text;
}

std::string row(const std::string& name, const LatencySummary& s) {
    return "| " + name + " | " + fixed(s.p50) + " | " + fixed(s.p99) + " | " + fixed(s.p999) +
           " | " + fixed(s.max) + " | " + std::to_string(s.count) + " |\n";
}

std::optional<LatencyHistogram> runCyclictest(int priority, int cpu, int cpu_latency_us,
                                              double duration_s, std::string& error) {
    std::vector<std::string> argv{
        HAPTIC_CYCLICTEST_PATH, "-m", "-p", std::to_string(priority), "-i", "1000", "-l",
        std::to_string(static_cast<long>(duration_s * 1000.0)), "-q", "-h", "20000",
        // The same CPU latency request as hapticd's (loop.cpu_latency_us), or none.
        cpu_latency_us >= 0 ? "--latency=" + std::to_string(cpu_latency_us) : "--laptop"};
    if (cpu >= 0) {
        argv.insert(argv.end(), {"-a", std::to_string(cpu)});
    }
    const auto result = testing::runCommand(
        argv, std::chrono::milliseconds(static_cast<long>(duration_s * 1000.0) + 30'000));
    if (result.exit_code != 0) {
        error = "cyclictest failed (exit " + std::to_string(result.exit_code) + "): " + result.err;
        return std::nullopt;
    }
    return parseCyclictestOutput(result.out, error);
}

// Runs hapticd for `duration_s` of counted ticks after a 1 s warm-up and appends every
// tick's wake-up latency and compute time from haptic/telemetry to `out`.
void runDaemonLoop(const BenchOptions& options, const config::DaemonConfig& cfg,
                   const std::string& domain, double duration_s, DaemonLoopSamples& out) {
    ipc::DdsParticipant participant(
        ipc::DdsSettings{static_cast<std::uint32_t>(std::stoi(domain)),
                         cfg.dds.profiles_file.string(), cfg.dds.participant_profile},
        "hapticd_loop_bench");
    auto reader = participant.createReader<idl::HapticTelemetryPubSubType>(ipc::kTelemetryTopic,
                                                                           ipc::TopicKind::kStream);
    std::vector<std::string> argv{HAPTICD_PATH,           "-c",   options.daemon_config,
                                  "--dds-domain",         domain, "--duration",
                                  fixed(duration_s + 5.0)};
    if (!options.realtime.empty()) {
        argv.insert(argv.end(), {"--realtime", options.realtime});
    }
    if (!options.sim_link.empty()) {
        argv.insert(argv.end(), {"--sim-link", options.sim_link});
    }
    ChildProcess daemon(argv, "bench-hapticd");

    const auto wanted = static_cast<std::uint64_t>(duration_s * cfg.loop.rate_hz);
    const auto warmup = static_cast<std::uint64_t>(cfg.loop.rate_hz);
    const std::size_t before = out.wakeup_us.size();
    std::uint64_t first_tick = 0;
    std::uint64_t last_tick = 0;
    idl::HapticTelemetry batch;
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(duration_s + 15.0);
    while (out.wakeup_us.size() - before < wanted && std::chrono::steady_clock::now() < deadline &&
           daemon.running()) {
        if (!reader.waitAndTake(batch, 100ms)) {
            continue;
        }
        for (const auto& sample : batch.samples()) {
            // One sample per device per tick carries the same tick timing: count device 0.
            if (sample.device_index() != 0 || sample.tick() < warmup) {
                continue;
            }
            if (out.wakeup_us.size() == before) {
                first_tick = sample.tick();
            }
            last_tick = sample.tick();
            out.wakeup_us.push_back(sample.wakeup_latency_us());
            out.tick_work_us.push_back(sample.tick_work_us());
            out.read_us.push_back(sample.read_us());
            out.write_us.push_back(sample.write_us());
            out.compute_us.push_back(sample.tick_work_us() - sample.read_us() - sample.write_us());
        }
    }
    const std::size_t delivered = out.wakeup_us.size() - before;
    if (delivered > 0) {
        out.ticks_spanned += last_tick - first_tick + 1;
    }
    if (delivered < wanted && out.error.empty()) {
        out.error = "hapticd delivered " + std::to_string(delivered) + " of " +
                    std::to_string(wanted) + " ticks: " + daemon.stderrText();
    }
    daemon.terminate();
}

std::unique_ptr<ChildProcess> startSim(const BenchOptions& options, const std::string& transport,
                                       const std::string& domain) {
    return std::make_unique<ChildProcess>(
        std::vector<std::string>{HANDSIM_PATH, "-c", options.sim_config, "--dds-domain", domain,
                                 "--sim-link", transport},
        "bench-handsim-" + transport);
}

struct ProbeResult {
    LatencySummary tick;
    LatencySummary delivery;
};

ProbeResult runProbe(const BenchOptions& options, const std::string& transport,
                     const std::string& domain, std::string& error) {
    auto sim = startSim(options, transport, domain);
    const auto result = testing::runCommand(
        {"/proc/self/exe", "--probe", transport, "--latency-duration",
         fixed(options.latency_duration_s), "--daemon-config", options.daemon_config,
         "--dds-domain", domain},
        std::chrono::milliseconds(static_cast<long>(options.latency_duration_s * 1000.0) + 30'000));
    ProbeResult probe;
    unsigned long long tick_count = 0;
    unsigned long long delivery_count = 0;
    if (result.exit_code != 0 ||
        std::sscanf(result.out.c_str(), "probe %llu %lf %lf %lf %lf delivery %llu %lf %lf %lf %lf",
                    &tick_count, &probe.tick.p50, &probe.tick.p99, &probe.tick.p999,
                    &probe.tick.max, &delivery_count, &probe.delivery.p50, &probe.delivery.p99,
                    &probe.delivery.p999, &probe.delivery.max) != 10) {
        error = "the " + transport + " probe failed (exit " + std::to_string(result.exit_code) +
                "): " + result.err + (sim->running() ? "" : " handsim: " + sim->stderrText());
    }
    probe.tick.count = tick_count;
    probe.delivery.count = delivery_count;
    return probe;
}

std::string hostLine() {
    utsname host{};
    ::uname(&host);
    char date[32];
    const std::time_t now = std::time(nullptr);
    std::strftime(date, sizeof(date), "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
    // Other work on the machine moves every number here; the load average says how much.
    std::string load;
    std::getline(std::ifstream("/proc/loadavg"), load);
    return std::string(date) + ", kernel " + host.release + " " + host.version + ", " +
           std::to_string(std::thread::hardware_concurrency()) + " CPUs, load average " +
           load.substr(0, load.find(' ', load.find(' ', load.find(' ') + 1) + 1)) + " at the end";
}

std::string ratio(double daemon, double reference) {
    if (reference <= 0.0 || daemon <= 0.0) {
        return "n/a";
    }
    const double value = daemon / reference;
    return fixed(value) + (value <= 1.5 ? " (met)" : " (missed)");
}

std::string roudiConfig(const config::DaemonConfig& cfg) {
    return cfg.iceoryx ? cfg.iceoryx->roudi_config.string()
                       : std::string(HAPTIC_DEFAULT_CONFIG_DIR "/roudi.toml");
}

int runBenchmark(const BenchOptions& options) {
    const auto cfg = config::loadDaemonConfig(options.daemon_config);
    const std::string domain = std::to_string(200 + ::getpid() % 30);
    const bool iceoryx_daemon = options.sim_link.empty()
                                    ? cfg.sim_link.transport == config::SimTransport::kIceoryx
                                    : options.sim_link == "iceoryx";
    // Its own RouDi, so no other iceoryx process (a demo, a running hapticd, a test) shares
    // the measurement or takes RouDi away in the middle of it.
    if (ipc::probeRoudi().reachable) {
        std::fprintf(stderr,
                     "hapticd_loop_bench: an iox-roudi is already running; stop it (and any "
                     "hapticd, handsim or demo using it) first\n");
        return EXIT_FAILURE;
    }
    auto roudi = std::make_unique<ChildProcess>(
        std::vector<std::string>{IOX_ROUDI_EXECUTABLE, "-c", roudiConfig(cfg), "-l", "warning"},
        "bench-roudi");
    for (int i = 0; i < 500 && !ipc::probeRoudi().reachable; ++i) {
        std::this_thread::sleep_for(20ms);
    }
    if (!ipc::probeRoudi().reachable) {
        std::fprintf(stderr, "hapticd_loop_bench: iox-roudi did not come up: %s\n",
                     roudi->stderrText().c_str());
        return EXIT_FAILURE;
    }
    std::vector<std::unique_ptr<ChildProcess>> extra;
    for (const auto& command : options.with) {
        extra.push_back(std::make_unique<ChildProcess>(splitWords(command), "bench-with"));
    }
    auto sim = startSim(options, iceoryx_daemon ? "iceoryx" : "dds", domain);
    std::this_thread::sleep_for(1s);

    std::string error;
    const double round_s = options.duration_s / options.rounds;
    LatencyHistogram cyclic_total;
    DaemonLoopSamples loop;
    for (auto* series :
         {&loop.wakeup_us, &loop.tick_work_us, &loop.read_us, &loop.compute_us, &loop.write_us}) {
        series->reserve(static_cast<std::size_t>(options.duration_s * cfg.loop.rate_hz));
    }
    for (int round = 1; round <= options.rounds && error.empty(); ++round) {
        std::fprintf(stderr, "round %d of %d: cyclictest for %.1f s, then hapticd ...\n", round,
                     options.rounds, round_s);
        if (const auto histogram = runCyclictest(cfg.loop.priority, cfg.loop.cpu_affinity,
                                                 cfg.loop.cpu_latency_us, round_s, error)) {
            merge(cyclic_total, *histogram);
        }
        runDaemonLoop(options, cfg, domain, round_s, loop);
    }
    const LatencySummary cyclic = summarize(cyclic_total);
    const LatencySummary wakeup = summarize(loop.wakeup_us);
    const std::uint64_t ticks = loop.wakeup_us.size();
    sim.reset();
    std::fprintf(stderr, "sim -> daemon latency, iceoryx then DDS, %.0f s each ...\n",
                 options.latency_duration_s);
    std::string iceoryx_error;
    std::string dds_error;
    const ProbeResult iceoryx = runProbe(options, "iceoryx", domain, iceoryx_error);
    const ProbeResult dds = runProbe(options, "dds", domain, dds_error);
    extra.clear();
    roudi->terminate();

    std::string report =
        "### " + hostLine() + "\n\nCommand: `" + options.command_line +
        "`\n\nSCHED_FIFO priority " + std::to_string(cfg.loop.priority) + ", CPU affinity " +
        std::to_string(cfg.loop.cpu_affinity) + ", daemon sim link " +
        (iceoryx_daemon ? "iceoryx" : "dds") + "; cyclictest and hapticd took turns in " +
        std::to_string(options.rounds) + " rounds of " + fixed(round_s) + " s each.\n\n" +
        "| µs | p50 | p99 | p99.9 | max | samples |\n|---|---|---|---|---|---|\n";
    report += row("cyclictest wake-up latency", cyclic);
    report += row("hapticd wake-up latency", wakeup);
    report += "| hapticd / cyclictest wake-up (target ≤ 1.5) | " + ratio(wakeup.p50, cyclic.p50) +
              " | " + ratio(wakeup.p99, cyclic.p99) + " | " + ratio(wakeup.p999, cyclic.p999) +
              " | " + ratio(wakeup.max, cyclic.max) + " | |\n";
    report += row("hapticd tick work (read + compute + write; target p99 ≤ 100)",
                  summarize(loop.tick_work_us));
    report += row("… of which read (CAN read, sim inputs, commands)", summarize(loop.read_us));
    report +=
        row("… of which compute (core, strategies, optimiser, safety)", summarize(loop.compute_us));
    report += row("… of which write (CAN write, DeviceState hand-off)", summarize(loop.write_us));
    report += row("sim → daemon, iceoryx, stamp → taken by the 1 kHz tick", iceoryx.tick);
    report += row("sim → daemon, DDS, stamp → taken by the 1 kHz tick", dds.tick);
    report += row("sim → daemon, iceoryx, stamp → delivered (exo, event-driven)", iceoryx.delivery);
    report += row("sim → daemon, DDS, stamp → delivered (exo, event-driven)", dds.delivery);
    if (cyclic.overflows > 0) {
        report += "\ncyclictest: " + std::to_string(cyclic.overflows) +
                  " samples beyond its 20 ms histogram.\n";
    }
    if (ticks > 0) {
        report += "\nhapticd telemetry covered " + std::to_string(ticks) + " of " +
                  std::to_string(loop.ticks_spanned) + " ticks.\n";
    }
    for (const auto& message : {error, loop.error, iceoryx_error, dds_error}) {
        if (!message.empty()) {
            report += "\nERROR: " + message + "\n";
        }
    }
    std::fputs(report.c_str(), stdout);
    if (!options.output.empty()) {
        std::ofstream(options.output, std::ios::app) << report << "\n";
    }
    const bool ok =
        error.empty() && loop.error.empty() && iceoryx_error.empty() && dds_error.empty();
    return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}

}  // namespace
}  // namespace haptic::bench

int main(int argc, char** argv) {
    CLI::App app{"hapticd_loop_bench - hapticd's 1 kHz loop against cyclictest, same run"};
    haptic::bench::BenchOptions options;
    std::string probe;
    int probe_domain = -1;
    app.add_option("--duration", options.duration_s, "seconds for cyclictest and for hapticd")
        ->capture_default_str()
        ->check(CLI::Range(2.0, 3600.0));
    app.add_option("--rounds", options.rounds,
                   "cyclictest and hapticd take turns this many times, --duration / rounds each")
        ->capture_default_str()
        ->check(CLI::Range(1, 60));
    app.add_option("--latency-duration", options.latency_duration_s,
                   "seconds per sim -> daemon latency probe (iceoryx, DDS)")
        ->capture_default_str()
        ->check(CLI::Range(1.0, 3600.0));
    app.add_option("--daemon-config", options.daemon_config, "hapticd configuration")
        ->capture_default_str()
        ->check(CLI::ExistingFile);
    app.add_option("--sim-config", options.sim_config, "handsim configuration")
        ->capture_default_str()
        ->check(CLI::ExistingFile);
    app.add_option("--realtime", options.realtime, "hapticd --realtime override")
        ->check(CLI::IsMember({"enforce", "ignore"}));
    app.add_option("--sim-link", options.sim_link,
                   "hapticd's and handsim's sim link during the loop phase (default: the config's)")
        ->check(CLI::IsMember({"iceoryx", "dds"}));
    app.add_option("--with", options.with,
                   "another process to run during the benchmark, e.g. '/usr/bin/hapticemu ...' "
                   "(absolute path first; repeatable)");
    app.add_option("--output", options.output, "append the markdown table to this file");
    app.add_option("--probe", probe, "internal: run one sim-link latency probe")
        ->check(CLI::IsMember({"iceoryx", "dds"}));
    app.add_option("--dds-domain", probe_domain, "internal: the probe's DDS domain");
    CLI11_PARSE(app, argc, argv);
    if (probe.empty() && options.duration_s / options.rounds < 1.0) {
        std::fprintf(stderr,
                     "hapticd_loop_bench: --duration %.1f over --rounds %d leaves under 1 s per "
                     "round; each round needs at least 1 s past hapticd's 1 s warm-up\n",
                     options.duration_s, options.rounds);
        return EXIT_FAILURE;
    }
    if (probe.empty()) {  // a probe's stdout is parsed by its parent: results only
        haptic::bench::printProvenance(argc, argv);
    }
    for (int i = 0; i < argc; ++i) {
        options.command_line +=
            (i == 0 ? std::string("hapticd_loop_bench") : " " + std::string(argv[i]));
    }

    try {
        if (!probe.empty()) {
            auto cfg = haptic::config::loadDaemonConfig(options.daemon_config);
            if (probe_domain >= 0) {
                cfg.dds.domain_id = probe_domain;
            }
            return haptic::bench::runSimLinkProbe(cfg,
                                                  probe == "dds"
                                                      ? haptic::bench::ProbeTransport::kDds
                                                      : haptic::bench::ProbeTransport::kIceoryx,
                                                  options.latency_duration_s);
        }
        return haptic::bench::runBenchmark(options);
    } catch (const std::exception& error) {
        std::fprintf(stderr, "hapticd_loop_bench: %s\n", error.what());
    }
    return EXIT_FAILURE;
}
