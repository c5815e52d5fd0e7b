// libFuzzer target for the UDP bus wire decoder. Any datagram either is refused or decodes
// to a well-formed frame that re-encodes to exactly the same bytes.

#include <cstdint>
#include <cstring>

#include "haptic/can/udp_bus.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    haptic::can::CanFrame frame;
    if (!haptic::can::UdpBus::decode(data, size, frame)) {
        return 0;
    }
    if (!haptic::can::isWellFormed(frame)) {
        __builtin_trap();
    }
    std::uint8_t again[haptic::can::UdpBus::kHeaderSize + haptic::can::kFdMaxLength];
    const std::size_t length = haptic::can::UdpBus::encode(frame, data[7], again, sizeof(again));
    if (length != size || std::memcmp(again, data, size) != 0) {
        __builtin_trap();
    }
    return 0;
}
