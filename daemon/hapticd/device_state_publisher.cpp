#include "device_state_publisher.hpp"

namespace haptic::hapticd {

DeviceStatePublisher::DeviceStatePublisher(
    std::vector<iox::popo::Publisher<msgs::DeviceState>*> publishers,
    const std::vector<std::unique_ptr<DeviceStateSnapshot>>& snapshots,
    std::chrono::nanoseconds period)
    : publishers_(std::move(publishers)), snapshots_(snapshots), period_(period) {
    thread_ = std::thread([this] { run(); });
}

DeviceStatePublisher::~DeviceStatePublisher() {
    stop_.store(true);
    if (thread_.joinable()) {
        thread_.join();
    }
}

void DeviceStatePublisher::run() {
    std::vector<std::uint64_t> last_version(publishers_.size(), 0);
    msgs::DeviceState state;
    auto next = std::chrono::steady_clock::now();
    while (!stop_.load(std::memory_order_relaxed)) {
        for (std::size_t i = 0; i < publishers_.size(); ++i) {
            const auto& snapshot = *snapshots_[i];
            const std::uint64_t version = snapshot.version();
            if (version == last_version[i] || !snapshot.load(state)) {
                continue;
            }
            last_version[i] = version;
            publishers_[i]->loan().and_then([&](auto& sample) {
                *sample = state;
                sample.publish();
                published_.fetch_add(1, std::memory_order_relaxed);
            });
        }
        next += period_;
        const auto now = std::chrono::steady_clock::now();
        if (next < now) {
            next = now;  // fell behind (suspended): do not burst to catch up
        }
        std::this_thread::sleep_until(next);
    }
}

}  // namespace haptic::hapticd
