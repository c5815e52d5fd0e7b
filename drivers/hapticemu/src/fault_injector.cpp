#include "haptic/emu/fault_injector.hpp"

#include <linux/can/error.h>

#include <charconv>

namespace haptic::emu {
namespace {

bool parseNumber(std::string_view text, std::uint32_t& value) {
    const auto* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(text.data(), end, value);
    return ec == std::errc() && ptr == end;
}

std::string_view trim(std::string_view text) {
    while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) {
        text.remove_prefix(1);
    }
    while (!text.empty() && (text.back() == ' ' || text.back() == '\t' || text.back() == '\r' ||
                             text.back() == '\n')) {
        text.remove_suffix(1);
    }
    return text;
}

}  // namespace

void FaultInjector::transmit(can::CanBus& bus, const can::CanFrame& frame) noexcept {
    (void)bus.write(frame);
}

// Controller reports travel as error frames; buses that cannot carry them (SocketCAN) refuse
// them, and the emulator is then simply silent while bus-off.
void FaultInjector::sendPendingReports(can::CanBus& bus) noexcept {
    if (pending_bus_report_) {
        pending_bus_report_ = false;
        transmit(bus, can::makeErrorFrame(CAN_ERR_BUSOFF));
    }
    if (pending_restart_report_) {
        pending_restart_report_ = false;
        transmit(bus, can::makeErrorFrame(CAN_ERR_RESTARTED | CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE));
    }
}

bool FaultInjector::send(can::CanBus& bus, const can::CanFrame& frame,
                         std::int64_t now_ns) noexcept {
    sendPendingReports(bus);
    ++sent_count_;
    if (bus_off_ || drop_next_ > 0 || (drop_every_ > 0 && sent_count_ % drop_every_ == 0)) {
        if (drop_next_ > 0) {
            --drop_next_;
        }
        ++dropped_;
        return false;
    }
    can::CanFrame out = frame;
    if (corrupt_next_ > 0 && out.length > 0) {
        --corrupt_next_;
        ++corrupted_;
        out.data[out.length - 1] ^= 0x01;
    }
    if (delay_ns_ > 0) {
        if (delayed_size_ == kDelayCapacity) {
            ++dropped_;
            return false;
        }
        delayed_[(delayed_head_ + delayed_size_) % kDelayCapacity] = {out, now_ns + delay_ns_};
        ++delayed_size_;
        return true;
    }
    transmit(bus, out);
    return true;
}

void FaultInjector::flush(can::CanBus& bus, std::int64_t now_ns) noexcept {
    sendPendingReports(bus);
    while (delayed_size_ > 0 && delayed_[delayed_head_].due_ns <= now_ns) {
        transmit(bus, delayed_[delayed_head_].frame);
        delayed_head_ = (delayed_head_ + 1) % kDelayCapacity;
        --delayed_size_;
    }
}

bool FaultInjector::takeReboot() noexcept {
    const bool reboot = reboot_;
    reboot_ = false;
    return reboot;
}

bool FaultInjector::takeFaultChange() noexcept {
    const bool changed = fault_changed_;
    fault_changed_ = false;
    return changed;
}

bool FaultInjector::command(std::string_view line, std::string& error) {
    line = trim(line);
    const std::size_t space = line.find(' ');
    const std::string_view verb = line.substr(0, space);
    const std::string_view argument =
        space == std::string_view::npos ? std::string_view{} : trim(line.substr(space + 1));
    std::uint32_t number = 0;
    const bool has_number = parseNumber(argument, number);
    if (verb == "drop" && has_number) {
        drop_next_ = number;
    } else if (verb == "drop-every" && has_number) {
        drop_every_ = number;
    } else if (verb == "delay" && has_number) {
        delay_ns_ = static_cast<std::int64_t>(number) * 1'000'000;
    } else if (verb == "corrupt" && has_number) {
        corrupt_next_ = number;
    } else if (verb == "heartbeat" && (argument == "stop" || argument == "start")) {
        heartbeat_stopped_ = argument == "stop";
    } else if (verb == "state" && (argument == "stop" || argument == "start")) {
        state_stopped_ = argument == "stop";
    } else if (verb == "busoff" && argument.empty()) {
        bus_off_ = true;
        pending_bus_report_ = true;
    } else if (verb == "recover" && argument.empty()) {
        bus_off_ = false;
        pending_restart_report_ = true;
    } else if (verb == "fault" && has_number && number <= 6) {
        device_fault_ = static_cast<std::uint8_t>(number);
        fault_changed_ = true;
    } else if (verb == "reboot" && argument.empty()) {
        reboot_ = true;
    } else if (verb == "force-percent" && has_number && number <= 200) {
        force_percent_ = number;
    } else if (verb == "stuck-enable" && (argument == "on" || argument == "off")) {
        stuck_enable_ = argument == "on";
    } else if (verb == "servo-stuck" && has_number && number <= 3) {
        stuck_servo_ = static_cast<std::uint8_t>(number);
    } else if (verb == "echo-offset" && has_number && number <= 15) {
        echo_offset_ = static_cast<std::uint8_t>(number);
    } else if (verb == "clear" && argument.empty()) {
        drop_next_ = 0;
        drop_every_ = 0;
        delay_ns_ = 0;
        corrupt_next_ = 0;
        heartbeat_stopped_ = false;
        state_stopped_ = false;
        stuck_enable_ = false;
        stuck_servo_ = 0;
        echo_offset_ = 0;
        force_percent_ = 100;
        if (bus_off_) {
            bus_off_ = false;
            pending_restart_report_ = true;
        }
        if (device_fault_ != 0) {
            device_fault_ = 0;
            fault_changed_ = true;
        }
    } else {
        error = "unknown fault command '" + std::string(line) +
                "' (drop N, drop-every N, delay MS, corrupt N, heartbeat stop|start, state "
                "stop|start, busoff, "
                "recover, fault CODE, reboot, stuck-enable on|off, force-percent P, servo-stuck N, "
                "echo-offset N, "
                "clear)";
        return false;
    }
    return true;
}

}  // namespace haptic::emu
