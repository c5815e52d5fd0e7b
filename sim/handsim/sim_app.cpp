#include "sim_app.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include "SimStatusPubSubTypes.h"
#include "haptic/ipc/dds_participant.hpp"
#include "haptic/ipc/iceoryx_runtime.hpp"
#include "haptic/ipc/topics.hpp"
#include "haptic/msgs/conversions.hpp"
#include "haptic/process/shutdown.hpp"
#include "haptic/sim/placeholder_fingertip_plane.hpp"
#include "iceoryx_posh/popo/publisher.hpp"
#include "iceoryx_posh/popo/subscriber.hpp"
#include "sim_link_dds.hpp"

namespace haptic::handsim {
namespace {

iox::capro::ServiceDescription serviceFor(const std::string& device, std::string_view event) {
    const std::string service(ipc::kIceoryxService);
    const std::string event_name(event);
    return {iox::capro::IdString_t(iox::cxx::TruncateToCapacity, service.c_str()),
            iox::capro::IdString_t(iox::cxx::TruncateToCapacity, device.c_str()),
            iox::capro::IdString_t(iox::cxx::TruncateToCapacity, event_name.c_str())};
}

std::int64_t monotonicNs() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

struct DeviceLink {
    const config::DeviceConfig* device{nullptr};
    std::unique_ptr<iox::popo::Publisher<msgs::ConstraintSet>> constraint_sets;
    std::unique_ptr<iox::popo::Publisher<msgs::ContactSurface>> contact_surfaces;
    std::unique_ptr<iox::popo::Subscriber<msgs::DeviceState>> device_states;
    std::uint64_t published{0};
    std::uint64_t states_received{0};
    std::uint64_t seq{0};
};

sim::PlaceholderFingerParameters placeholderParameters(const config::SimConfig& cfg) {
    sim::PlaceholderFingerParameters parameters;
    for (const auto& device : cfg.devices) {
        if (device.isExoskeleton()) {
            parameters.phalanx_lengths_m = device.exoskeleton().finger.phalanx_lengths_m;
        }
    }
    return parameters;
}

// Step-time percentiles over the last status window, from stored samples (the sim is not on
// the hard RT path, so a small vector is fine here).
msgs::Percentiles percentiles(std::vector<double>& samples_us) {
    if (samples_us.empty()) {
        return {};
    }
    std::sort(samples_us.begin(), samples_us.end());
    auto at = [&](double q) {
        return samples_us[std::min(
            samples_us.size() - 1,
            static_cast<std::size_t>(q * static_cast<double>(samples_us.size())))];
    };
    return {at(0.5), at(0.99), samples_us.back()};
}

}  // namespace

int runSim(const SimOptions& options) {
    const auto& cfg = options.config;
    if (!cfg.scene.placeholder_contact) {
        spdlog::error(
            "{}: scene '{}' has no placeholder_contact block; this version simulates only "
            "the placeholder rigid fingertip against a plane",
            cfg.scene.source.string(), cfg.scene.name);
        return EXIT_FAILURE;
    }
    // Over DDS the sim needs no RouDi (and may run on another host).
    const bool dds_sim = cfg.sim_link.transport == config::SimTransport::kDds;
    std::optional<ipc::RoudiWatch> roudi_watch;
    if (!dds_sim) {
        ipc::initIceoryxRuntime("handsim");
        roudi_watch.emplace();
    }
    std::vector<DeviceLink> links(cfg.devices.size());
    for (std::size_t i = 0; i < cfg.devices.size(); ++i) {
        const auto& device = cfg.devices[i];
        links[i].device = &device;
        if (dds_sim) {
            continue;
        }
        if (device.isExoskeleton()) {
            links[i].constraint_sets = std::make_unique<iox::popo::Publisher<msgs::ConstraintSet>>(
                serviceFor(device.name, ipc::kConstraintSetEvent));
        } else {
            links[i].contact_surfaces =
                std::make_unique<iox::popo::Publisher<msgs::ContactSurface>>(
                    serviceFor(device.name, ipc::kContactSurfaceEvent));
        }
        iox::popo::SubscriberOptions subscriber_options;
        subscriber_options.queueCapacity = 1;
        links[i].device_states = std::make_unique<iox::popo::Subscriber<msgs::DeviceState>>(
            serviceFor(device.name, ipc::kDeviceStateEvent), subscriber_options);
    }

    ipc::DdsParticipant participant(
        ipc::DdsSettings{static_cast<std::uint32_t>(cfg.dds.domain_id),
                         cfg.dds.profiles_file.string(), cfg.dds.participant_profile},
        "handsim");
    auto status_writer = participant.createWriter<idl::SimStatusPubSubType>(
        ipc::kSimStatusTopic, ipc::TopicKind::kLatestState);
    std::unique_ptr<SimLinkDds> dds_link;
    if (dds_sim) {
        dds_link = std::make_unique<SimLinkDds>(participant, cfg.devices);
        spdlog::info("sim link over DDS on domain {} (no RouDi needed)", cfg.dds.domain_id);
    }
    msgs::ConstraintSet dds_constraints;
    msgs::ContactSurface dds_surface;
    msgs::DeviceState dds_state;

    sim::PlaceholderFingertipPlane model(placeholderParameters(cfg));
    spdlog::warn(
        "scene '{}': running the PLACEHOLDER rigid fingertip against the plane z = {:.3f} m "
        "(no soft hand yet)",
        cfg.scene.name, cfg.scene.placeholder_contact->plane_height_m);
    spdlog::info("stepping at {} Hz for {} device(s)", cfg.scene.rate_hz, cfg.devices.size());

    const auto period = std::chrono::nanoseconds(1'000'000'000LL / cfg.scene.rate_hz);
    const auto started = std::chrono::steady_clock::now();
    auto next = started;
    auto last_status = started;
    std::uint64_t steps = 0;
    std::uint64_t status_seq = 0;
    std::vector<double> step_times_us;
    step_times_us.reserve(static_cast<std::size_t>(cfg.scene.rate_hz) + 1);

    while (!process::shutdownRequested()) {
        next += period;
        std::this_thread::sleep_until(next);
        const auto step_start = std::chrono::steady_clock::now();
        const double t_s = std::chrono::duration<double>(step_start - started).count();
        model.setTime(t_s);
        const std::int64_t stamp = monotonicNs();

        for (std::size_t i = 0; i < links.size(); ++i) {
            auto& link = links[i];
            const std::string& name = link.device->name;
            if (dds_link) {
                if (link.device->isExoskeleton()) {
                    dds_constraints = msgs::ConstraintSet{};
                    model.fillConstraintSet(dds_constraints);
                    dds_constraints.header = {++link.seq, stamp, {}};
                    dds_constraints.header.source_id.assign(name);
                    link.published += dds_link->publish(i, dds_constraints) ? 1 : 0;
                } else {
                    dds_surface = msgs::ContactSurface{};
                    model.fillContactSurface(dds_surface);
                    dds_surface.header = {++link.seq, stamp, {}};
                    dds_surface.header.source_id.assign(name);
                    link.published += dds_link->publish(i, dds_surface) ? 1 : 0;
                }
                link.states_received += dds_link->takeDeviceStates(i, dds_state);
                continue;
            }
            if (link.constraint_sets) {
                link.constraint_sets->loan().and_then([&](auto& sample) {
                    *sample = msgs::ConstraintSet{};
                    model.fillConstraintSet(*sample);
                    sample->header = {++link.seq, stamp, {}};
                    sample->header.source_id.assign(name);
                    sample.publish();
                    ++link.published;
                });
            } else {
                link.contact_surfaces->loan().and_then([&](auto& sample) {
                    *sample = msgs::ContactSurface{};
                    model.fillContactSurface(*sample);
                    sample->header = {++link.seq, stamp, {}};
                    sample->header.source_id.assign(name);
                    sample.publish();
                    ++link.published;
                });
            }
            while (
                link.device_states->take().and_then([&](const auto&) { ++link.states_received; })) {
            }
        }
        ++steps;
        step_times_us.push_back(
            std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - step_start)
                .count());

        const auto now = std::chrono::steady_clock::now();
        if (now - last_status >= std::chrono::milliseconds(500)) {
            msgs::SimStatus status;
            status.header = {++status_seq, stamp, {}};
            status.header.source_id.assign(cfg.scene.name);
            status.rate_hz = static_cast<double>(step_times_us.size()) /
                             std::chrono::duration<double>(now - last_status).count();
            status.steps = steps;
            status.step_time_us = percentiles(step_times_us);
            status.model.assign("placeholder_rigid_fingertip_plane");
            status_writer.write(msgs::toIdl(status));
            step_times_us.clear();
            last_status = now;
            if (const auto lost = roudi_watch ? roudi_watch->check() : std::nullopt) {
                spdlog::error("{}; exiting so that handsim restarts with the new RouDi", *lost);
                return ipc::kRoudiLostExitCode;
            }
        }
        if (options.duration_s > 0.0 &&
            now - started >= std::chrono::duration<double>(options.duration_s)) {
            break;
        }
        if (now > next + 10 * period) {
            next = now;  // fell far behind (debugger, suspend): do not burst to catch up
        }
    }
    for (const auto& link : links) {
        spdlog::info("device '{}': published {} targets, received {} device states",
                     link.device->name, link.published, link.states_received);
    }
    return EXIT_SUCCESS;
}

}  // namespace haptic::handsim
