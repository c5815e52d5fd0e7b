// libFuzzer targets for the exoskeleton and the thimble frame decoders and the drivers
// behind them: built twice, as fuzz_exoskeleton_frames (HAPTIC_FUZZ_EXOSKELETON=1) and
// fuzz_thimble_frames (=0). The input is read as a stream of frames: an id picked among the device
// ids (or any 11/29-bit id), flags, a length and payload bytes, so most inputs reach the CRC,
// counter and range checks rather than stopping at "not our id". Invariants are checked with
// __builtin_trap so a violation is a crash libFuzzer reports:
//   - an accepted frame decodes to finite values inside the configured limits (+ margins);
//   - every rejected frame is counted exactly once.

#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstdint>

#include "haptic/can/loopback_bus.hpp"
#include "haptic/config/device.hpp"
#include "haptic/devices/exoskeleton_driver.hpp"
#include "haptic/devices/thimble_driver.hpp"
#include "haptic/protocol/exoskeleton_protocol.hpp"
#include "haptic/protocol/thimble_protocol.hpp"

namespace {

using namespace haptic;

// The shipped device files' values (config/devices/*.yaml). The fuzz build cannot link the
// YAML loader (see CMakeLists.txt), and the decoders only need ids and limits.
config::CanConfig canConfig(std::uint32_t command, std::uint32_t state, std::uint32_t heartbeat,
                            std::uint32_t fault) {
    config::CanConfig can;
    can.interface = "can0";
    can.command_id = command;
    can.state_id = state;
    can.heartbeat_id = heartbeat;
    can.fault_id = fault;
    can.heartbeat_timeout_ms = 50;
    can.state_timeout_ms = 10;
    return can;
}

config::DeviceConfig exoskeletonConfig() {
    config::DeviceConfig device;
    device.name = "exo";
    device.can = canConfig(0x101, 0x181, 0x701, 0x081);
    config::ExoskeletonConfig exo;
    exo.actuator = {0.0, 0.025, 40.0, 0.08, 0.005};
    constexpr double kDeg = 3.14159265358979323846 / 180.0;
    exo.finger.joint_limits_rad = {
        {{-20.0 * kDeg, 90.0 * kDeg}, {0.0, 110.0 * kDeg}, {0.0, 80.0 * kDeg}}};
    device.params = exo;
    return device;
}

config::DeviceConfig thimbleConfig() {
    config::DeviceConfig device;
    device.name = "thimble";
    device.can = canConfig(0x102, 0x182, 0x702, 0x082);
    config::ThimbleConfig thimble;
    constexpr double kDeg = 3.14159265358979323846 / 180.0;
    thimble.servos = {-30.0 * kDeg, 90.0 * kDeg, 400.0 * kDeg, 0.03};
    device.params = thimble;
    return device;
}

struct Devices {
    config::DeviceConfig exo = exoskeletonConfig();
    config::DeviceConfig thimble = thimbleConfig();
};

const Devices& shippedDevices() {
    static const Devices loaded;
    return loaded;
}

void require(bool condition) {
    if (!condition) {
        __builtin_trap();
    }
}

bool within(double value, double lo, double hi) {
    return std::isfinite(value) && value >= lo && value <= hi;
}

can::CanFrame nextFrame(FuzzedDataProvider& input, const config::CanConfig& a,
                        const config::CanConfig& b) {
    can::CanFrame frame;
    const std::uint32_t ids[] = {a.command_id, a.state_id, a.heartbeat_id, a.fault_id,
                                 b.command_id, b.state_id, b.heartbeat_id, b.fault_id};
    const auto pick = input.ConsumeIntegralInRange<std::uint8_t>(0, 9);
    frame.id = pick < 8 ? ids[pick] : input.ConsumeIntegral<std::uint32_t>() & 0x1FFFFFFFU;
    frame.flags = pick < 8 && input.ConsumeBool() ? 0 : input.ConsumeIntegral<std::uint8_t>();
    frame.length = input.ConsumeBool() ? 8 : input.ConsumeIntegralInRange<std::uint8_t>(0, 64);
    for (std::uint8_t i = 0; i < frame.length; ++i) {
        frame.data[i] = input.ConsumeIntegral<std::uint8_t>();
    }
    // Half of the frames get a valid CRC so the payload checks are reached.
    if (frame.length >= 8 && input.ConsumeBool()) {
        frame.data[0] = protocol::crc8SaeJ1850(frame.id, &frame.data[1]);
    }
    return frame;
}

[[maybe_unused]] void checkExoskeleton(const protocol::ExoskeletonMessage& message,
                                       const config::DeviceConfig& device) {
    using Type = protocol::ExoskeletonMessage::Type;
    const auto& actuator = device.exoskeleton().actuator;
    const double force_limit = actuator.max_force_n * 1.1 + 0.02;
    switch (message.type) {
        case Type::kCommand:
            require(within(message.command.force_n, -actuator.max_force_n - 0.02,
                           actuator.max_force_n + 0.02));
            break;
        case Type::kActuatorState:
            require(within(message.actuator.stroke_m, actuator.stroke_min_m - 0.0011,
                           actuator.stroke_max_m + 0.0011));
            require(within(message.actuator.force_n, -force_limit, force_limit));
            require(message.actuator.command_echo < 16);
            break;
        case Type::kEncoders:
            for (std::size_t j = 0; j < 3; ++j) {
                const auto& limits = device.exoskeleton().finger.joint_limits_rad[j];
                require(within(message.encoders.joint_rad[j], limits.min - 0.1, limits.max + 0.1));
            }
            break;
        default:
            break;
    }
}

}  // namespace

constexpr bool kExoskeleton = HAPTIC_FUZZ_EXOSKELETON != 0;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const Devices& d = shippedDevices();
    FuzzedDataProvider input(data, size);
    protocol::ExoskeletonCodec exo_codec(d.exo);
    protocol::ThimbleCodec thimble_codec(d.thimble);
    can::LoopbackBus bus;
    devices::ExoskeletonDriver exo_driver(d.exo, bus);
    devices::ThimbleDriver thimble_driver(d.thimble, bus);
    std::int64_t now_ns = 0;
    const auto& servos = d.thimble.thimble().servos;
    for (int i = 0; i < 256 && input.remaining_bytes() > 0; ++i) {
        const can::CanFrame frame = nextFrame(input, d.exo.can, d.thimble.can);
        now_ns += input.ConsumeIntegralInRange<std::int64_t>(0, 100'000'000);

        if constexpr (kExoskeleton) {
            const std::uint64_t rejects = exo_codec.rejects().total();
            const auto message = exo_codec.decode(frame);
            checkExoskeleton(message, d.exo);
            const bool rejected = message.type == protocol::ExoskeletonMessage::Type::kRejected;
            require(exo_codec.rejects().total() == rejects + (rejected ? 1 : 0));
        } else {
            const std::uint64_t rejects = thimble_codec.rejects().total();
            const auto message = thimble_codec.decode(frame);
            using Type = protocol::ThimbleMessage::Type;
            require(thimble_codec.rejects().total() ==
                    rejects + (message.type == Type::kRejected ? 1 : 0));
            if (message.type == Type::kState || message.type == Type::kCommand) {
                const auto& angles = message.type == Type::kState
                                         ? message.state.servo_angle_rad
                                         : message.command.servo_target_rad;
                for (double angle : angles) {
                    require(within(angle, servos.min_rad - 0.1, servos.max_rad + 0.1));
                }
            }
        }
        // The drivers see the same frames, error frames included (through the bus state).
        if (frame.isError()) {
            (void)bus.injectReceive(frame);
            can::CanFrame drained;
            (void)bus.read(drained);
        }
        if constexpr (kExoskeleton) {
            exo_driver.handleFrame(frame, now_ns);
            (void)exo_driver.faults(now_ns);
        } else {
            thimble_driver.handleFrame(frame, now_ns);
            (void)thimble_driver.faults(now_ns);
        }
    }
    return 0;
}
