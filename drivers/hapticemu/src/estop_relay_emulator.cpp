#include "haptic/emu/estop_relay_emulator.hpp"

#include <charconv>

namespace haptic::emu {

void EstopRelayEmulator::tick(can::CanBus& bus, std::int64_t now_ns) noexcept {
    if (next_ns_ < 0) {
        next_ns_ = now_ns;
    }
    if (now_ns < next_ns_) {
        return;
    }
    // A relay keeps its own period: after a stall of this process it sends once, not a burst.
    next_ns_ = now_ns - next_ns_ >= kPeriodNs ? now_ns + kPeriodNs : next_ns_ + kPeriodNs;
    if (silent_) {
        return;
    }
    can::CanFrame frame;
    protocol::encodeEstopStatus(status_id_, button_, counter_, frame);
    counter_ = static_cast<std::uint8_t>((counter_ + 1) % protocol::kCounterModulo);
    if (corrupt_next_ > 0) {
        --corrupt_next_;
        frame.data[2] ^= 0x01;  // pressed <-> released, CRC now wrong
    }
    if (bus.write(frame) == can::IoResult::kOk) {
        ++sent_;
    }
}

bool EstopRelayEmulator::command(std::string_view line, std::string& error) {
    if (line == "press") {
        button_ = protocol::EstopButton::kPressed;
    } else if (line == "release") {
        button_ = protocol::EstopButton::kReleased;
    } else if (line == "silence") {
        silent_ = true;
    } else if (line == "resume") {
        silent_ = false;
    } else if (line.substr(0, 8) == "corrupt ") {
        const std::string_view count = line.substr(8);
        int value = 0;
        const auto [end, ec] = std::from_chars(count.data(), count.data() + count.size(), value);
        if (ec != std::errc{} || end != count.data() + count.size() || value < 0) {
            error = "estop corrupt N: N a count of frames";
            return false;
        }
        corrupt_next_ = value;
    } else {
        error = "estop: press, release, silence, resume or corrupt N";
        return false;
    }
    return true;
}

}  // namespace haptic::emu
