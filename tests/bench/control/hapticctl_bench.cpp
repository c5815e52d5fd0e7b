// hapticctl_bench: what an operator waits for, against a real hapticd (no devices needed):
//   1. N consecutive `hapticctl status` processes, start-up included, through the local
//      control socket: how many answered "no daemon" (exit 3) and the wall time per call;
//   2. the same through DDS (`--over-dds`, what every call did before the socket), fewer
//      calls: the baseline of the same run;
//   3. `estop` from the moment its request is written on the socket to the RT tick that
//      applied it (the reply's stamp, CLOCK_MONOTONIC of the same host), `clear` between.
// Targets (#19): zero false "no daemon", status p95 <= 50 ms and max <= 250 ms, estop p99
// <= 5 ms. Results and the command in docs/benchmarks.md.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "haptic/common/clock.hpp"
#include "haptic/common/statistics.hpp"
#include "haptic/config/daemon.hpp"
#include "haptic/control/control_socket.hpp"
#include "haptic/ipc/iceoryx_runtime.hpp"
#include "haptic/msgs/conversions.hpp"
#include "provenance.hpp"

namespace haptic::bench {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::CommandResult;
using testing::runCommand;

struct Calls {
    std::vector<double> ms;
    int failed{0};
    int no_daemon{0};
};

Calls statusCalls(const std::vector<std::string>& argv, int count) {
    Calls calls;
    for (int i = 0; i < count; ++i) {
        const auto start = std::chrono::steady_clock::now();
        const CommandResult result = runCommand(argv, 30s);
        calls.ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count());
        calls.no_daemon += result.exit_code == 3 ? 1 : 0;
        calls.failed += result.exit_code != 0 ? 1 : 0;
    }
    return calls;
}

std::string line(const char* what, std::vector<double> samples, int failed, int no_daemon) {
    const std::size_t n = samples.size();
    char text[256];
    std::snprintf(text, sizeof(text),
                  "%-34s n %4zu  p50 %8.2f  p95 %8.2f  p99 %8.2f  max %8.2f ms  failed %d "
                  "(no daemon %d)\n",
                  what, n, common::percentile(samples, 0.50), common::percentile(samples, 0.95),
                  common::percentile(samples, 0.99), common::percentile(samples, 1.0), failed,
                  no_daemon);
    return text;
}

// One command on a fresh connection; the RT tick's stamp of its reply (0 when refused).
std::int64_t sendCommand(const std::filesystem::path& socket, msgs::CommandKind kind,
                         std::int64_t& written_ns) {
    control::ControlClient client(socket);
    if (client.connect() != control::ControlClient::Connect::kConnected) {
        return 0;
    }
    msgs::HapticCommand command;
    static std::uint64_t request = 0;
    command.request_id = ++request;
    command.header.source_id.assign("hapticctl_bench");
    command.kind = kind;
    std::vector<char> datagram;
    (void)control::encode(control::kCommandRequest, msgs::toIdl(command), datagram);
    written_ns = common::monotonicNowNs();
    const auto answer = client.request(datagram, 2s);
    idl::HapticCommandReply wire;
    msgs::HapticCommandReply reply;
    if (!answer || answer->kind != control::kReplyAnswer ||
        !control::decode(answer->body.data(), answer->body.size(), wire) ||
        !msgs::fromIdl(wire, reply).ok() || !reply.accepted) {
        return 0;
    }
    return reply.header.stamp_ns;
}

}  // namespace
}  // namespace haptic::bench

int main(int argc, char** argv) {
    using namespace haptic;
    using namespace std::chrono_literals;
    using testing::ChildProcess;
    using testing::runCommand;
    CLI::App app{"hapticctl status and estop latency against a real hapticd"};
    int calls = 500;
    int dds_calls = 20;
    int estops = 200;
    std::string output;
    int domain = 190;
    app.add_option("--calls", calls, "hapticctl status calls over the socket")
        ->capture_default_str();
    app.add_option("--dds-calls", dds_calls, "the same over DDS (the baseline)")
        ->capture_default_str();
    app.add_option("--estops", estops, "estop requests (each followed by clear)")
        ->capture_default_str();
    app.add_option("--dds-domain", domain, "the daemon's DDS domain")->capture_default_str();
    app.add_option("-o,--output", output, "also write the results to this file");
    CLI11_PARSE(app, argc, argv);
    bench::printProvenance(argc, argv);

    if (ipc::probeRoudi().reachable) {
        std::fprintf(stderr, "hapticctl_bench: an iox-roudi is already running; stop it\n");
        return 1;
    }
    const std::string config_dir = HAPTIC_CONFIG_DIR;
    config::DaemonConfig cfg = config::loadDaemonConfig(config_dir + "/daemon.yaml");
    cfg.dds.domain_id = domain;
    const std::filesystem::path socket = config::controlSocketPath(cfg);
    ChildProcess roudi({IOX_ROUDI_EXECUTABLE, "-c", config_dir + "/roudi.toml", "-l", "warning"},
                       "roudi");
    for (auto deadline = std::chrono::steady_clock::now() + 10s; !ipc::probeRoudi().reachable;) {
        if (std::chrono::steady_clock::now() > deadline) {
            std::fprintf(stderr, "hapticctl_bench: iox-roudi did not come up\n");
            return 1;
        }
        std::this_thread::sleep_for(20ms);
    }
    ChildProcess daemon({HAPTICD_PATH, "-c", config_dir + "/daemon.yaml", "--realtime", "ignore",
                         "--dds-domain", std::to_string(domain)},
                        "hapticd");
    const std::vector<std::string> status{
        HAPTICCTL_PATH,         "-c",    config_dir + "/daemon.yaml", "--dds-domain",
        std::to_string(domain), "status"};
    for (auto deadline = std::chrono::steady_clock::now() + 30s;
         runCommand(status, 10s).exit_code != 0;) {
        if (std::chrono::steady_clock::now() > deadline || !daemon.running()) {
            std::fprintf(stderr, "hapticctl_bench: hapticd never answered: %s\n",
                         daemon.stderrText().c_str());
            return 1;
        }
    }

    std::string report = "socket " + socket.string() + "\n";
    const bench::Calls local = bench::statusCalls(status, calls);
    report += bench::line("hapticctl status (socket)", local.ms, local.failed, local.no_daemon);
    std::vector<std::string> over_dds = status;
    over_dds.insert(over_dds.end() - 1, "--over-dds");
    const bench::Calls dds = bench::statusCalls(over_dds, dds_calls);
    report += bench::line("hapticctl --over-dds status", dds.ms, dds.failed, dds.no_daemon);
    std::vector<double> sorted_local = local.ms;
    std::vector<double> sorted_dds = dds.ms;
    char ratio[160];
    std::snprintf(ratio, sizeof(ratio), "socket / DDS: p50 %.3f, p95 %.3f (same run)\n",
                  common::percentile(sorted_local, 0.5) / common::percentile(sorted_dds, 0.5),
                  common::percentile(sorted_local, 0.95) / common::percentile(sorted_dds, 0.95));
    report += ratio;

    std::vector<double> estop_ms;
    int estop_failed = 0;
    for (int i = 0; i < estops; ++i) {
        std::int64_t written_ns = 0;
        const std::int64_t applied_ns =
            bench::sendCommand(socket, msgs::CommandKind::kEstop, written_ns);
        if (applied_ns == 0) {
            ++estop_failed;
        } else {
            estop_ms.push_back(static_cast<double>(applied_ns - written_ns) * 1e-6);
        }
        std::int64_t ignored = 0;
        (void)bench::sendCommand(socket, msgs::CommandKind::kClearFault, ignored);
        std::this_thread::sleep_for(5ms);  // not in step with the loop's ticks
    }
    report += bench::line("estop: written -> applied on RT", estop_ms, estop_failed, 0);
    std::fputs(report.c_str(), stdout);
    if (!output.empty()) {
        std::ofstream(output) << report;
    }
    (void)daemon.terminate();
    (void)roudi.terminate();
    return 0;
}
