#pragma once

// One more party on a device's UDP CAN bus, decoding that device's own frames (state,
// heartbeat, fault, and hapticd's commands) as they arrive: what the process tests judge the
// devices by, rather than hapticd's view of them.

#include <poll.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <vector>

#include "haptic/can/udp_bus.hpp"
#include "haptic/common/clock.hpp"
#include "haptic/config/device.hpp"
#include "haptic/protocol/exoskeleton_protocol.hpp"
#include "haptic/protocol/thimble_protocol.hpp"

namespace haptic::testing {

template <typename Message>
struct Heard {
    std::int64_t at_ns;
    Message message;
};

// One more party on a device's UDP bus, decoding that device's frames as they arrive.
template <typename Codec, typename Message>
class BusListener {
  public:
    BusListener(const config::DeviceConfig& device)
        : bus_(can::UdpBusConfig{device.can.udp_port, device.can.udp_slots, {}}), codec_(device) {}

    std::vector<Heard<Message>> listen(std::chrono::milliseconds duration) {
        std::vector<Heard<Message>> heard;
        const std::int64_t end = common::monotonicNowNs() + duration.count() * 1'000'000;
        while (common::monotonicNowNs() < end) {
            pollfd fd{bus_.pollFd(), POLLIN, 0};
            (void)::poll(&fd, 1, 1);
            can::CanFrame frame;
            while (bus_.read(frame) == can::IoResult::kOk) {
                const Message message = codec_.decode(frame);
                if (message.type != Message::Type::kNotForThisDevice &&
                    message.type != Message::Type::kRejected) {
                    heard.push_back({common::monotonicNowNs(), message});
                }
            }
        }
        return heard;
    }

  private:
    can::UdpBus bus_;
    Codec codec_;
};

using ExoListener = BusListener<protocol::ExoskeletonCodec, protocol::ExoskeletonMessage>;
using ThimbleListener = BusListener<protocol::ThimbleCodec, protocol::ThimbleMessage>;
using ExoType = protocol::ExoskeletonMessage::Type;
using ThimbleType = protocol::ThimbleMessage::Type;

inline bool enabledWithForce(const protocol::ExoskeletonMessage& m, double min_force_n) {
    return m.type == ExoType::kActuatorState && (m.actuator.status & protocol::kExoEnabled) != 0 &&
           std::abs(m.actuator.force_n) >= min_force_n;
}

inline bool limp(const protocol::ExoskeletonMessage& m) {
    return m.type == ExoType::kActuatorState && m.actuator.force_n == 0.0 &&
           (m.actuator.status & protocol::kExoEnabled) == 0;
}

// The exoskeleton raising its own command timeout: it went limp because no command came, not
// because hapticd sent its safe one.
inline bool reportsCommandTimeout(const protocol::ExoskeletonMessage& m) {
    return m.type == ExoType::kFault && m.fault.active &&
           m.fault.code == protocol::DeviceFaultCode::kCommandTimeout;
}

}  // namespace haptic::testing
