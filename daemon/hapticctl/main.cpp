// hapticctl: the operator CLI. On hapticd's host, status and commands go through hapticd's
// local control socket (its peer credentials say what the caller may do); elsewhere, or with
// --over-dds, over DDS (haptic/status, and haptic/command, which takes only estop). It never
// calls into the daemon's RT thread: hapticd's non-RT thread forwards commands through a
// lock-free queue, so no query or command can cause an overrun.

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <exception>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "HapticCommandPubSubTypes.h"
#include "HapticStatusPubSubTypes.h"
#include "HapticTelemetryPubSubTypes.h"
#include "SimStatusPubSubTypes.h"
#include "bash_completion.hpp"
#include "closed_loop_report.hpp"
#include "haptic/common/clock.hpp"
#include "haptic/config/daemon.hpp"
#include "haptic/config/enums.hpp"
#include "haptic/config/error.hpp"
#include "haptic/control/control_socket.hpp"
#include "haptic/ipc/dds_participant.hpp"
#include "haptic/ipc/topics.hpp"
#include "haptic/msgs/conversions.hpp"
#include "haptic/process/logging.hpp"
#include "haptic/process/main_skeleton.hpp"
#include "haptic/process/shutdown.hpp"
#include "status_format.hpp"
#include "status_json.hpp"
#include "telemetry_csv.hpp"

namespace {

using namespace std::chrono_literals;

// Exit codes, so scripts can tell a refused command or a daemon that is down from a broken
// installation.
constexpr int kExitError = 1;
constexpr int kExitRefused = 2;
constexpr int kExitNoDaemon = 3;

std::chrono::milliseconds toMs(double seconds) {
    return std::chrono::milliseconds(static_cast<long>(seconds * 1000.0));
}

// The status screen (or its JSON, docs/hapticctl.md) for one sample; returns false (after
// printing why) if it is malformed.
bool renderStatus(const haptic::idl::HapticStatus& sample, std::string& screen, bool json = false) {
    haptic::msgs::HapticStatus status;
    if (const auto result = haptic::msgs::fromIdl(sample, status); !result.ok()) {
        std::fprintf(stderr, "hapticctl: malformed status sample: %s\n", result.error.c_str());
        return false;
    }
    // Stamps are CLOCK_MONOTONIC of the daemon's host; over DDS from another host the age is
    // meaningless, so it is shown only when it is plausible.
    const double age_s =
        static_cast<double>(haptic::common::monotonicNowNs() - status.header.stamp_ns) * 1e-9;
    const double shown_age_s = age_s >= 0.0 && age_s < 3600.0 ? age_s : -1.0;
    screen = json ? haptic::ctl::statusJson(status, shown_age_s) + "\n"
                  : haptic::ctl::formatStatus(status, shown_age_s);
    return true;
}

void reportNoDaemon(const haptic::config::DaemonConfig& cfg, double timeout_s) {
    std::fprintf(stderr,
                 "hapticctl: no hapticd status on DDS topic '%s' (domain %d) within %.1f s; is "
                 "hapticd running?\n",
                 haptic::ipc::kStatusTopic, cfg.dds.domain_id, timeout_s);
}

// One status sample on stdout, as the screen or its JSON; the exit code.
int printRenderedStatus(const haptic::idl::HapticStatus& sample, bool json) {
    std::string screen;
    if (!renderStatus(sample, screen, json)) {
        return kExitError;
    }
    std::cout << screen << std::flush;
    return EXIT_SUCCESS;
}

constexpr int kConnected = 0;
constexpr int kNoLocalDaemon = -1;

// kConnected; kNoLocalDaemon when no hapticd serves a control socket on this host (no socket
// file, or a stale one), for the caller to try DDS; or the exit code after saying why.
int connectLocally(haptic::control::ControlClient& client) {
    using Connect = haptic::control::ControlClient::Connect;
    switch (client.connect()) {
        case Connect::kConnected:
            return kConnected;
        case Connect::kNoSocket:
        case Connect::kRefused:
            return kNoLocalDaemon;
        case Connect::kError:
            break;
    }
    std::fprintf(stderr, "hapticctl: local control socket %s\n", client.error().c_str());
    return kExitError;
}

// The status from hapticd's local control socket; nullopt when no hapticd serves one on this
// host (no socket file, or a stale one), for the caller to try DDS.
std::optional<int> printStatusLocally(const haptic::config::DaemonConfig& cfg, double timeout_s,
                                      bool json) {
    namespace control = haptic::control;
    control::ControlClient client(haptic::config::controlSocketPath(cfg));
    if (const auto failed = connectLocally(client); failed != kConnected) {
        return failed == kNoLocalDaemon ? std::nullopt : std::optional<int>(failed);
    }
    // A hapticd still starting answers "no status yet": ask again until the timeout.
    const auto deadline = std::chrono::steady_clock::now() + toMs(timeout_s);
    std::string last_error;
    for (;;) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
            deadline - std::chrono::steady_clock::now());
        const auto answer =
            client.request({control::kStatusRequest}, std::max(left, std::chrono::milliseconds(1)));
        if (!answer) {
            std::fprintf(stderr, "hapticctl: no status from hapticd on %s: %s\n",
                         haptic::config::controlSocketPath(cfg).c_str(), client.error().c_str());
            return kExitNoDaemon;
        }
        if (answer->kind == control::kStatusAnswer) {
            haptic::idl::HapticStatus sample;
            if (!control::decode(answer->body.data(), answer->body.size(), sample)) {
                std::fprintf(stderr, "hapticctl: malformed status on the control socket\n");
                return kExitError;
            }
            return printRenderedStatus(sample, json);
        }
        last_error.assign(answer->body.begin(), answer->body.end());
        if (std::chrono::steady_clock::now() + 20ms >= deadline) {
            std::fprintf(stderr, "hapticctl: hapticd: %s\n", last_error.c_str());
            return kExitNoDaemon;
        }
        std::this_thread::sleep_for(20ms);
    }
}

int printStatus(const haptic::config::DaemonConfig& cfg, double timeout_s, bool json,
                bool over_dds) {
    if (!over_dds) {
        if (const auto local = printStatusLocally(cfg, timeout_s, json)) {
            return *local;
        }
    }
    haptic::ipc::DdsParticipant participant(haptic::ipc::ddsSettings(cfg.dds), "hapticctl");
    auto reader = participant.createReader<haptic::idl::HapticStatusPubSubType>(
        haptic::ipc::kStatusTopic, haptic::ipc::TopicKind::kLatestState);
    haptic::idl::HapticStatus sample;
    if (!reader.waitAndTake(sample, toMs(timeout_s))) {
        reportNoDaemon(cfg, timeout_s);
        return kExitNoDaemon;
    }
    return printRenderedStatus(sample, json);
}

// handsim's status (sim/status, which handsim publishes over DDS whichever sim link it uses).
int printSimStatus(const haptic::config::DaemonConfig& cfg, double timeout_s, bool json) {
    haptic::ipc::DdsParticipant participant(haptic::ipc::ddsSettings(cfg.dds), "hapticctl");
    auto reader = participant.createReader<haptic::idl::SimStatusPubSubType>(
        haptic::ipc::kSimStatusTopic, haptic::ipc::TopicKind::kLatestState);
    haptic::idl::SimStatus sample;
    if (!reader.waitAndTake(sample, toMs(timeout_s))) {
        std::fprintf(stderr,
                     "hapticctl: no handsim status on DDS topic '%s' (domain %d) within %.1f s; "
                     "is handsim running?\n",
                     haptic::ipc::kSimStatusTopic, cfg.dds.domain_id, timeout_s);
        return kExitNoDaemon;
    }
    haptic::msgs::SimStatus status;
    if (const auto result = haptic::msgs::fromIdl(sample, status); !result.ok()) {
        std::fprintf(stderr, "hapticctl: malformed sim status sample: %s\n", result.error.c_str());
        return kExitError;
    }
    const double age_s =
        static_cast<double>(haptic::common::monotonicNowNs() - status.header.stamp_ns) * 1e-9;
    const double shown_age_s = age_s >= 0.0 && age_s < 3600.0 ? age_s : -1.0;
    std::cout << (json ? haptic::ctl::simStatusJson(status, shown_age_s) + "\n"
                       : haptic::ctl::formatSimStatus(status, shown_age_s))
              << std::flush;
    return EXIT_SUCCESS;
}

// Redraws the status screen every `interval_s` until Ctrl-C (or `count` screens, for
// scripts). A daemon that goes away is shown as such, and watch keeps waiting for it.
int watchStatus(const haptic::config::DaemonConfig& cfg, double interval_s, int count) {
    haptic::process::installShutdownHandlers();
    haptic::ipc::DdsParticipant participant(haptic::ipc::ddsSettings(cfg.dds), "hapticctl");
    auto reader = participant.createReader<haptic::idl::HapticStatusPubSubType>(
        haptic::ipc::kStatusTopic, haptic::ipc::TopicKind::kLatestState);
    haptic::idl::HapticStatus sample;
    std::string screen;
    const bool to_terminal = ::isatty(STDOUT_FILENO) == 1;
    for (int drawn = 0; count == 0 || drawn < count; ++drawn) {
        const bool fresh = reader.waitAndTake(sample, toMs(std::max(interval_s, 2.0)));
        if (haptic::process::shutdownRequested()) {
            break;
        }
        // Home the cursor and clear the screen, as watch(1) does, on a terminal; piped, one
        // snapshot after the other with no control codes.
        if (to_terminal) {
            std::cout << "\033[H\033[2J";
        } else if (drawn > 0) {
            std::cout << "\n";
        }
        if (!fresh) {
            std::cout << "● hapticd - no status on '" << haptic::ipc::kStatusTopic << "' (domain "
                      << cfg.dds.domain_id << "); waiting for the daemon\n";
        } else if (renderStatus(sample, screen)) {
            std::cout << screen;
        }
        std::cout << std::flush;
        if ((count != 0 && drawn + 1 >= count) ||
            !haptic::process::sleepUnlessShutdown(
                std::chrono::duration_cast<std::chrono::nanoseconds>(
                    std::chrono::duration<double>(interval_s)))) {
            break;
        }
    }
    return EXIT_SUCCESS;
}

// Writes haptic/telemetry to CSV for `duration_s` (or until Ctrl-C). Exit 3 if no sample
// arrived within the timeout.
int recordTelemetry(const haptic::config::DaemonConfig& cfg, const std::string& path,
                    double duration_s, double timeout_s) {
    haptic::process::installShutdownHandlers();
    // "-" is standard output (then the summary goes to stderr, out of the data's way).
    const bool to_stdout = path == "-";
    std::ofstream file;
    if (!to_stdout) {
        file.open(path);
        if (!file) {
            std::fprintf(stderr, "hapticctl: cannot write '%s'\n", path.c_str());
            return kExitError;
        }
    }
    std::ostream& out = to_stdout ? std::cout : file;
    haptic::ipc::DdsParticipant participant(haptic::ipc::ddsSettings(cfg.dds), "hapticctl");
    auto reader = participant.createReader<haptic::idl::HapticTelemetryPubSubType>(
        haptic::ipc::kTelemetryTopic, haptic::ipc::TopicKind::kStream);
    // The provenance comes from hapticd's status: its version, its configuration digest and
    // the device names (read once the telemetry flows, so the status writer is matched too).
    auto status_reader = participant.createReader<haptic::idl::HapticStatusPubSubType>(
        haptic::ipc::kStatusTopic, haptic::ipc::TopicKind::kLatestState);
    haptic::idl::HapticTelemetry sample;
    haptic::msgs::HapticTelemetry batch;
    std::int64_t origin_ns = -1;
    std::uint64_t rows = 0;
    haptic::ctl::TickGapCounter gaps(
        static_cast<std::uint64_t>(std::max(cfg.loop.telemetry_decimation, 1)));
    auto deadline = std::chrono::steady_clock::now() + toMs(timeout_s);
    while (!haptic::process::shutdownRequested() && std::chrono::steady_clock::now() < deadline) {
        if (!reader.waitAndTake(sample, 100ms)) {
            continue;
        }
        if (const auto result = haptic::msgs::fromIdl(sample, batch); !result.ok()) {
            std::fprintf(stderr, "hapticctl: malformed telemetry sample: %s\n",
                         result.error.c_str());
            return kExitError;
        }
        for (std::size_t i = 0; i < batch.samples.size(); ++i) {
            if (origin_ns < 0) {
                origin_ns = batch.samples[i].stamp_ns;
                deadline = std::chrono::steady_clock::now() + toMs(duration_s);
                const std::int64_t wall_clock_ns =
                    std::chrono::duration_cast<std::chrono::nanoseconds>(
                        std::chrono::system_clock::now().time_since_epoch())
                        .count();
                // The next status comes within two status periods (the reader keeps no history
                // for a late joiner); the telemetry history meanwhile holds what arrives.
                const auto status_wait =
                    std::chrono::milliseconds(100 + 2000 / std::max(cfg.loop.status_rate_hz, 1));
                haptic::idl::HapticStatus status_sample;
                haptic::msgs::HapticStatus status;
                bool have_status = false;
                if (status_reader.waitAndTake(status_sample, status_wait)) {
                    const auto converted = haptic::msgs::fromIdl(status_sample, status);
                    have_status = converted.ok();
                    if (!have_status) {
                        std::fprintf(stderr, "hapticctl: malformed status sample: %s\n",
                                     converted.error.c_str());
                    }
                }
                out << haptic::ctl::telemetryCsvProvenance(HAPTIC_VERSION, wall_clock_ns, origin_ns,
                                                           have_status ? &status : nullptr)
                    << haptic::ctl::telemetryCsvHeader();
            }
            const haptic::msgs::TelemetrySample& s = batch.samples[i];
            gaps.add(s.device_index, s.tick);
            out << haptic::ctl::telemetryCsvRow(s, origin_ns);
            ++rows;
        }
    }
    if (rows == 0) {
        std::fprintf(stderr,
                     "hapticctl: no telemetry on DDS topic '%s' (domain %d) within %.1f s; is "
                     "hapticd running?\n",
                     haptic::ipc::kTelemetryTopic, cfg.dds.domain_id, timeout_s);
        return kExitNoDaemon;
    }
    out.flush();
    if (!out) {
        std::fprintf(stderr, "hapticctl: writing '%s' failed\n", path.c_str());
        return kExitError;
    }
    std::fprintf(to_stdout ? stderr : stdout, "%llu rows written to %s\n",
                 static_cast<unsigned long long>(rows), to_stdout ? "stdout" : path.c_str());
    if (const std::uint64_t missing = gaps.missing(); missing > 0) {
        std::fprintf(stderr,
                     "hapticctl: %llu samples missing (gaps in the tick numbers): hapticd "
                     "dropped them (see its log) or DDS lost them\n",
                     static_cast<unsigned long long>(missing));
    }
    return EXIT_SUCCESS;
}

// Renders a recorded CSV to PNG with gnuplot (Debian's gnuplot-nox), script on its stdin.
std::optional<std::string> readWholeFile(const std::string& path) {
    std::ifstream file(path);
    if (!file) {
        return std::nullopt;
    }
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
}

// Prints the end-to-end figures of the recording (closed_loop_report.hpp).
void printReport(const std::map<int, haptic::ctl::DeviceColumns>& devices, double clamp_n,
                 double thimble_max_force_n) {
    haptic::ctl::ContactQualitySettings settings;
    settings.clamp_n = clamp_n;
    haptic::ctl::ContactQualitySettings thimble_settings;
    thimble_settings.clamp_n = thimble_max_force_n;
    std::fputs(haptic::ctl::formatReport(devices, settings, thimble_settings).c_str(), stdout);
}

int plotTelemetry(const std::string& csv_path, std::string png_path, double clamp_n,
                  double thimble_max_force_n, const std::string& felt_path) {
    if (png_path.empty()) {
        png_path = csv_path + ".png";
    }
    const auto csv = readWholeFile(csv_path);
    if (!csv) {
        std::fprintf(stderr, "hapticctl: cannot read '%s'\n", csv_path.c_str());
        return kExitError;
    }
    // The recording's columns, read once for the felt log and the report. With a felt log
    // they are read, and the log matched, before gnuplot runs: a log that cannot be used is an
    // error, not a plot without it. Without one, after (as before the felt log existed).
    std::optional<std::map<int, haptic::ctl::DeviceColumns>> devices;
    bool with_felt = false;
    haptic::ctl::FeltLogPlot felt_plot;
    if (!felt_path.empty()) {
        const auto felt_text = readWholeFile(felt_path);
        if (!felt_text) {
            std::fprintf(stderr, "hapticctl: cannot read '%s'\n", felt_path.c_str());
            return kExitError;
        }
        haptic::ctl::RecordingInfo recording;
        std::vector<std::string> attached;
        try {
            recording = haptic::ctl::readRecordingInfo(*csv);
            devices = haptic::ctl::readTelemetryCsv(*csv);
        } catch (const std::runtime_error& e) {
            std::fprintf(stderr, "hapticctl: %s: %s\n", csv_path.c_str(), e.what());
            return kExitError;
        }
        try {
            attached = haptic::ctl::attachFeltLog(*devices, recording,
                                                  haptic::ctl::readFeltLog(*felt_text));
        } catch (const std::runtime_error& e) {
            std::fprintf(stderr, "hapticctl: %s: %s\n", felt_path.c_str(), e.what());
            return kExitError;
        }
        // The thimbles among them got the pad's columns: one plot line each.
        for (const auto& [index, device] : *devices) {
            if (device.values.contains("felt_force_x_n")) {
                felt_plot.devices.push_back(recording.device_names.at(index));
            }
        }
        if (attached.empty()) {
            std::fprintf(stderr, "hapticctl: '%s' names no device of the recording '%s'\n",
                         felt_path.c_str(), csv_path.c_str());
            return kExitError;
        }
        felt_plot.path = felt_path;
        felt_plot.complete_rows = haptic::ctl::completeFeltLogRows(*felt_text);
        felt_plot.origin_ns = recording.origin_ns;
        with_felt = true;
        for (const auto& [index, device] : *devices) {
            const auto& time = device.column("time_s");
            felt_plot.end_s =
                time.empty() ? felt_plot.end_s : std::max(felt_plot.end_s, time.back());
        }
    }
    int pipe_fds[2];
    if (::pipe(pipe_fds) != 0) {
        std::perror("hapticctl: pipe");
        return kExitError;
    }
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, pipe_fds[0], STDIN_FILENO);
    posix_spawn_file_actions_addclose(&actions, pipe_fds[1]);
    char program[] = "gnuplot";
    char* argv[] = {program, nullptr};
    pid_t pid = -1;
    const int spawned = posix_spawnp(&pid, program, &actions, nullptr, argv, environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(pipe_fds[0]);
    if (spawned != 0) {
        ::close(pipe_fds[1]);
        std::fprintf(stderr, "hapticctl: cannot run gnuplot (install gnuplot-nox): %s\n",
                     std::strerror(spawned));
        return kExitError;
    }
    const std::string script = haptic::ctl::telemetryPlotScript(
        csv_path, png_path, clamp_n, thimble_max_force_n, with_felt ? &felt_plot : nullptr);
    const bool written =
        ::write(pipe_fds[1], script.data(), script.size()) == static_cast<ssize_t>(script.size());
    ::close(pipe_fds[1]);
    int status = 0;
    ::waitpid(pid, &status, 0);
    if (!written || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::fprintf(stderr, "hapticctl: gnuplot failed on '%s'\n", csv_path.c_str());
        return kExitError;
    }
    std::printf("%s\n", png_path.c_str());
    if (!devices) {
        devices = haptic::ctl::readTelemetryCsv(*csv);
    }
    printReport(*devices, clamp_n, thimble_max_force_n);
    return EXIT_SUCCESS;
}

// Sends one command and waits for the reply carrying its request id. The command is
// (re)sent once the daemon's reader is matched and again every 500 ms until answered: a
// first send can reach the daemon before its reply writer has discovered our reader, and
// the daemon answers a repeated request id from its record instead of running it twice.
// What a reply means for the caller: its message, and the exit code.
int reportReply(const haptic::msgs::HapticCommandReply& reply) {
    const std::string message(reply.message.view());
    if (!reply.accepted) {
        std::fprintf(stderr, "hapticctl: refused: %s\n", message.c_str());
        return kExitRefused;
    }
    std::printf("%s\n", message.c_str());
    return EXIT_SUCCESS;
}

// The command through hapticd's local control socket; nullopt when no hapticd serves one on
// this host, for the caller to try DDS.
std::optional<int> sendCommandLocally(const haptic::config::DaemonConfig& cfg,
                                      const haptic::idl::HapticCommand& wire, double timeout_s) {
    namespace control = haptic::control;
    control::ControlClient client(haptic::config::controlSocketPath(cfg));
    if (const auto failed = connectLocally(client); failed != kConnected) {
        return failed == kNoLocalDaemon ? std::nullopt : std::optional<int>(failed);
    }
    std::vector<char> datagram;
    if (!control::encode(control::kCommandRequest, wire, datagram)) {
        std::fprintf(stderr, "hapticctl: the command does not encode\n");
        return kExitError;
    }
    const auto answer = client.request(datagram, toMs(timeout_s));
    if (!answer) {
        std::fprintf(stderr, "hapticctl: hapticd did not answer on %s: %s\n",
                     haptic::config::controlSocketPath(cfg).c_str(), client.error().c_str());
        return kExitNoDaemon;
    }
    haptic::idl::HapticCommandReply sample;
    haptic::msgs::HapticCommandReply reply;
    if (answer->kind != control::kReplyAnswer ||
        !control::decode(answer->body.data(), answer->body.size(), sample)) {
        std::fprintf(stderr, "hapticctl: malformed answer on the control socket\n");
        return kExitError;
    }
    // Another release's hapticd: the conversion names the schema it sent.
    if (const auto result = haptic::msgs::fromIdl(sample, reply); !result.ok()) {
        std::fprintf(stderr, "hapticctl: answer on the control socket refused: %s\n",
                     result.error.c_str());
        return kExitError;
    }
    return reportReply(reply);
}

int sendCommand(const haptic::config::DaemonConfig& cfg, haptic::msgs::CommandKind kind,
                const std::string& argument, double timeout_s, bool over_dds) {
    haptic::msgs::HapticCommand command;
    command.request_id = (static_cast<std::uint64_t>(::getpid()) << 32) ^
                         static_cast<std::uint64_t>(haptic::common::monotonicNowNs());
    command.header.seq = 1;
    command.header.stamp_ns = haptic::common::monotonicNowNs();
    command.header.source_id.assign("hapticctl");
    command.kind = kind;
    if (argument.size() > haptic::msgs::DeviceId::kMaxLength) {
        std::fprintf(stderr, "hapticctl: argument '%s' is longer than %zu characters\n",
                     argument.c_str(), haptic::msgs::DeviceId::kMaxLength);
        return kExitError;
    }
    command.argument.assign(argument);
    const auto wire = haptic::msgs::toIdl(command);
    if (!over_dds) {
        const auto local = sendCommandLocally(cfg, wire, timeout_s);
        // A stop must get through: when the socket fails it (permissions, a stalled or
        // flooded daemon), it goes over DDS as well, which takes estop from anyone.
        const bool try_dds = kind == haptic::msgs::CommandKind::kEstop && local &&
                             (*local == kExitError || *local == kExitNoDaemon);
        if (local && !try_dds) {
            return *local;
        }
        if (try_dds) {
            std::fprintf(stderr, "hapticctl: sending estop over DDS as well\n");
        }
    }

    haptic::ipc::DdsParticipant participant(haptic::ipc::ddsSettings(cfg.dds), "hapticctl");
    auto writer = participant.createWriter<haptic::idl::HapticCommandPubSubType>(
        haptic::ipc::kCommandTopic, haptic::ipc::TopicKind::kStream);
    auto reader = participant.createReader<haptic::idl::HapticCommandReplyPubSubType>(
        haptic::ipc::kCommandReplyTopic, haptic::ipc::TopicKind::kStream);

    const auto deadline = std::chrono::steady_clock::now() + toMs(timeout_s);
    auto last_sent = std::chrono::steady_clock::time_point{};
    bool sent = false;
    haptic::idl::HapticCommandReply sample;
    while (std::chrono::steady_clock::now() < deadline) {
        const auto now = std::chrono::steady_clock::now();
        if (writer.matchedReaders() > 0 && (!sent || now - last_sent >= 500ms)) {
            sent = writer.write(wire) || sent;
            last_sent = now;
        }
        if (!reader.waitAndTake(sample, 50ms)) {
            continue;
        }
        // Another release's reply: its request id would be read from another layout.
        if (sample.header().schema() != haptic::msgs::kSchema) {
            std::fprintf(stderr,
                         "hapticctl: a reply of message schema 0x%08x, this hapticctl reads "
                         "0x%08x: hapticd is from another release\n",
                         static_cast<unsigned>(sample.header().schema()),
                         static_cast<unsigned>(haptic::msgs::kSchema));
            return kExitError;
        }
        if (sample.request_id() != command.request_id) {
            continue;
        }
        haptic::msgs::HapticCommandReply reply;
        if (const auto result = haptic::msgs::fromIdl(sample, reply); !result.ok()) {
            std::fprintf(stderr, "hapticctl: malformed reply: %s\n", result.error.c_str());
            return kExitError;
        }
        return reportReply(reply);
    }
    if (sent) {
        std::fprintf(stderr, "hapticctl: hapticd did not answer on '%s' within %.1f s\n",
                     haptic::ipc::kCommandReplyTopic, timeout_s);
    } else {
        std::fprintf(stderr,
                     "hapticctl: no hapticd listening on '%s' (domain %d) within %.1f s; is "
                     "hapticd running?\n",
                     haptic::ipc::kCommandTopic, cfg.dds.domain_id, timeout_s);
    }
    return kExitNoDaemon;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "hapticctl - status and commands for the haptic runtime (hapticd's local control "
        "socket on its host, DDS elsewhere)"};
    app.set_version_flag("--version", "hapticctl " HAPTIC_VERSION);
    app.require_subcommand(1);
    // Global options may follow the subcommand too (hapticctl status --timeout 5).
    app.fallthrough();
    std::string config_path = HAPTIC_DEFAULT_CONFIG_DIR "/daemon.yaml";
    int dds_domain = -1;
    // A command waits longer than a status query: DDS discovery of the command reader and
    // the reply writer, measured here at 0.2 s usually, sometimes took over 2 s.
    double timeout_s = 0.0;
    app.add_option("-c,--config", config_path,
                   "daemon configuration file (for the DDS domain and profile)")
        ->capture_default_str();
    app.add_option("--dds-domain", dds_domain, "override dds.domain_id")->check(CLI::Range(0, 232));
    bool over_dds = false;
    app.add_flag("--over-dds", over_dds,
                 "skip the local control socket and use DDS, as on another host (status; "
                 "commands: only estop is taken)");
    app.add_option("--timeout", timeout_s,
                   "seconds to wait for the daemon's status (default 2), handsim's status or a "
                   "reply (default 5)")
        ->check(CLI::PositiveNumber);

    auto* status = app.add_subcommand("status", "print the daemon's state and loop statistics");
    auto* sim = app.add_subcommand(
        "sim", "print handsim's status: step rate and time, zeroed steps, rejected inputs");
    bool json = false;
    status->add_flag("--json", json,
                     "one JSON object instead of the screen (schema haptic.status/1, "
                     "docs/hapticctl.md)");
    sim->add_flag("--json", json,
                  "one JSON object instead of the screen (schema haptic.sim_status/1)");
    double interval_s = 1.0;
    int count = 0;
    auto* watch = app.add_subcommand("watch", "redraw the status screen live (Ctrl-C stops)");
    watch->add_option("-n,--interval", interval_s, "seconds between screens")
        ->capture_default_str()
        ->check(CLI::Range(0.05, 3600.0));
    watch->add_option("--count", count, "stop after this many screens (0: until Ctrl-C)")
        ->capture_default_str()
        ->check(CLI::NonNegativeNumber);

    std::string record_path;
    double record_duration_s = 5.0;
    auto* record = app.add_subcommand("record", "write haptic/telemetry to a CSV file");
    record->add_option("file", record_path, "CSV file to write ('-': standard output)")->required();
    record->add_option("--duration", record_duration_s, "seconds to record")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    std::string plot_path;
    std::string plot_output;
    auto* plot = app.add_subcommand("plot", "PNG of forces and loop timing from a recorded CSV");
    plot->add_option("file", plot_path, "CSV written by 'record'")->required();
    plot->add_option("-o,--output", plot_output, "PNG to write (default: <file>.png)");
    double plot_clamp_n = 10.0;
    plot->add_option("--exo-clamp-n", plot_clamp_n,
                     "the exoskeleton's force clamp (safety.max_force_n) for the clamp figure")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    double plot_thimble_max_force_n = 1.5;
    plot->add_option("--thimble-max-force-n", plot_thimble_max_force_n,
                     "the thimble's pad force limit (safety.max_force_n): the pad-force axis "
                     "shows twice it")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    std::string plot_felt;
    plot->add_option("--felt", plot_felt,
                     "the virtual user's felt log (hapticemu --felt-log) of the same run: the "
                     "felt pad force joins the thimble's panel and report");

    using haptic::msgs::CommandKind;
    struct Simple {
        const char* name;
        const char* help;
        CommandKind kind;
        CLI::App* sub{nullptr};
    };
    Simple simple[] = {
        {"enable", "start rendering (IDLE -> RENDERING)", CommandKind::kEnable},
        {"disable", "stop rendering, forces to zero (RENDERING -> IDLE)", CommandKind::kDisable},
        {"estop", "emergency stop: forces off until 'clear'", CommandKind::kEstop},
        {"clear", "clear a latched fault or an emergency stop (-> IDLE)", CommandKind::kClearFault},
    };
    for (auto& entry : simple) {
        entry.sub = app.add_subcommand(entry.name, entry.help);
    }
    std::string method_name;
    // The names hapticd knows, for --help; hapticd itself judges the name (it answers with
    // exit 2 and "unknown rendering method" for any other).
    std::string method_names;
    std::vector<std::string> method_list;
    for (const auto& entry :
         haptic::config::EnumTraits<haptic::config::RenderingMethod>::kEntries) {
        method_names += (method_names.empty() ? "" : ", ") + std::string(entry.name);
        method_list.emplace_back(entry.name);
    }
    auto* method =
        app.add_subcommand("method", "choose the rendering method (IDLE, or live while RENDERING)");
    method->add_option("name", method_name, "the exoskeleton's rendering method: " + method_names)
        ->required();
    bool bash_completion = false;  // answered below, before parsing
    app.add_flag("--bash-completion", bash_completion,
                 "print the bash completion script (generated from these options) and exit");
    // Before parsing: it needs no subcommand and no configuration.
    for (int i = 1; i < argc; ++i) {
        if (std::string(argv[i]) == "--bash-completion") {
            std::cout << haptic::ctl::bashCompletion(app, {{"method", method_list}});
            return EXIT_SUCCESS;
        }
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& error) {
        // --help is exit 0; any usage error is exit 1 like every other error.
        return app.exit(error) == 0 ? EXIT_SUCCESS : kExitError;
    }

    return haptic::process::runMain("hapticctl", [&] {
        auto cfg = haptic::config::loadDaemonConfig(config_path);
        if (dds_domain >= 0) {
            cfg.dds.domain_id = dds_domain;
        }
        haptic::process::setupLogging("hapticctl", "warn");
        const bool is_command = !status->parsed() && !sim->parsed() && !watch->parsed() &&
                                !record->parsed() && !plot->parsed();
        if (timeout_s <= 0.0) {
            // handsim's status comes every 500 ms on a volatile topic, after discovery,
            // which took about 2.4 s in a third of the end-to-end test's runs.
            timeout_s = is_command || sim->parsed() ? 5.0 : 2.0;
        }
        if (status->parsed()) {
            return printStatus(cfg, timeout_s, json, over_dds);
        }
        if (sim->parsed()) {
            return printSimStatus(cfg, timeout_s, json);
        }
        if (watch->parsed()) {
            return watchStatus(cfg, interval_s, count);
        }
        if (record->parsed()) {
            return recordTelemetry(cfg, record_path, record_duration_s, timeout_s);
        }
        if (plot->parsed()) {
            return plotTelemetry(plot_path, plot_output, plot_clamp_n, plot_thimble_max_force_n,
                                 plot_felt);
        }
        if (method->parsed()) {
            return sendCommand(cfg, CommandKind::kSetMethod, method_name, timeout_s, over_dds);
        }
        for (const auto& entry : simple) {
            if (entry.sub->parsed()) {
                return sendCommand(cfg, entry.kind, "", timeout_s, over_dds);
            }
        }
        return kExitError;  // CLI11 requires one subcommand, so this is not reached
    });
}
