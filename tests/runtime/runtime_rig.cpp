#include "runtime_rig.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "haptic/runtime/thimble_channel.hpp"

namespace haptic::testing {
namespace {

std::vector<config::DeviceConfig> shippedDevices() {
    const std::string dir = HAPTIC_CONFIG_DIR;
    return {config::loadDeviceConfig(dir + "/devices/exoskeleton.yaml"),
            config::loadDeviceConfig(dir + "/devices/thimble.yaml")};
}

daemon::CoreSettings coreSettings() {
    daemon::CoreSettings settings;
    for (const auto& entry : config::EnumTraits<config::RenderingMethod>::kEntries) {
        settings.known_methods.emplace_back(entry.name);
    }
    settings.rendering_method = "linearized_subspace";
    settings.stall_limit_ns = 10'000'000;  // can.command_timeout_ms of the shipped devices
    return settings;
}

std::vector<daemon::DeviceDescriptor> descriptors() {
    return {{"exo", msgs::DeviceKind::kExoskeleton, 3, 1},
            {"thimble", msgs::DeviceKind::kThimble, 3, 3}};
}

}  // namespace

RuntimeRig::RuntimeRig() : RuntimeRig([](std::vector<config::DeviceConfig>&) {}) {}

RuntimeRig::RuntimeRig(const std::function<void(std::vector<config::DeviceConfig>&)>& adjust)
    : devices([&adjust] {
          auto shipped = shippedDevices();
          adjust(shipped);
          return shipped;
      }()),
      core(coreSettings(), descriptors()),
      runtime(devices, {&host, &host}, runtime::ChannelSettings{}) {
    host.connect(target);
    for (const auto& device : devices) {
        emulators.push_back(emu::makeEmulator(device, target, emu::EmulatorOptions{}));
    }
    core.markStarted(now);

    // A wall at MCP <= -0.4 rad, beyond the joint's -20 degree limit: the emulated finger is
    // always inside it, so the renderer always asks for force (saturated by the port guard).
    constraint_set.header.source_id.assign("exo");
    constraint_set.dof = 3;
    msgs::LinearConstraint wall;
    wall.a = {-1.0, 0.0, 0.0};
    wall.b = 0.4;
    constraint_set.constraints.push_back(wall);
    // A flat object 0.5 mm into the thimble's pad (64 samples).
    contact_surface.header.source_id.assign("thimble");
    for (int i = 0; i < 8; ++i) {
        for (int j = 0; j < 8; ++j) {
            msgs::ContactSample s;
            s.p_device_m = {-0.0035 + 0.001 * i, -0.0035 + 0.001 * j, 0.017};
            s.signed_distance_m = -0.0005;
            s.normal_device = {0.0, 0.0, -1.0};
            s.weight = 1e-6;
            contact_surface.samples.push_back(s);
        }
    }
}

void RuntimeRig::devicesOnly(int milliseconds) {
    for (int i = 0; i < milliseconds; ++i) {
        advanceDevices();
    }
}

void RuntimeRig::advanceDevices() {
    now += kMs;
    host.setTime(now);
    target.setTime(now);
    can::CanFrame frame;
    while (target.read(frame) == can::IoResult::kOk) {
        for (auto& emulator : emulators) {
            emulator->handleFrame(frame, now);
        }
    }
    for (auto& emulator : emulators) {
        emulator->tick(now);
    }
    if (estop_relay) {
        estop_relay->tick(target, now);
    }
}

void RuntimeRig::attachEstopRelay() {
    estop_relay = std::make_unique<emu::EstopRelayEmulator>(kEstopRelayId);
    runtime.attachEstopRelay(kExo, kEstopRelayId, 30 * kMs);
}

void RuntimeRig::tick() {
    advanceDevices();
    runtime.read(now);
    daemon::TickTiming timing;
    core.update(now, timing);
    runtime.compute(core, now);
    if (core.snapshotDue(now)) {
        core.fillStatus(now, status);
    }
    runtime.write();
    for (std::size_t i = 0; i < core.deviceCount(); ++i) {
        core.fillDeviceState(i, now, device_state);
        core.fillTelemetry(i, tick_count, now, timing, telemetry);
    }
    ++tick_count;
}

void RuntimeRig::offerContact() {
    constraint_set.header.seq++;
    constraint_set.header.stamp_ns = now;
    contact_surface.header.seq++;
    contact_surface.header.stamp_ns = now;
    (void)core.offerConstraintSet(kExo, constraint_set, now);
    (void)core.offerContactSurface(kThimble, contact_surface, now);
}

bool RuntimeRig::command(msgs::CommandKind kind, const char* argument) {
    command_scratch = msgs::HapticCommand{};
    command_scratch.request_id++;
    command_scratch.kind = kind;
    command_scratch.argument.assign(argument);
    return core.applyCommand(command_scratch, now, reply).accepted;
}

void RuntimeRig::emulatorFault(std::size_t device, const char* line) {
    std::string error;
    ASSERT_TRUE(emulators[device]->faults().command(line, error)) << error;
}

void renderWithContact(RuntimeRig& rig) {
    rig.offerContact();
    rig.ticks(20);  // devices heard, state fresh
    ASSERT_TRUE(rig.command(msgs::CommandKind::kEnable));
    for (int i = 0; i < 300; ++i) {
        if (i % 10 == 0) {
            rig.offerContact();  // a 100 Hz sim
        }
        rig.tick();
    }
    ASSERT_EQ(rig.core.state(), msgs::DaemonState::kRendering);
}

double distance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
    double sum = 0.0;
    for (std::size_t i = 0; i < 3; ++i) {
        sum += (a[i] - b[i]) * (a[i] - b[i]);
    }
    return std::sqrt(sum);
}

const std::array<double, 3>& retract(RuntimeRig& rig) {
    return static_cast<runtime::ThimbleChannel&>(rig.runtime.channel(kThimble))
        .retractServoAngles();
}

double RuntimeRig::exoForce() const {
    return core.deviceReport(kExo).exoskeleton.actuator_force_cmd_n;
}

std::array<double, 3> RuntimeRig::thimbleTargets() const {
    const auto& commanded = core.deviceReport(kThimble).thimble.servo_angle_cmd_rad;
    return {commanded[0], commanded[1], commanded[2]};
}

}  // namespace haptic::testing
