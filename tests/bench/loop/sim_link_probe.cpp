#include "sim_link_probe.hpp"

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <thread>
#include <vector>

#include "dds_sim_link.hpp"
#include "haptic/common/clock.hpp"
#include "haptic/daemon/periodic_timer.hpp"
#include "haptic/ipc/dds_participant.hpp"
#include "haptic/ipc/iceoryx_channels.hpp"
#include "haptic/ipc/iceoryx_runtime.hpp"
#include "haptic/ipc/topics.hpp"
#include "iceoryx_posh/popo/subscriber.hpp"
#include "iceoryx_posh/popo/wait_set.hpp"
#include "latency_stats.hpp"

namespace haptic::bench {
namespace {

struct IceoryxInputs {
    std::vector<std::unique_ptr<iox::popo::Subscriber<msgs::ConstraintSet>>> constraint_sets;
    std::vector<std::unique_ptr<iox::popo::Subscriber<msgs::ContactSurface>>> contact_surfaces;
};

// Delivery latency without the tick: a second subscriber to the first exoskeleton's
// ConstraintSet, woken by the transport itself (iceoryx WaitSet, DDS wait_for_unread_message).
class DeliveryWatcher {
  public:
    DeliveryWatcher(const config::DaemonConfig& cfg, ipc::DdsParticipant* participant,
                    std::int64_t count_from_ns)
        : count_from_ns_(count_from_ns) {
        latencies_us_.reserve(100'000);
        for (const auto& device : cfg.devices) {
            if (!device.isExoskeleton()) {
                continue;
            }
            if (participant != nullptr) {
                dds_reader_ = participant->createReader<idl::ConstraintSetPubSubType>(
                    ipc::deviceTopic(ipc::kConstraintSetTopic, device.name),
                    ipc::TopicKind::kLatestState);
                thread_ = std::thread([this] { runDds(); });
            } else {
                iox::popo::SubscriberOptions options;
                options.queueCapacity = 16;
                iceoryx_ = std::make_unique<iox::popo::Subscriber<msgs::ConstraintSet>>(
                    ipc::deviceService(device.name, ipc::kConstraintSetEvent), options);
                thread_ = std::thread([this] { runIceoryx(); });
            }
            break;
        }
    }
    ~DeliveryWatcher() { stop(); }
    DeliveryWatcher(const DeliveryWatcher&) = delete;
    DeliveryWatcher& operator=(const DeliveryWatcher&) = delete;

    std::vector<double>& stop() {
        stop_.store(true);
        if (thread_.joinable()) {
            thread_.join();
        }
        return latencies_us_;
    }

  private:
    void record(std::int64_t stamp_ns) {
        const std::int64_t now = common::monotonicNowNs();
        if (now >= count_from_ns_) {
            latencies_us_.push_back(static_cast<double>(now - stamp_ns) * 1e-3);
        }
    }
    void runIceoryx() {
        iox::popo::WaitSet<> waitset;
        if (waitset.attachState(*iceoryx_, iox::popo::SubscriberState::HAS_DATA).has_error()) {
            return;
        }
        while (!stop_.load()) {
            (void)waitset.timedWait(iox::units::Duration::fromMilliseconds(100));
            while (iceoryx_->take().and_then(
                [&](const auto& sample) { record(sample->header.stamp_ns); })) {
            }
        }
    }
    void runDds() {
        idl::ConstraintSet sample;
        while (!stop_.load()) {
            if (dds_reader_.waitAndTake(sample, std::chrono::milliseconds(100))) {
                record(sample.header().stamp_ns());
                while (dds_reader_.take(sample)) {
                    record(sample.header().stamp_ns());
                }
            }
        }
    }

    std::int64_t count_from_ns_;
    std::unique_ptr<iox::popo::Subscriber<msgs::ConstraintSet>> iceoryx_;
    ipc::DdsReader<idl::ConstraintSet> dds_reader_;
    std::vector<double> latencies_us_;
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

}  // namespace

int runSimLinkProbe(const config::DaemonConfig& cfg, ProbeTransport transport, double duration_s) {
    IceoryxInputs iceoryx;
    std::unique_ptr<ipc::DdsParticipant> participant;
    std::unique_ptr<hapticd::DdsSimLink> dds_link;
    if (transport == ProbeTransport::kIceoryx) {
        ipc::initIceoryxRuntime("hapticd_latency_probe");
        for (const auto& device : cfg.devices) {
            if (device.isExoskeleton()) {
                iceoryx.constraint_sets.push_back(
                    std::make_unique<iox::popo::Subscriber<msgs::ConstraintSet>>(
                        ipc::deviceService(device.name, ipc::kConstraintSetEvent),
                        ipc::latestValueSubscriberOptions()));
            } else {
                iceoryx.contact_surfaces.push_back(
                    std::make_unique<iox::popo::Subscriber<msgs::ContactSurface>>(
                        ipc::deviceService(device.name, ipc::kContactSurfaceEvent),
                        ipc::latestValueSubscriberOptions()));
            }
        }
    } else {
        participant = std::make_unique<ipc::DdsParticipant>(ipc::ddsSettings(cfg.dds),
                                                            "hapticd_latency_probe");
        std::vector<hapticd::SimLinkDevice> devices;
        for (const auto& device : cfg.devices) {
            devices.push_back({device.name, device.isExoskeleton() ? msgs::DeviceKind::kExoskeleton
                                                                   : msgs::DeviceKind::kThimble});
        }
        dds_link = std::make_unique<hapticd::DdsSimLink>(*participant, std::move(devices));
        dds_link->start();
    }

    std::vector<double> latencies_us;
    latencies_us.reserve(static_cast<std::size_t>(duration_s * 2000.0) + 16);
    const auto setup = daemon::applyRealtimeSettings(
        {daemon::RealtimePolicy::kIgnore, cfg.loop.priority, cfg.loop.cpu_affinity});
    std::fprintf(stderr, "probe: %s\n", setup.report.c_str());

    const std::int64_t started = common::monotonicNowNs();
    const std::int64_t count_from = started + 500'000'000;
    DeliveryWatcher delivery(cfg, participant.get(), count_from);
    daemon::PeriodicTimer timer(1'000'000'000LL / cfg.loop.rate_hz);
    timer.start();
    const std::int64_t end = started + static_cast<std::int64_t>(duration_s * 1e9);
    for (std::int64_t now = started; now < end;) {
        (void)timer.waitNext();
        now = common::monotonicNowNs();
        const auto record = [&](std::int64_t stamp_ns) {
            if (now >= count_from) {
                latencies_us.push_back(static_cast<double>(now - stamp_ns) * 1e-3);
            }
        };
        if (dds_link) {
            for (std::size_t i = 0; i < dds_link->deviceCount(); ++i) {
                if (const auto* message = dds_link->takeConstraintSet(i)) {
                    record(message->header.stamp_ns);
                }
                if (const auto* message = dds_link->takeContactSurface(i)) {
                    record(message->header.stamp_ns);
                }
            }
            continue;
        }
        for (auto& subscriber : iceoryx.constraint_sets) {
            while (subscriber->take().and_then(
                [&](const auto& sample) { record(sample->header.stamp_ns); })) {
            }
        }
        for (auto& subscriber : iceoryx.contact_surfaces) {
            while (subscriber->take().and_then(
                [&](const auto& sample) { record(sample->header.stamp_ns); })) {
            }
        }
    }
    if (dds_link) {
        dds_link->stop();
    }
    const LatencySummary summary = summarize(latencies_us);
    const LatencySummary delivered = summarize(delivery.stop());
    std::printf("probe %llu %.1f %.1f %.1f %.1f\n", static_cast<unsigned long long>(summary.count),
                summary.p50, summary.p99, summary.p999, summary.max);
    std::printf("delivery %llu %.1f %.1f %.1f %.1f\n",
                static_cast<unsigned long long>(delivered.count), delivered.p50, delivered.p99,
                delivered.p999, delivered.max);
    return summary.count > 0 && delivered.count > 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}

}  // namespace haptic::bench
