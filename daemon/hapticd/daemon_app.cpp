#include "daemon_app.hpp"

#include <pthread.h>
#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include "HapticStatusPubSubTypes.h"
#include "HapticTelemetryPubSubTypes.h"
#include "command_relay.hpp"
#include "dds_sim_link.hpp"
#include "device_state_publisher.hpp"
#include "haptic/common/clock.hpp"
#include "haptic/config/daemon.hpp"
#include "haptic/control/control_server.hpp"
#include "haptic/daemon/command_channel.hpp"
#include "haptic/daemon/daemon_core.hpp"
#include "haptic/daemon/seqlock.hpp"
#include "haptic/daemon/spsc_queue.hpp"
#include "haptic/daemon/status_journal.hpp"
#include "haptic/daemon/watchdog_gate.hpp"
#include "haptic/ipc/dds_participant.hpp"
#include "haptic/ipc/iceoryx_channels.hpp"
#include "haptic/ipc/iceoryx_runtime.hpp"
#include "haptic/ipc/topics.hpp"
#include "haptic/msgs/conversions.hpp"
#include "haptic/process/shutdown.hpp"
#include "haptic/runtime/core_settings.hpp"
#include "haptic/runtime/device_runtime.hpp"
#include "iceoryx_posh/popo/publisher.hpp"
#include "iceoryx_posh/popo/subscriber.hpp"

namespace haptic::hapticd {
namespace {

using common::monotonicNowNs;

// One sample per device per published tick (loop.telemetry_decimation), drained every ~10 ms
// by the non-RT thread. Telemetry is
// best effort (the RT thread never waits for it): 2048 slots hold about one second of two
// devices, so only a non-RT thread stalled that long loses samples, and they are counted.
using TelemetryQueue = daemon::SpscQueue<msgs::TelemetrySample, 2048>;

// The iceoryx endpoints of one device. Exactly one of the two subscribers exists, matching
// the device kind; none exist when the sim link is DDS (see dds_sim_link.hpp). The RT
// thread takes from the subscribers; the publisher belongs to the DeviceStatePublisher thread.
struct DeviceEndpoints {
    std::unique_ptr<iox::popo::Subscriber<msgs::ConstraintSet>> constraint_sets;
    std::unique_ptr<iox::popo::Subscriber<msgs::ContactSurface>> contact_surfaces;
    std::unique_ptr<iox::popo::Publisher<msgs::DeviceState>> device_state;
};

// Everything the RT thread touches, built before it starts.
class RealtimeLoop {
  public:
    RealtimeLoop(const config::DaemonConfig& cfg, std::vector<DeviceEndpoints>& endpoints,
                 DdsSimLink* dds_sim_link, daemon::CommandChannel& commands,
                 TelemetryQueue& telemetry, runtime::DeviceRuntime& devices,
                 std::vector<std::unique_ptr<DeviceStateSnapshot>>& device_states)
        : core_(runtime::coreSettings(cfg, HAPTIC_VERSION), runtime::deviceDescriptors(cfg)),
          endpoints_(endpoints),
          dds_sim_link_(dds_sim_link),
          devices_(devices),
          device_states_(device_states),
          commands_(commands),
          telemetry_(telemetry),
          realtime_{cfg.loop.realtime == config::RealtimeMode::kEnforce
                        ? daemon::RealtimePolicy::kEnforce
                        : daemon::RealtimePolicy::kIgnore,
                    cfg.loop.priority, cfg.loop.cpu_affinity, cfg.loop.cpu_latency_us},
          period_ns_(1'000'000'000LL / cfg.loop.rate_hz),
          stall_limit_ns_(runtime::coreSettings(cfg, HAPTIC_VERSION).stall_limit_ns) {}

    // The thread is named so an operator can find it (`top -H`, `ps -L`, `chrt -p`) and a
    // test can stop it alone.
    void start() {
        thread_ = std::thread([this] { run(); });
        (void)::pthread_setname_np(thread_.native_handle(), kThreadName);
    }
    static constexpr const char* kThreadName = "hapticd-rt";
    // Never leave a joinable thread behind: an exception on the non-RT side must still stop
    // the loop cleanly instead of std::terminate.
    ~RealtimeLoop() { stop(); }
    RealtimeLoop(const RealtimeLoop&) = delete;
    RealtimeLoop& operator=(const RealtimeLoop&) = delete;

    void stop() {
        stop_requested_.store(true);
        if (thread_.joinable()) {
            thread_.join();
        }
    }

    // 0 = starting, 1 = running, -1 = refused to start (see setupReport()).
    [[nodiscard]] int startState() const noexcept { return start_state_.load(); }
    [[nodiscard]] const std::string& setupReport() const noexcept { return setup_report_; }
    [[nodiscard]] std::uint64_t ticks() const noexcept {
        return ticks_.load(std::memory_order_relaxed);
    }
    [[nodiscard]] std::uint64_t telemetryDropped() const noexcept {
        return telemetry_dropped_.load(std::memory_order_relaxed);
    }
    [[nodiscard]] const daemon::SeqLock<msgs::HapticStatus>& status() const noexcept {
        return status_;
    }
    // After stop(): the most recent gap between two command writes that was longer than the
    // stall limit (the devices' command timeout), if it ended within kExitStallWindowNs of the
    // last safe command; else 0. The main thread journals the core's stall fault
    // (kFaultLoopStalled) only from a later status snapshot, which a stall during the stop
    // never gets, and one in the fail-stop itself has no next tick to raise it. A stall the
    // journal did report just before the stop is reported here a second time.
    [[nodiscard]] std::int64_t exitStallNs() const noexcept {
        return exit_stall_ns_.load(std::memory_order_relaxed);
    }
    [[nodiscard]] std::int64_t stallLimitNs() const noexcept { return stall_limit_ns_; }
    static constexpr std::int64_t kExitStallWindowNs = 200'000'000;

  private:
    // Ticks of safe commands written after the loop ends: more than one, so a single frame
    // lost on the bus cannot leave a device holding its force.
    static constexpr int kSafeStopTicks = 5;

    void run() {
        auto setup = daemon::applyRealtimeSettings(realtime_);
        setup_report_ = setup.report;
        cpu_latency_ = std::move(setup.cpu_latency);
        if (!setup.ok) {
            start_state_.store(-1);
            return;
        }
        daemon::PeriodicTimer timer(period_ns_);
        core_.markStarted(monotonicNowNs());
        timer.start();
        start_state_.store(1);

        daemon::TickTiming timing;
        std::int64_t previous_wake = 0;
        // The gaps between command writes, as the devices see them (their timeout counts from
        // the last command heard): the most recent one above the stall limit.
        std::int64_t last_write_ns = 0;
        std::int64_t stall_gap_ns = 0;
        std::int64_t stall_end_ns = 0;
        const auto noteWrite = [&](std::int64_t at_ns) noexcept {
            if (last_write_ns != 0 && stall_limit_ns_ > 0 &&
                at_ns - last_write_ns > stall_limit_ns_) {
                stall_gap_ns = at_ns - last_write_ns;
                stall_end_ns = at_ns;
            }
            last_write_ns = at_ns;
        };
        // SIGTERM/SIGINT end the loop here, on the next tick, not when the main thread next
        // wakes (up to 10 ms later): the devices are safe within two ticks of the signal.
        while (!stop_requested_.load(std::memory_order_relaxed) && !process::shutdownRequested()) {
            timing.wakeup_latency_us = static_cast<double>(timer.waitNext()) * 1e-3;
            const std::int64_t wake = monotonicNowNs();
            timing.period_us = previous_wake == 0
                                   ? static_cast<double>(period_ns_) * 1e-3
                                   : static_cast<double>(wake - previous_wake) * 1e-3;
            previous_wake = wake;

            devices_.read(wake);
            takeSimInputs(wake);
            takeCommands(wake);
            const std::int64_t read_done = monotonicNowNs();
            core_.update(read_done, timing);
            devices_.compute(core_, read_done);
            if (core_.snapshotDue(read_done)) {
                core_.fillStatus(read_done, status_scratch_);
                status_.store(status_scratch_);
            }
            const std::int64_t compute_done = monotonicNowNs();
            devices_.write();
            storeDeviceStates(compute_done);
            const std::int64_t write_done = monotonicNowNs();
            noteWrite(write_done);

            // This tick's split is recorded by the next update(); the statistics trail by
            // one tick, which does not matter for percentiles.
            timing.read_us = static_cast<double>(read_done - wake) * 1e-3;
            timing.compute_us = static_cast<double>(compute_done - read_done) * 1e-3;
            timing.write_us = static_cast<double>(write_done - compute_done) * 1e-3;
            queueTelemetry(ticks_.load(std::memory_order_relaxed), wake, timing);
            ticks_.fetch_add(1, std::memory_order_relaxed);
        }
        // Fail-stop: whatever ended the loop (SIGTERM, --duration, RouDi loss, an exception on
        // the non-RT side unwinding this object), every device gets its safe command on the
        // next kSafeStopTicks ticks before the buses close, so none is left holding the last
        // force. A SIGKILL skips this; only the device's own command timeout covers it.
        for (int i = 0; i < kSafeStopTicks; ++i) {
            (void)timer.waitNext();
            devices_.read(monotonicNowNs());
            devices_.writeSafe();
            noteWrite(monotonicNowNs());
        }
        if (stall_end_ns != 0 && last_write_ns - stall_end_ns <= kExitStallWindowNs) {
            exit_stall_ns_.store(stall_gap_ns, std::memory_order_relaxed);
        }
    }

    void takeSimInputs(std::int64_t now_ns) noexcept {
        if (dds_sim_link_ != nullptr) {
            takeDdsSimInputs(now_ns);
            return;
        }
        for (std::size_t i = 0; i < endpoints_.size(); ++i) {
            auto& endpoint = endpoints_[i];
            if (endpoint.constraint_sets) {
                while (endpoint.constraint_sets->take().and_then([&](const auto& sample) {
                    (void)core_.offerConstraintSet(i, *sample, now_ns);
                })) {
                }
            }
            if (endpoint.contact_surfaces) {
                while (endpoint.contact_surfaces->take().and_then([&](const auto& sample) {
                    (void)core_.offerContactSurface(i, *sample, now_ns);
                })) {
                }
            }
        }
    }

    void takeDdsSimInputs(std::int64_t now_ns) noexcept {
        for (std::size_t i = 0; i < dds_sim_link_->deviceCount(); ++i) {
            if (const auto* message = dds_sim_link_->takeConstraintSet(i)) {
                (void)core_.offerConstraintSet(i, *message, now_ns);
            }
            if (const auto* message = dds_sim_link_->takeContactSurface(i)) {
                (void)core_.offerContactSurface(i, *message, now_ns);
            }
        }
    }

    void takeCommands(std::int64_t now_ns) noexcept {
        while (commands_.takeCommand(command_scratch_)) {
            core_.applyCommand(command_scratch_, now_ns, reply_scratch_);
            // The command took effect either way; a reply lost to a stalled non-RT side
            // is visible in haptic/status.
            (void)commands_.postReply(reply_scratch_);
        }
    }

    void queueTelemetry(std::uint64_t tick, std::int64_t now_ns,
                        const daemon::TickTiming& timing) noexcept {
        if (!core_.telemetryDue(tick)) {
            return;
        }
        for (std::size_t i = 0; i < endpoints_.size(); ++i) {
            core_.fillTelemetry(i, tick, now_ns, timing, telemetry_scratch_);
            if (!telemetry_.push(telemetry_scratch_)) {
                telemetry_dropped_.fetch_add(1, std::memory_order_relaxed);
            }
        }
    }

    // A non-RT thread puts these on the sim link: the DeviceStatePublisher on iceoryx, the
    // DdsSimLink's writer on DDS.
    void storeDeviceStates(std::int64_t now_ns) noexcept {
        for (std::size_t i = 0; i < device_states_.size(); ++i) {
            core_.fillDeviceState(i, now_ns, device_state_scratch_);
            if (dds_sim_link_ != nullptr) {
                dds_sim_link_->storeDeviceState(i, device_state_scratch_);
            } else {
                device_states_[i]->store(device_state_scratch_);
            }
        }
    }

    daemon::DaemonCore core_;
    std::vector<DeviceEndpoints>& endpoints_;
    DdsSimLink* dds_sim_link_;  // null when the sim link is iceoryx
    runtime::DeviceRuntime& devices_;
    std::vector<std::unique_ptr<DeviceStateSnapshot>>& device_states_;
    msgs::DeviceState device_state_scratch_{};
    daemon::CommandChannel& commands_;
    msgs::HapticCommand command_scratch_{};
    msgs::HapticCommandReply reply_scratch_{};
    TelemetryQueue& telemetry_;
    msgs::TelemetrySample telemetry_scratch_{};
    daemon::RealtimeSettings realtime_;
    process::CpuLatencyRequest cpu_latency_;  // held while the loop object lives
    std::int64_t period_ns_;
    std::int64_t stall_limit_ns_;
    std::atomic<std::int64_t> exit_stall_ns_{0};
    msgs::HapticStatus status_scratch_{};
    daemon::SeqLock<msgs::HapticStatus> status_;
    std::atomic<bool> stop_requested_{false};
    std::atomic<int> start_state_{0};
    std::atomic<std::uint64_t> ticks_{0};
    std::atomic<std::uint64_t> telemetry_dropped_{0};
    std::string setup_report_;
    std::thread thread_;
};

// Logs what changed since the last snapshot (status_journal.hpp).
void journal(const msgs::HapticStatus* before, const msgs::HapticStatus& after) {
    for (const daemon::JournalLine& line : daemon::statusChanges(before, after)) {
        switch (line.level) {
            case daemon::JournalLine::Level::kError:
                spdlog::error("{}", line.text);
                break;
            case daemon::JournalLine::Level::kWarning:
                spdlog::warn("{}", line.text);
                break;
            case daemon::JournalLine::Level::kInfo:
                spdlog::info("{}", line.text);
                break;
        }
    }
}

}  // namespace

int runDaemon(const DaemonOptions& options) {
    const auto& cfg = options.config;
    // Over DDS the daemon needs no RouDi: the sim link is its only iceoryx user.
    const bool dds_sim = cfg.sim_link.transport == config::SimTransport::kDds;
    daemon::CommandChannel commands;
    // Operators on this host: the local socket, whose peer credentials say who may do what.
    // First of all, so that a second hapticd on this domain stops here, before it joins
    // RouDi or opens a device.
    control::ControlServer control_server(config::controlSocketPath(cfg),
                                          cfg.control.operator_group, commands);
    const std::optional<ipc::RoudiWatch> roudi_watch =
        ipc::joinRoudi(!dds_sim, "hapticd", cfg.iceoryx);
    spdlog::info("local control on {} (operators: root and group '{}'{})",
                 control_server.path().string(), cfg.control.operator_group,
                 control_server.groupKnown() ? "" : ", which does not exist on this host");
    std::vector<DeviceEndpoints> endpoints(cfg.devices.size());
    for (std::size_t i = 0; i < cfg.devices.size(); ++i) {
        const auto& device = cfg.devices[i];
        spdlog::info("device '{}' ({}) from {}", device.name,
                     device.isExoskeleton() ? "exoskeleton" : "thimble", device.source.string());
        if (dds_sim) {
            continue;
        }
        if (device.isExoskeleton()) {
            endpoints[i].constraint_sets =
                std::make_unique<iox::popo::Subscriber<msgs::ConstraintSet>>(
                    ipc::deviceService(device.name, ipc::kConstraintSetEvent),
                    ipc::latestValueSubscriberOptions());
        } else {
            endpoints[i].contact_surfaces =
                std::make_unique<iox::popo::Subscriber<msgs::ContactSurface>>(
                    ipc::deviceService(device.name, ipc::kContactSurfaceEvent),
                    ipc::latestValueSubscriberOptions());
        }
        iox::popo::PublisherOptions publisher_options;
        publisher_options.historyCapacity = 1;
        endpoints[i].device_state = std::make_unique<iox::popo::Publisher<msgs::DeviceState>>(
            ipc::deviceService(device.name, ipc::kDeviceStateEvent), publisher_options);
    }

    ipc::DdsParticipant participant(ipc::ddsSettings(cfg.dds), "hapticd");
    auto status_writer = participant.createWriter<idl::HapticStatusPubSubType>(
        ipc::kStatusTopic, ipc::TopicKind::kLatestState);

    CommandRelay command_relay(participant, commands, control_server);
    auto telemetry_writer = participant.createWriter<idl::HapticTelemetryPubSubType>(
        ipc::kTelemetryTopic, ipc::TopicKind::kStream);
    auto telemetry = std::make_unique<TelemetryQueue>();
    std::uint64_t telemetry_seq = 0;
    msgs::HapticTelemetry batch;
    const auto publishTelemetry = [&] {
        while (true) {
            batch = msgs::HapticTelemetry{};
            msgs::TelemetrySample sample;
            while (batch.samples.size() < msgs::kMaxTelemetrySamples && telemetry->pop(sample)) {
                batch.samples.push_back(sample);
            }
            if (batch.samples.size() == 0) {
                return;
            }
            batch.header.seq = ++telemetry_seq;
            batch.header.stamp_ns = monotonicNowNs();
            batch.header.source_id.assign("hapticd");
            telemetry_writer.write(msgs::toIdl(batch));
        }
    };
    // CAN: one bus per distinct interface / UDP port block, one driver and renderer per device.
    const runtime::OpenedBuses buses = runtime::openBuses(cfg.devices, cfg.estop_relay);
    runtime::ChannelSettings channel_settings;
    channel_settings.period_s = 1.0 / cfg.loop.rate_hz;
    runtime::DeviceRuntime devices(cfg.devices, buses.per_device, channel_settings);
    for (std::size_t i = 0; i < cfg.devices.size(); ++i) {
        spdlog::info("device '{}' on {}", cfg.devices[i].name, buses.descriptions[i]);
    }
    if (const auto& relay = cfg.estop_relay; relay.enabled) {
        const auto bus_device = static_cast<std::size_t>(
            std::find_if(cfg.devices.begin(), cfg.devices.end(),
                         [&](const auto& device) { return device.name == relay.bus_device; }) -
            cfg.devices.begin());
        devices.attachEstopRelay(bus_device, relay.status_id,
                                 static_cast<std::int64_t>(relay.timeout_ms) * 1'000'000);
        spdlog::info("hardware E-stop: relay status 0x{:03x} on the bus of '{}', {} ms timeout",
                     relay.status_id, relay.bus_device, relay.timeout_ms);
    } else {
        spdlog::warn(
            "no hardware E-stop input (daemon.yaml estop_relay.enabled: false): only `hapticctl "
            "estop` and a hard-wired power cut stop the devices");
    }
    std::vector<std::unique_ptr<DeviceStateSnapshot>> device_states;
    for (std::size_t i = 0; i < endpoints.size(); ++i) {
        device_states.push_back(std::make_unique<DeviceStateSnapshot>());
    }
    // The sim link has a participant of its own, apart from status, telemetry and commands
    // (#19): its discovery, history and resources are not shared with the control topics.
    std::unique_ptr<ipc::DdsParticipant> link_participant;
    std::unique_ptr<DdsSimLink> dds_sim_link;
    std::unique_ptr<DeviceStatePublisher> device_state_publisher;
    if (dds_sim) {
        std::vector<SimLinkDevice> link_devices;
        for (const auto& device : cfg.devices) {
            link_devices.push_back({device.name, device.isExoskeleton()
                                                     ? msgs::DeviceKind::kExoskeleton
                                                     : msgs::DeviceKind::kThimble});
        }
        link_participant =
            std::make_unique<ipc::DdsParticipant>(ipc::ddsSettings(cfg.dds), "hapticd-sim-link");
        dds_sim_link = std::make_unique<DdsSimLink>(*link_participant, std::move(link_devices));
        dds_sim_link->start();
        spdlog::info("sim link over DDS on domain {} (no RouDi needed)", cfg.dds.domain_id);
    } else {
        std::vector<iox::popo::Publisher<msgs::DeviceState>*> device_state_publishers;
        for (auto& endpoint : endpoints) {
            device_state_publishers.push_back(endpoint.device_state.get());
        }
        device_state_publisher = std::make_unique<DeviceStatePublisher>(
            std::move(device_state_publishers), device_states, std::chrono::milliseconds(1));
    }

    RealtimeLoop loop(cfg, endpoints, dds_sim_link.get(), commands, *telemetry, devices,
                      device_states);
    loop.start();
    while (loop.startState() == 0) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (loop.startState() < 0) {
        spdlog::error("{}", loop.setupReport());
        loop.stop();
        return EXIT_FAILURE;
    }
    spdlog::info("{}", loop.setupReport());
    spdlog::info("1 kHz loop running at {} Hz with {} device(s); status on DDS '{}' domain {}",
                 cfg.loop.rate_hz, cfg.devices.size(), ipc::kStatusTopic, cfg.dds.domain_id);
    sd_notify(0, "READY=1\nSTATUS=rendering loop running");

    // Watchdog pings prove the RT loop is ticking, not merely that this thread is alive.
    std::uint64_t watchdog_usec = 0;
    const bool watchdog = sd_watchdog_enabled(0, &watchdog_usec) > 0;
    const auto status_period = std::chrono::nanoseconds(1'000'000'000LL / cfg.loop.status_rate_hz);
    const auto started = std::chrono::steady_clock::now();
    std::uint64_t last_version = 0;
    daemon::WatchdogGate watchdog_gate(static_cast<std::int64_t>(watchdog_usec) * 1000 / 2,
                                       cfg.loop.rate_hz);
    auto last_roudi_check = started;
    std::uint64_t dropped_reported = 0;
    int exit_code = EXIT_SUCCESS;
    msgs::HapticStatus status;
    // The last snapshot written to the journal: faults and state changes are logged from here,
    // since the RT thread that raises them never logs.
    std::optional<msgs::HapticStatus> journaled;
    // Wake often enough for every job: commands within ~10 ms, each status snapshot, and,
    // under systemd, the watchdog at least twice per WatchdogSec.
    auto wake_period = std::min(std::chrono::duration_cast<std::chrono::nanoseconds>(status_period),
                                std::chrono::nanoseconds(10'000'000));
    if (watchdog) {
        wake_period = std::min(wake_period, std::chrono::nanoseconds(watchdog_usec * 1000 / 4));
    }
    // The control socket's requests wake this thread at once (an E-stop reaches the RT thread
    // within a tick or two); while a forwarded command awaits its reply, every millisecond.
    // Each wake also relays haptic/command and the RT thread's replies.
    const auto serveUntil = [&](std::chrono::steady_clock::time_point until) {
        for (auto now = std::chrono::steady_clock::now();
             now < until && !process::shutdownRequested(); now = std::chrono::steady_clock::now()) {
            const auto slice =
                control_server.awaitingReplies()
                    ? std::chrono::milliseconds(1)
                    : std::min(std::chrono::duration_cast<std::chrono::milliseconds>(until - now) +
                                   std::chrono::milliseconds(1),
                               std::chrono::milliseconds(20));
            control_server.serve(slice);
            command_relay.poll();
        }
        return !process::shutdownRequested();
    };
    while (serveUntil(std::chrono::steady_clock::now() + wake_period)) {
        publishTelemetry();
        // The RT thread produces a snapshot per status period; publish each one once.
        const auto& snapshots = loop.status();
        if (snapshots.version() != last_version && snapshots.load(status)) {
            last_version = snapshots.version();
            const idl::HapticStatus wire = msgs::toIdl(status);
            status_writer.write(wire);
            control_server.publish(wire);
            journal(journaled ? &*journaled : nullptr, status);
            journaled = status;
        }
        const auto now = std::chrono::steady_clock::now();
        if (now - last_roudi_check >= std::chrono::milliseconds(200)) {
            last_roudi_check = now;
            // A recording with holes must not be a surprise found at exit: say so as it
            // happens (the RT thread drops rather than waits when the queue is full).
            if (const std::uint64_t dropped = loop.telemetryDropped(); dropped > dropped_reported) {
                spdlog::warn("{} telemetry samples dropped (queue full; {} in all)",
                             dropped - dropped_reported, dropped);
                dropped_reported = dropped;
            }
            if (const auto lost = roudi_watch ? roudi_watch->check() : std::nullopt) {
                // The loop stops below with its fail-stop (every device's safe command). A
                // fresh hapticd can register with the new RouDi, this one cannot.
                spdlog::error("{}; stopping so that hapticd restarts with the new RouDi", *lost);
                exit_code = ipc::kRoudiLostExitCode;
                break;
            }
        }
        if (watchdog && watchdog_gate.pingDue(monotonicNowNs(), loop.ticks())) {
            sd_notify(0, "WATCHDOG=1");
        }
        if (options.duration_s > 0.0 &&
            now - started >= std::chrono::duration<double>(options.duration_s)) {
            break;
        }
    }
    sd_notify(0, "STOPPING=1");
    loop.stop();
    spdlog::info("stopped after {} ticks ({} telemetry samples dropped)", loop.ticks(),
                 loop.telemetryDropped());
    if (const std::int64_t stall_ns = loop.exitStallNs(); stall_ns > 0) {
        spdlog::error(
            "fail-stop: loop stalled {:.1f} ms between two commands within its last {} ms "
            "(limit {:.1f} ms); any device listening went safe by its own command timeout",
            static_cast<double>(stall_ns) * 1e-6, RealtimeLoop::kExitStallWindowNs / 1'000'000,
            static_cast<double>(loop.stallLimitNs()) * 1e-6);
    }
    if (dds_sim_link) {
        dds_sim_link->stop();
        for (std::size_t i = 0; i < cfg.devices.size(); ++i) {
            spdlog::info("sim link dds: device '{}': received {} messages", cfg.devices[i].name,
                         dds_sim_link->received(i));
        }
        spdlog::info(
            "sim link dds: {} messages fitting no twin refused, {} device states published",
            dds_sim_link->unconvertible(), dds_sim_link->statesPublished());
    }
    return exit_code;
}

}  // namespace haptic::hapticd
