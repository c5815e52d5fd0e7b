// hapticemu: emulates the exoskeleton or the thimble on a CAN bus (the real frames, device
// dynamics and a user model), the way libfranka's mock server stands in for the robot.
//
// This version validates a device file and prints what it would emulate. The bus
// transports, device dynamics and user model arrive with the CAN-drivers issue; until then
// it refuses to pretend and exits with kExitNotAvailable.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "haptic/config/device.hpp"
#include "haptic/config/error.hpp"
#include "haptic/process/logging.hpp"

namespace {
constexpr int kExitNotAvailable = 2;
}

int main(int argc, char** argv) {
    CLI::App app{"hapticemu - CAN device emulator for the exoskeleton and the thimble"};
    std::string device_path;
    bool check_only = false;
    app.add_option("-d,--device", device_path, "device configuration file")->required();
    app.add_flag("--check", check_only, "validate the device file, print a summary and exit");
    CLI11_PARSE(app, argc, argv);

    try {
        const auto device = haptic::config::loadDeviceConfig(device_path);
        haptic::process::setupLogging("hapticemu", "info");
        spdlog::info(
            "device '{}' ({}) on CAN interface '{}': command 0x{:03x}, state 0x{:03x}, "
            "heartbeat 0x{:03x}, fault 0x{:03x}",
            device.name, device.isExoskeleton() ? "exoskeleton" : "thimble", device.can.interface,
            device.can.command_id, device.can.state_id, device.can.heartbeat_id,
            device.can.fault_id);
        if (check_only) {
            return EXIT_SUCCESS;
        }
        std::fprintf(stderr,
                     "hapticemu: device emulation is not available in this version (it arrives "
                     "with the CAN drivers); only --check works\n");
        return kExitNotAvailable;
    } catch (const haptic::config::ConfigError& error) {
        std::fprintf(stderr, "hapticemu: configuration error: %s\n", error.what());
    } catch (const std::exception& error) {
        std::fprintf(stderr, "hapticemu: %s\n", error.what());
    }
    return EXIT_FAILURE;
}
