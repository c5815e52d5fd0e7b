#pragma once

// How many refused or malformed commands of one local user reach the journal: a user flooding
// the control socket must not flood the journal (each request is still answered). The first
// `lines_per_window` of a uid's window are logged; the rest are counted and reported in one
// line once the window is over. Main thread only (it allocates per uid seen).

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace haptic::control {

class PerUidLogLimit {
  public:
    using Clock = std::chrono::steady_clock;

    PerUidLogLimit(int lines_per_window, Clock::duration window)
        : lines_per_window_(lines_per_window), window_(window) {}

    // Whether this event of `uid` is to be logged now.
    bool admit(uid_t uid, Clock::time_point now) {
        Window& w = windows_[uid];
        if (w.logged == 0 && w.suppressed == 0) {
            w.start = now;
        }
        if (w.logged < lines_per_window_) {
            ++w.logged;
            return true;
        }
        ++w.suppressed;
        return false;
    }

    // The users whose window ended by `now` with events left unlogged, and how many; their
    // windows start afresh.
    std::vector<std::pair<uid_t, std::uint64_t>> expired(Clock::time_point now) {
        std::vector<std::pair<uid_t, std::uint64_t>> out;
        for (auto it = windows_.begin(); it != windows_.end();) {
            if (now - it->second.start < window_) {
                ++it;
                continue;
            }
            if (it->second.suppressed > 0) {
                out.emplace_back(it->first, it->second.suppressed);
            }
            it = windows_.erase(it);
        }
        return out;
    }

    [[nodiscard]] int linesPerWindow() const noexcept { return lines_per_window_; }
    [[nodiscard]] Clock::duration window() const noexcept { return window_; }

  private:
    struct Window {
        Clock::time_point start{};
        int logged{0};
        std::uint64_t suppressed{0};
    };
    int lines_per_window_;
    Clock::duration window_;
    std::unordered_map<uid_t, Window> windows_;
};

}  // namespace haptic::control
