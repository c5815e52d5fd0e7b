// hapticemu: emulates the exoskeleton or the thimble on a CAN bus: the real frames, device
// dynamics and a user model, with fault injection from stdin (see fault_injector.hpp for the
// commands). It plays the part libfranka's mock server plays for the robot.
//
//   hapticemu -d config/devices/exoskeleton.yaml --bus udp [--udp-port 47000]
//   hapticemu -d config/devices/thimble.yaml --bus socketcan --interface vcan0
//
// It prints "ready" on stdout once the bus is open, and each fault command's result
// ("ok" or "error: ...") on stdout, so a test driving it through pipes can synchronise.

#include <poll.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <memory>
#include <string>

#include "haptic/can/socketcan_bus.hpp"
#include "haptic/can/udp_bus.hpp"
#include "haptic/common/clock.hpp"
#include "haptic/config/device.hpp"
#include "haptic/config/error.hpp"
#include "haptic/emu/device_emulator.hpp"
#include "haptic/process/logging.hpp"
#include "haptic/process/main_skeleton.hpp"
#include "haptic/process/shutdown.hpp"

namespace {

// Splits what stdin delivered into lines and applies each as a fault command.
class CommandReader {
  public:
    // Returns false at end of input.
    bool readAvailable(haptic::emu::FaultInjector& faults) {
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
            if (faults.command(line, error)) {
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

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"hapticemu - CAN device emulator for the exoskeleton and the thimble"};
    std::string device_path;
    bool check_only = false;
    std::string bus_kind = "udp";
    std::string interface;
    int udp_port = 47000;
    int udp_slots = 8;
    std::string mode = "stream";
    double duration_s = 0.0;
    std::string log_level = "info";
    app.add_option("-d,--device", device_path, "device configuration file")->required();
    app.add_flag("--check", check_only, "validate the device file, print a summary and exit");
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
    app.add_option("--log-level", log_level, "trace, debug, info, warn, error");
    CLI11_PARSE(app, argc, argv);

    return haptic::process::runMain("hapticemu", [&] {
        const auto device = haptic::config::loadDeviceConfig(device_path);
        haptic::process::setupLogging("hapticemu", log_level);
        // The emulator joins the bus the device file describes, as hapticd does, unless told
        // otherwise.
        if (udp_port_option->count() == 0) {
            udp_port = device.can.udp_port;
        }
        if (udp_slots_option->count() == 0) {
            udp_slots = device.can.udp_slots;
        }
        if (interface.empty()) {
            interface = device.can.interface;
        }
        spdlog::info(
            "device '{}' ({}): command 0x{:03x}, state 0x{:03x}, heartbeat 0x{:03x}, fault "
            "0x{:03x}",
            device.name, device.isExoskeleton() ? "exoskeleton" : "thimble", device.can.command_id,
            device.can.state_id, device.can.heartbeat_id, device.can.fault_id);
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
            socketcan.fd = device.can.fd;
            socketcan.receive_ids = {device.can.command_id};
            bus = std::make_unique<haptic::can::SocketCanBus>(socketcan);
            spdlog::info("on SocketCAN {}", interface);
        }
        haptic::emu::EmulatorOptions options;
        options.mode = mode == "lockstep" ? haptic::emu::EmulatorMode::kLockstep
                                          : haptic::emu::EmulatorMode::kStream;
        auto emulator = haptic::emu::makeEmulator(device, *bus, options);

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
        while (!haptic::process::shutdownRequested()) {
            std::int64_t now_ns = haptic::common::monotonicNowNs();
            if (duration_ns > 0 && now_ns - start_ns >= duration_ns) {
                break;
            }
            emulator->tick(now_ns);
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
                stdin_open = commands.readAvailable(emulator->faults());
            }
            haptic::can::CanFrame frame;
            for (int i = 0; i < 256 && bus->read(frame) == haptic::can::IoResult::kOk; ++i) {
                now_ns = haptic::common::monotonicNowNs();
                emulator->handleFrame(frame, now_ns);
            }
        }
        const auto& rejects = emulator->rejects();
        spdlog::info("stopping: {} commands accepted, {} rejected", emulator->commandsAccepted(),
                     rejects.total());
        return EXIT_SUCCESS;
    });
}
