#include "dds_sim_link.hpp"

#include <spdlog/spdlog.h>

#include <fastdds/dds/core/condition/GuardCondition.hpp>
#include <fastdds/dds/core/condition/StatusCondition.hpp>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/core/status/StatusMask.hpp>

#include "haptic/ipc/topics.hpp"
#include "haptic/msgs/conversions.hpp"

namespace haptic::hapticd {

namespace dds = eprosima::fastdds::dds;

// Every member on the DDS side is touched only by the link thread; the RT side only by the
// RT thread; the SeqLocks are the hand-over between them.
struct DdsSimLink::Device {
    SimLinkDevice descriptor;
    ipc::DdsReader<idl::ConstraintSet> constraint_reader;
    ipc::DdsReader<idl::ContactSurface> surface_reader;
    ipc::DdsWriter<idl::DeviceState> state_writer;

    // Link thread scratch (the IDL types allocate; the twins are too large for the stack).
    idl::ConstraintSet idl_constraints;
    idl::ContactSurface idl_surface;
    msgs::ConstraintSet constraints{};
    msgs::ContactSurface surface{};
    msgs::DeviceState state{};
    std::uint64_t state_published_version{0};
    std::chrono::steady_clock::time_point state_published_at{};
    std::uint64_t unconvertible_logged{0};

    daemon::SeqLock<msgs::ConstraintSet> constraint_slot;
    daemon::SeqLock<msgs::ContactSurface> surface_slot;
    daemon::SeqLock<msgs::DeviceState> state_slot;
    std::atomic<std::uint64_t> received{0};

    // RT thread side; the link thread reads the versions taken, so that a message of another
    // schema never displaces one the RT thread has not taken yet.
    std::atomic<std::uint64_t> constraint_taken{0};
    std::atomic<std::uint64_t> surface_taken{0};
    msgs::ConstraintSet rt_constraints{};
    msgs::ContactSurface rt_surface{};
};

DdsSimLink::DdsSimLink(ipc::DdsParticipant& participant, std::vector<SimLinkDevice> devices,
                       std::chrono::nanoseconds state_publish_period)
    : state_publish_period_(state_publish_period),
      stop_condition_(std::make_unique<dds::GuardCondition>()) {
    for (auto& descriptor : devices) {
        auto device = std::make_unique<Device>();
        const std::string& name = descriptor.name;
        if (descriptor.kind == msgs::DeviceKind::kExoskeleton) {
            device->constraint_reader = participant.createReader<idl::ConstraintSetPubSubType>(
                ipc::deviceTopic(ipc::kConstraintSetTopic, name), ipc::TopicKind::kLatestState);
        } else {
            device->surface_reader = participant.createReader<idl::ContactSurfacePubSubType>(
                ipc::deviceTopic(ipc::kContactSurfaceTopic, name), ipc::TopicKind::kLatestState);
        }
        device->state_writer = participant.createWriter<idl::DeviceStatePubSubType>(
            ipc::deviceTopic(ipc::kDeviceStateTopic, name), ipc::TopicKind::kLatestState);
        device->descriptor = std::move(descriptor);
        devices_.push_back(std::move(device));
    }
}

DdsSimLink::~DdsSimLink() {
    stop();
}

void DdsSimLink::start() {
    if (!thread_.joinable()) {
        stop_requested_.store(false);
        thread_ = std::thread([this] { run(); });
    }
}

void DdsSimLink::stop() {
    stop_requested_.store(true);
    stop_condition_->set_trigger_value(true);
    if (thread_.joinable()) {
        thread_.join();
    }
    stop_condition_->set_trigger_value(false);
}

void DdsSimLink::run() {
    dds::WaitSet waitset;
    for (auto& device : devices_) {
        dds::DataReader* reader = device->descriptor.kind == msgs::DeviceKind::kExoskeleton
                                      ? device->constraint_reader.handle()
                                      : device->surface_reader.handle();
        dds::StatusCondition& condition = reader->get_statuscondition();
        condition.set_enabled_statuses(dds::StatusMask::data_available());
        waitset.attach_condition(condition);
    }
    waitset.attach_condition(*stop_condition_);

    const auto seconds = std::chrono::duration_cast<std::chrono::seconds>(state_publish_period_);
    const eprosima::fastrtps::Duration_t timeout(
        static_cast<std::int32_t>(seconds.count()),
        static_cast<std::uint32_t>((state_publish_period_ - seconds).count()));
    dds::ConditionSeq active;
    while (!stop_requested_.load()) {
        // Woken by new sim data or the stop condition; otherwise every publish period so the
        // DeviceState stream keeps flowing while the sim is silent.
        (void)waitset.wait(active, timeout);
        for (auto& device : devices_) {
            drain(*device);
        }
        publishStates(std::chrono::steady_clock::now());
    }
}

void DdsSimLink::drain(Device& device) {
    const std::string& name = device.descriptor.name;
    const auto reject = [&](const std::string& reason) {
        const std::uint64_t count = unconvertible_.fetch_add(1, std::memory_order_relaxed) + 1;
        // The first of each burst is enough to diagnose a mismatched sim build.
        if (device.unconvertible_logged++ % 1000 == 0) {
            spdlog::warn(
                "sim link dds: device '{}': refused a message that fits no twin: {} ({} "
                "so far; one of another schema goes on for hapticd to count)",
                name, reason, count);
        }
    };
    // Each convertible message is stored at once: a later unconvertible one must not leave a
    // half-overwritten twin behind to be stored (one of another schema is stored for its
    // header, which the RT thread refuses before it reads anything else).
    if (device.descriptor.kind == msgs::DeviceKind::kExoskeleton) {
        while (device.constraint_reader.take(device.idl_constraints)) {
            const auto result = msgs::fromIdl(device.idl_constraints, device.constraints);
            if (!result.ok()) {
                reject(result.error);
                // Another release's message goes on all the same, its header alone read: the
                // RT thread refuses it first, as other_schema, and the status counts it. Only
                // into a slot the RT thread has emptied: it never displaces a valid message.
                if (device.constraints.header.schema != msgs::kSchema &&
                    device.constraint_slot.version() ==
                        device.constraint_taken.load(std::memory_order_acquire)) {
                    device.constraint_slot.store(device.constraints);
                }
                continue;
            }
            device.received.fetch_add(1, std::memory_order_relaxed);
            device.constraint_slot.store(device.constraints);
        }
    } else {
        while (device.surface_reader.take(device.idl_surface)) {
            const auto result = msgs::fromIdl(device.idl_surface, device.surface);
            if (!result.ok()) {
                reject(result.error);
                if (device.surface.header.schema != msgs::kSchema &&
                    device.surface_slot.version() ==
                        device.surface_taken.load(std::memory_order_acquire)) {
                    device.surface_slot.store(device.surface);
                }
                continue;
            }
            device.received.fetch_add(1, std::memory_order_relaxed);
            device.surface_slot.store(device.surface);
        }
    }
}

void DdsSimLink::publishStates(std::chrono::steady_clock::time_point now) {
    for (auto& device : devices_) {
        const std::uint64_t version = device->state_slot.version();
        if (version == device->state_published_version ||
            now - device->state_published_at < state_publish_period_) {
            continue;
        }
        if (!device->state_slot.load(device->state)) {
            continue;
        }
        device->state_published_version = version;
        device->state_published_at = now;
        if (device->state_writer.write(msgs::toIdl(device->state))) {
            states_published_.fetch_add(1, std::memory_order_relaxed);
        }
    }
}

const msgs::ConstraintSet* DdsSimLink::takeConstraintSet(std::size_t index) noexcept {
    Device& device = *devices_[index];
    if (device.constraint_slot.version() ==
        device.constraint_taken.load(std::memory_order_relaxed)) {
        return nullptr;
    }
    const std::uint64_t version = device.constraint_slot.tryLoad(device.rt_constraints);
    if (version == 0) {
        return nullptr;
    }
    device.constraint_taken.store(version, std::memory_order_release);
    return &device.rt_constraints;
}

const msgs::ContactSurface* DdsSimLink::takeContactSurface(std::size_t index) noexcept {
    Device& device = *devices_[index];
    if (device.surface_slot.version() == device.surface_taken.load(std::memory_order_relaxed)) {
        return nullptr;
    }
    const std::uint64_t version = device.surface_slot.tryLoad(device.rt_surface);
    if (version == 0) {
        return nullptr;
    }
    device.surface_taken.store(version, std::memory_order_release);
    return &device.rt_surface;
}

void DdsSimLink::storeDeviceState(std::size_t index, const msgs::DeviceState& state) noexcept {
    devices_[index]->state_slot.store(state);
}

std::uint64_t DdsSimLink::received(std::size_t index) const noexcept {
    return devices_[index]->received.load(std::memory_order_relaxed);
}

}  // namespace haptic::hapticd
