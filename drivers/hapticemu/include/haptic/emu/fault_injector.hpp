#pragma once

// Faults the emulator applies to what it sends, switched at run time by text commands
// (hapticemu reads them from stdin, one per line):
//   drop N          drop the next N outgoing frames
//   drop-every N    drop every Nth outgoing frame from now on (0: off)
//   delay MS        hold every outgoing frame for MS milliseconds (0: off)
//   corrupt N       flip one payload bit in each of the next N frames (breaks the CRC)
//   heartbeat stop | heartbeat start
//   busoff          report bus-off (an error frame where the bus can carry one) and go silent
//   recover         report the controller restart and transmit again
//   fault CODE      report device fault CODE (1-6) as active; `fault 0` clears it
//   reboot          the device restarts: uptime from 0, disabled, no command seen yet
//   stuck-enable on|off  the exoskeleton's firmware ignores a disable once enabled (a stuck
//                   drive enable: it keeps following the force setpoint)
//   force-percent P the exoskeleton's actuator produces (and measures) P % of its setpoint,
//                   0-200 (a weak or miscalibrated drive); 100 is healthy
//   servo-stuck N   the thimble's servo N (1-3) holds its angle whatever its target; 0: none
//   clear           all of the above off
// Fixed-size delay queue: no allocation while running.

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

#include "haptic/can/bus.hpp"

namespace haptic::emu {

class FaultInjector {
  public:
    static constexpr std::size_t kDelayCapacity = 1024;

    // Sends `frame` through the faults. Returns false when the frame was dropped.
    bool send(can::CanBus& bus, const can::CanFrame& frame, std::int64_t now_ns) noexcept;
    // Releases delayed frames that are due.
    void flush(can::CanBus& bus, std::int64_t now_ns) noexcept;

    // Applies one text command. Returns false with `error` set for a bad command.
    bool command(std::string_view line, std::string& error);

    [[nodiscard]] bool heartbeatStopped() const noexcept { return heartbeat_stopped_; }
    // `state stop`: the device goes on with its heartbeat but sends no state frames (a stuck
    // sensor board, a firmware task that hung).
    [[nodiscard]] bool stateStopped() const noexcept { return state_stopped_; }
    [[nodiscard]] bool busOff() const noexcept { return bus_off_; }
    [[nodiscard]] std::uint8_t deviceFault() const noexcept { return device_fault_; }
    // Set when a fault frame must go out (fault raised or cleared); the emulator resets it.
    bool takeFaultChange() noexcept;
    // Set by `reboot`; the emulator restarts its device and resets it.
    bool takeReboot() noexcept;
    [[nodiscard]] bool stuckEnable() const noexcept { return stuck_enable_; }
    [[nodiscard]] double forceFraction() const noexcept { return force_percent_ * 0.01; }
    // The thimble servo (1-3) that holds its angle, 0 when none.
    [[nodiscard]] std::uint8_t stuckServo() const noexcept { return stuck_servo_; }
    // Added to the command counter the exoskeleton echoes: the echo of a device that obeys
    // another host's commands, not the ones it is sent here (0: the true echo).
    [[nodiscard]] std::uint8_t echoOffset() const noexcept { return echo_offset_; }
    [[nodiscard]] std::uint64_t droppedFrames() const noexcept { return dropped_; }
    [[nodiscard]] std::uint64_t corruptedFrames() const noexcept { return corrupted_; }

  private:
    struct Delayed {
        can::CanFrame frame;
        std::int64_t due_ns;
    };
    void transmit(can::CanBus& bus, const can::CanFrame& frame) noexcept;
    void sendPendingReports(can::CanBus& bus) noexcept;

    std::uint32_t drop_next_{0};
    std::uint32_t drop_every_{0};
    std::uint64_t sent_count_{0};
    std::int64_t delay_ns_{0};
    std::uint32_t corrupt_next_{0};
    bool heartbeat_stopped_{false};
    bool state_stopped_{false};
    bool bus_off_{false};
    bool pending_bus_report_{false};
    bool pending_restart_report_{false};
    std::uint8_t device_fault_{0};
    bool fault_changed_{false};
    bool reboot_{false};
    bool stuck_enable_{false};
    std::uint8_t stuck_servo_{0};
    std::uint8_t echo_offset_{0};
    std::uint32_t force_percent_{100};
    std::array<Delayed, kDelayCapacity> delayed_{};
    std::size_t delayed_head_{0};
    std::size_t delayed_size_{0};
    std::uint64_t dropped_{0};
    std::uint64_t corrupted_{0};
};

}  // namespace haptic::emu
