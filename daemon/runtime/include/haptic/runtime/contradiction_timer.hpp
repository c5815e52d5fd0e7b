#pragma once

#include <algorithm>
#include <cstdint>

namespace haptic::runtime {

// How long a device's feedback has contradicted its command, for the plausibility faults
// (105). A contradiction counts as lasting while it holds on most of the judged frames: each
// contradicting tick adds the time since the previous tick, each plausible one takes it away,
// and the contradiction ends only when that balance falls below zero (at zero a pattern such
// as "contradicting, contradicting, plausible" would end and restart for ever). So a single
// plausible frame (a late echo, one frame of another host's traffic the device did not obey)
// does not restart the clock, as it did: a contradiction on a share p > 1/2 of the ticks
// outlasts a timeout T after about T / (2p - 1), and one on every tick after T exactly.
// Judged per tick on the latest state. Allocation-free and O(1), for the RT loop.
class ContradictionTimer {
  public:
    // One judged tick. Returns the time the contradiction has lasted (since its first frame)
    // once its balance exceeds `timeout_ns`, else 0.
    [[nodiscard]] std::int64_t update(bool contradicts, std::int64_t now_ns,
                                      std::int64_t timeout_ns) noexcept {
        const std::int64_t dt_ns = last_ns_ < 0 ? 0 : std::max<std::int64_t>(now_ns - last_ns_, 0);
        last_ns_ = now_ns;
        if (contradicts) {
            if (since_ns_ < 0) {
                since_ns_ = now_ns;  // the first contradicting frame: the balance starts here
                balance_ns_ = 0;
            } else {
                // Capped just above the timeout: a repaired device's report ends on its first
                // plausible tick, however long (or after whatever stall) it had contradicted.
                balance_ns_ = std::min(balance_ns_ + dt_ns, timeout_ns + 1);
            }
        } else if (since_ns_ >= 0) {
            balance_ns_ -= dt_ns;
            if (balance_ns_ < 0) {
                since_ns_ = -1;
                balance_ns_ = 0;
            }
        }
        return since_ns_ >= 0 && balance_ns_ > timeout_ns ? now_ns - since_ns_ : 0;
    }

    // A tick that cannot be judged (stale link, the device's own fault): nothing carries over.
    void reset() noexcept {
        since_ns_ = -1;
        last_ns_ = -1;
        balance_ns_ = 0;
    }

    [[nodiscard]] bool contradicting() const noexcept { return since_ns_ >= 0; }

  private:
    std::int64_t since_ns_{-1};  // the first frame of the standing contradiction
    std::int64_t last_ns_{-1};   // the previous judged tick
    std::int64_t balance_ns_{0};
};

}  // namespace haptic::runtime
