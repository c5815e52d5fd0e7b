// hapticemu: emulates the exoskeleton and the thimble on a CAN bus: the real frames, device
// dynamics, and either a built-in user motion or the virtual user, with fault injection from
// stdin (see fault_injector.hpp for the commands). It plays the part libfranka's mock server
// plays for the robot.
//
//   hapticemu -d config/devices/exoskeleton.yaml --bus udp [--udp-port 47000]
//   hapticemu -d config/devices/thimble.yaml --bus socketcan --interface vcan0
//   hapticemu --user config/user.yaml     every device the user wears, one hand, and the
//                                         tracker publishing that hand on tracking/hand
//                                         ("tracker stop" on stdin silences the tracker,
//                                         "tracker start" resumes it)
//   ... --estop-relay 0x0E0               also the E-stop relay's status on that id
//                                         ("estop press" on stdin presses its button)
//   ... --user FILE --felt-log felt.csv   what the user feels of each worn device, every
//                                         tick (hapticctl plot --felt reads it)
//
// It prints "ready" on stdout once the bus is open, and each fault command's result
// ("ok" or "error: ...") on stdout, so a test driving it through pipes can synchronise. With
// several devices a fault command starts with the device's name ("thimble stop-heartbeat").

#include <poll.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <exception>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "HandPosePubSubTypes.h"
#include "haptic/can/socketcan_bus.hpp"
#include "haptic/can/udp_bus.hpp"
#include "haptic/common/clock.hpp"
#include "haptic/config/device.hpp"
#include "haptic/config/error.hpp"
#include "haptic/config/virtual_user.hpp"
#include "haptic/emu/device_emulator.hpp"
#include "haptic/emu/estop_relay_emulator.hpp"
#include "haptic/emu/virtual_user.hpp"
#include "haptic/ipc/dds_participant.hpp"
#include "haptic/msgs/conversions.hpp"
#include "haptic/process/logging.hpp"
#include "haptic/process/main_skeleton.hpp"
#include "haptic/process/shutdown.hpp"

namespace {

// Splits what stdin delivered into lines and applies each as a fault command.
struct EmulatedDevice {
    haptic::config::DeviceConfig config;
    std::unique_ptr<haptic::emu::DeviceEmulator> emulator;
    bool timed_out{false};  // last seen emulator->commandTimedOut(), to log each change once
};

// A fault command for one of several devices names it first; a lone device needs no name.
bool applyFaultCommand(std::vector<EmulatedDevice>& devices, const std::string& line,
                       std::string& error) {
    if (devices.size() == 1) {
        return devices.front().emulator->faults().command(line, error);
    }
    const std::size_t space = line.find(' ');
    const std::string name = line.substr(0, space);
    std::string names;
    for (EmulatedDevice& device : devices) {
        if (device.config.name == name) {
            return device.emulator->faults().command(
                space == std::string::npos ? std::string() : line.substr(space + 1), error);
        }
        names += (names.empty() ? "" : ", ") + device.config.name;
    }
    error = "start the command with a device name (" + names + ")";
    return false;
}

class CommandReader {
  public:
    // Returns false at end of input.
    // `tracker_silenced` is null without a virtual user.
    bool readAvailable(std::vector<EmulatedDevice>& devices, haptic::emu::EstopRelayEmulator* relay,
                       bool* tracker_silenced) {
        char buffer[512];
        const ssize_t count = ::read(STDIN_FILENO, buffer, sizeof(buffer));
        if (count <= 0) {
            return count < 0 && errno == EINTR;
        }
        pending_.append(buffer, static_cast<std::size_t>(count));
        std::size_t newline = 0;
        while ((newline = pending_.find('\n')) != std::string::npos) {
            const std::string line = pending_.substr(0, newline);
            pending_.erase(0, newline + 1);
            if (line.find_first_not_of(" \t\r") == std::string::npos) {
                continue;
            }
            std::string error;
            const bool for_relay = line.rfind("estop ", 0) == 0;
            const bool for_tracker = line.rfind("tracker ", 0) == 0;
            if (for_tracker) {
                const std::string verb = line.substr(8);
                if (tracker_silenced == nullptr) {
                    error = "no tracker (start with --user FILE)";
                } else if (verb == "stop" || verb == "start") {
                    *tracker_silenced = verb == "stop";
                } else {
                    error = "tracker stop|start";
                }
                if (error.empty()) {
                    std::printf("ok %s\n", line.c_str());
                } else {
                    std::printf("error: %s\n", error.c_str());
                }
            } else if (for_relay && relay == nullptr) {
                error = "no E-stop relay emulated (start with --estop-relay ID)";
            } else if (for_relay ? relay->command(line.substr(6), error)
                                 : applyFaultCommand(devices, line, error)) {
                std::printf("ok %s\n", line.c_str());
            } else {
                std::printf("error: %s\n", error.c_str());
            }
            std::fflush(stdout);
        }
        return true;
    }

  private:
    std::string pending_;
};

// The virtual user's log of what it felt, one row per worn device per tick. stamp_ns is
// CLOCK_MONOTONIC, the clock of hapticd's telemetry stamps, so a recording on the same host
// lines up with it (hapticctl plot --felt).
class FeltLog {
  public:
    explicit FeltLog(const std::string& path) : path_(path), file_(std::fopen(path.c_str(), "w")) {
        if (file_ == nullptr) {
            throw std::runtime_error("--felt-log " + path + ": " + std::strerror(errno));
        }
        // A buffer that holds the 100 ticks between flushes, so the file only ever grows by
        // whole ticks (a reader follows it while the run goes on) and not mid-line.
        std::setvbuf(file_, nullptr, _IOFBF, kBufferBytes);
        std::fprintf(file_,
                     "# hapticemu " HAPTIC_VERSION
                     " felt log: per worn device, how deep the user's finger reaches into the "
                     "scene's static objects, and for a thimble the pad under its plate (config "
                     "pad; pose_known 0: no pad contact known); stamp_ns is CLOCK_MONOTONIC; "
                     "force on the pad and moment about the device origin, device frame\n"
                     "stamp_ns,device,finger_penetration_m,pose_known,indentation_m,force_x_n,"
                     "force_y_n,force_z_n,moment_x_nm,moment_y_nm,moment_z_nm\n");
    }
    ~FeltLog() {
        if (std::fclose(file_) != 0 && !failed_) {
            spdlog::error("--felt-log {}: closing failed ({})", path_, std::strerror(errno));
        }
    }
    FeltLog(const FeltLog&) = delete;
    FeltLog& operator=(const FeltLog&) = delete;

    void write(std::int64_t stamp_ns, const std::vector<haptic::emu::VirtualUser::Felt>& felt) {
        if (failed_) {
            return;
        }
        bool ok = true;
        for (const auto& device : felt) {
            const haptic::emu::FeltPadContact& c = device.pad;
            ok = ok && std::fprintf(file_, "%lld,%s,%.7f,%d,%.7f,%.5f,%.5f,%.5f,%.7f,%.7f,%.7f\n",
                                    static_cast<long long>(stamp_ns), device.device.c_str(),
                                    device.finger_penetration_m, c.pose_known ? 1 : 0,
                                    c.indentation_m, c.force_device_n.x(), c.force_device_n.y(),
                                    c.force_device_n.z(), c.moment_device_nm.x(),
                                    c.moment_device_nm.y(), c.moment_device_nm.z()) > 0;
        }
        // A reader follows the file while the run goes on (the demo plots before stopping us).
        if (++ticks_ % 100 == 0) {
            ok = ok && std::fflush(file_) == 0;
        }
        if (!ok) {
            // The devices go on: a full disk must not stop the emulated hardware, only its log.
            failed_ = true;
            spdlog::error("--felt-log {}: writing failed ({}); no more rows are written", path_,
                          std::strerror(errno));
        }
    }

  private:
    // 100 ticks of a few devices' rows (about 110 bytes each).
    static constexpr std::size_t kBufferBytes = 1 << 17;
    std::string path_;
    std::FILE* file_;
    std::uint64_t ticks_{0};
    bool failed_{false};
};

std::string readFile(const std::filesystem::path& path) {
    std::ifstream file(path);
    if (!file) {
        throw std::runtime_error(path.string() + ": cannot open the replay file");
    }
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"hapticemu - CAN device emulator for the exoskeleton and the thimble"};
    app.set_version_flag("--version", "hapticemu " HAPTIC_VERSION);
    std::vector<std::string> device_paths;
    std::string user_path;
    bool check_only = false;
    std::string bus_kind = "udp";
    std::string interface;
    int udp_port = 47000;
    int udp_slots = 8;
    std::string mode = "stream";
    double duration_s = 0.0;
    int dds_domain = -1;
    std::string log_level = "info";
    auto* device_option =
        app.add_option("-d,--device", device_paths,
                       "device configuration file; repeat it for several devices on one bus");
    auto* user_option = app.add_option(
        "--user", user_path,
        "virtual user file (config/user.yaml): emulates every device it lists, worn by one "
        "hand, and publishes that hand on the tracker topic");
    device_option->excludes(user_option);
    app.add_flag("--check", check_only, "validate the files, print a summary and exit");
    app.add_option("--bus", bus_kind, "udp or socketcan")
        ->check(CLI::IsMember({"udp", "socketcan"}));
    app.add_option("--interface", interface, "SocketCAN interface (default: the device file's)");
    auto* udp_port_option =
        app.add_option("--udp-port", udp_port,
                       "first UDP port of the bus's port block (default: the device file's "
                       "can.udp_port)")
            ->check(CLI::Range(1, 65535));
    auto* udp_slots_option =
        app.add_option("--udp-slots", udp_slots,
                       "parties on the UDP bus (default: the device file's can.udp_slots)")
            ->check(CLI::Range(2, 32));
    app.add_option("--mode", mode,
                   "stream (clocked, like the device) or lockstep (one tick per "
                   "command, for tests)")
        ->check(CLI::IsMember({"stream", "lockstep"}));
    app.add_option("--duration", duration_s, "stop after this many seconds (0: until signalled)");
    app.add_option("--dds-domain", dds_domain, "with --user: override dds.domain_id")
        ->check(CLI::Range(0, 232));
    std::string estop_relay_id;
    app.add_option("--estop-relay", estop_relay_id,
                   "also emulate the E-stop relay, sending its status on this CAN id (hex, as "
                   "daemon.yaml's estop_relay.status_id); commands on stdin: estop press|release|"
                   "silence|resume|corrupt N");
    std::string felt_log_path;
    app.add_option("--felt-log", felt_log_path,
                   "with --user: write what the user feels of each worn device (finger "
                   "penetration, the pad under a thimble), every tick, to this CSV (hapticctl "
                   "plot --felt)")
        ->needs(user_option);
    auto* log_level_option = app.add_option(
        "--log-level", log_level, "trace, debug, info, warn, error (default: the user file's)");
    CLI11_PARSE(app, argc, argv);
    if (device_paths.empty() && user_path.empty()) {
        std::fprintf(stderr, "hapticemu: give --device FILE (one or more) or --user FILE\n");
        return 2;
    }

    return haptic::process::runMain("hapticemu", [&] {
        std::optional<haptic::config::VirtualUserConfig> user_config;
        std::vector<EmulatedDevice> devices;
        if (!user_path.empty()) {
            user_config = haptic::config::loadVirtualUserConfig(user_path);
            if (dds_domain >= 0) {
                user_config->dds.domain_id = dds_domain;
            }
            if (log_level_option->count() == 0) {
                log_level = std::string(haptic::config::toString(user_config->log_level));
            }
            for (const auto& device : user_config->devices) {
                devices.push_back({device, nullptr});
            }
        } else {
            for (const auto& path : device_paths) {
                devices.push_back({haptic::config::loadDeviceConfig(path), nullptr});
            }
        }
        haptic::process::setupLogging("hapticemu", log_level);
        const haptic::config::DeviceConfig& first = devices.front().config;
        // The emulator joins the bus the device files describe, as hapticd does, unless told
        // otherwise.
        if (udp_port_option->count() == 0) {
            udp_port = first.can.udp_port;
        }
        if (udp_slots_option->count() == 0) {
            udp_slots = first.can.udp_slots;
        }
        if (interface.empty()) {
            interface = first.can.interface;
        }
        if (bus_kind == "socketcan" && interface.empty()) {
            throw std::runtime_error("--bus socketcan: " + first.source.string() +
                                     " names no can.interface (its can.transport is udp); "
                                     "give --interface");
        }
        std::vector<std::uint32_t> command_ids;
        for (const EmulatedDevice& device : devices) {
            const auto& can = device.config.can;
            if (user_path.empty() && can.bus() != first.can.bus()) {
                throw std::runtime_error("device '" + device.config.name +
                                         "' is on another bus than '" + first.name +
                                         "'; one hapticemu emulates one bus");
            }
            spdlog::info(
                "device '{}' ({}): command 0x{:03x}, state 0x{:03x}, heartbeat 0x{:03x}, fault "
                "0x{:03x}",
                device.config.name, device.config.isExoskeleton() ? "exoskeleton" : "thimble",
                can.command_id, can.state_id, can.heartbeat_id, can.fault_id);
            command_ids.push_back(can.command_id);
        }
        std::unique_ptr<haptic::emu::EstopRelayEmulator> relay;
        if (!estop_relay_id.empty()) {
            std::size_t parsed = 0;
            unsigned long id = 0;
            try {
                id = std::stoul(estop_relay_id, &parsed, 0);
            } catch (const std::exception&) {
                parsed = 0;
            }
            if (parsed != estop_relay_id.size() || id > 0x7FF) {
                throw std::runtime_error("--estop-relay " + estop_relay_id +
                                         ": expected an 11-bit CAN id such as 0x0E0");
            }
            relay =
                std::make_unique<haptic::emu::EstopRelayEmulator>(static_cast<std::uint32_t>(id));
            spdlog::info("E-stop relay: status 0x{:03x} every 10 ms, released", id);
        }
        std::unique_ptr<haptic::emu::VirtualUser> user;
        if (user_config) {
            const auto& scene = user_config->scene;
            const std::string replay =
                scene.tracking.source == haptic::config::TrackingSource::kReplay
                    ? readFile(scene.tracking.replay_file)
                    : std::string();
            user = std::make_unique<haptic::emu::VirtualUser>(*user_config, replay);
            spdlog::info(
                "virtual user: intent from scene '{}', tracker on '{}' at {} Hz, {} ms latency",
                scene.name, user_config->tracker.topic, user_config->tracker.rate_hz,
                user_config->tracker.latency_ms);
        }
        if (check_only) {
            return EXIT_SUCCESS;
        }
        std::unique_ptr<haptic::can::CanBus> bus;
        if (bus_kind == "udp") {
            haptic::can::UdpBusConfig udp;
            udp.base_port = static_cast<std::uint16_t>(udp_port);
            udp.slots = static_cast<std::uint16_t>(udp_slots);
            bus = std::make_unique<haptic::can::UdpBus>(udp);
            spdlog::info("on {}", haptic::can::describe(udp));
        } else {
            haptic::can::SocketCanConfig socketcan;
            socketcan.interface = interface;
            socketcan.fd = first.can.fd;
            socketcan.receive_ids = command_ids;
            bus = std::make_unique<haptic::can::SocketCanBus>(socketcan);
            spdlog::info("on SocketCAN {}", interface);
        }
        haptic::emu::EmulatorOptions options;
        options.mode = mode == "lockstep" ? haptic::emu::EmulatorMode::kLockstep
                                          : haptic::emu::EmulatorMode::kStream;
        for (EmulatedDevice& device : devices) {
            device.emulator = haptic::emu::makeEmulator(device.config, *bus, options);
            if (user) {
                user->wear(device.config, *device.emulator);
            }
        }
        std::unique_ptr<FeltLog> felt_log;
        if (!felt_log_path.empty()) {
            felt_log = std::make_unique<FeltLog>(felt_log_path);
        }
        std::unique_ptr<haptic::ipc::DdsParticipant> participant;
        haptic::ipc::DdsWriter<haptic::idl::HandPose> tracker_writer;
        if (user) {
            participant = std::make_unique<haptic::ipc::DdsParticipant>(
                haptic::ipc::ddsSettings(user_config->dds), "hapticemu");
            tracker_writer = participant->createWriter<haptic::idl::HandPosePubSubType>(
                user_config->tracker.topic, haptic::ipc::TopicKind::kStream);
        }

        haptic::process::installShutdownHandlers();
        std::printf("ready\n");
        std::fflush(stdout);
        CommandReader commands;
        bool stdin_open = true;
        const std::int64_t start_ns = haptic::common::monotonicNowNs();
        const auto duration_ns = static_cast<std::int64_t>(duration_s * 1e9);
        // Stream mode runs on its own 1 kHz clock, as a device's controller does: it sleeps
        // until the next tick and then drains the bus. Waiting on the socket instead would
        // make every frame hapticd sends wake this process from inside hapticd's write()
        // (a cross-CPU wake-up, tens of µs in a VM) and charge it to hapticd's RT tick.
        // Lockstep mode answers each command at once, so it waits on the socket.
        const bool clocked = options.mode == haptic::emu::EmulatorMode::kStream;
        constexpr std::int64_t kTickNs = 1'000'000;
        std::int64_t next_tick_ns = start_ns;
        std::uint64_t tracker_dropped = 0;
        bool tracker_silenced = false;
        while (!haptic::process::shutdownRequested()) {
            std::int64_t now_ns = haptic::common::monotonicNowNs();
            if (duration_ns > 0 && now_ns - start_ns >= duration_ns) {
                break;
            }
            // Drain the bus before tick() judges the command timeout: after a stall of this
            // process the commands hapticd sent meanwhile are waiting here, and the device
            // must be judged on them, not on its own absence.
            haptic::can::CanFrame frame;
            for (int i = 0; i < 256 && bus->read(frame) == haptic::can::IoResult::kOk; ++i) {
                now_ns = haptic::common::monotonicNowNs();
                for (std::size_t d = 0; d < devices.size(); ++d) {
                    // Each device listens to its own command id, as on a real bus.
                    if (devices.size() == 1 || frame.id == command_ids[d]) {
                        devices[d].emulator->handleFrame(frame, now_ns);
                    }
                }
            }
            now_ns = haptic::common::monotonicNowNs();
            const double t_s = 1e-9 * static_cast<double>(now_ns - start_ns);
            if (user) {
                user->drive(t_s);
            }
            for (EmulatedDevice& device : devices) {
                device.emulator->tick(now_ns);
                if (device.emulator->commandTimedOut() != device.timed_out) {
                    device.timed_out = device.emulator->commandTimedOut();
                    if (device.timed_out) {
                        spdlog::warn("'{}': no valid command for {} ms: safe state, fault 4",
                                     device.config.name, device.config.can.command_timeout_ms);
                    } else {
                        spdlog::info("'{}': safe command received, command timeout cleared",
                                     device.config.name);
                    }
                }
            }
            if (relay) {
                relay->tick(*bus, now_ns);
            }
            if (felt_log) {
                felt_log->write(now_ns, user->feel(t_s));
            }
            if (user) {
                const auto pose = user->track(now_ns, t_s);
                if (pose && !tracker_silenced) {
                    if (!tracker_writer.write(haptic::msgs::toIdl(*pose))) {
                        ++tracker_dropped;
                    }
                }
            }
            pollfd fds[2] = {{clocked ? -1 : bus->pollFd(), POLLIN, 0},
                             {stdin_open ? 0 : -1, POLLIN, 0}};
            if (clocked) {
                next_tick_ns += kTickNs;
                if (next_tick_ns < now_ns - 10 * kTickNs) {
                    next_tick_ns = now_ns + kTickNs;  // starved for a while: do not catch up
                }
                const timespec wake{static_cast<time_t>(next_tick_ns / 1'000'000'000),
                                    static_cast<long>(next_tick_ns % 1'000'000'000)};
                while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &wake, nullptr) == EINTR &&
                       !haptic::process::shutdownRequested()) {
                }
            }
            if (::poll(fds, 2, clocked ? 0 : 1) < 0 && errno != EINTR) {
                throw std::runtime_error(std::string("poll: ") + std::strerror(errno));
            }
            if ((fds[1].revents & (POLLIN | POLLHUP)) != 0) {
                stdin_open = commands.readAvailable(devices, relay.get(),
                                                    user ? &tracker_silenced : nullptr);
            }
        }
        for (const EmulatedDevice& device : devices) {
            spdlog::info("stopping '{}': {} commands accepted, {} rejected, {} command timeouts",
                         device.config.name, device.emulator->commandsAccepted(),
                         device.emulator->rejects().total(), device.emulator->commandTimeouts());
        }
        if (user) {
            spdlog::info("tracker: {} poses published, {} not written", user->samplesPublished(),
                         tracker_dropped);
        }
        return EXIT_SUCCESS;
    });
}
