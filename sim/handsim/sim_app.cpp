#include "sim_app.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <memory>
#include <optional>
#include <stdexcept>
#include <thread>
#include <type_traits>
#include <vector>

#include "SimStatusPubSubTypes.h"
#include "haptic/common/clock.hpp"
#include "haptic/common/statistics.hpp"
#include "haptic/ipc/dds_participant.hpp"
#include "haptic/ipc/iceoryx_channels.hpp"
#include "haptic/ipc/iceoryx_runtime.hpp"
#include "haptic/ipc/topics.hpp"
#include "haptic/msgs/conversions.hpp"
#include "haptic/process/cpu_latency.hpp"
#include "haptic/process/shutdown.hpp"
#include "haptic/softhand/scene_simulation.hpp"
#include "iceoryx_posh/popo/publisher.hpp"
#include "iceoryx_posh/popo/subscriber.hpp"
#include "sim_link_dds.hpp"
#include "tracking_source.hpp"

namespace haptic::handsim {
namespace {

struct DeviceLink {
    const config::DeviceConfig* device{nullptr};
    std::unique_ptr<iox::popo::Publisher<msgs::ConstraintSet>> constraint_sets;
    std::unique_ptr<iox::popo::Publisher<msgs::ContactSurface>> contact_surfaces;
    std::unique_ptr<iox::popo::Subscriber<msgs::DeviceState>> device_states;
    std::uint64_t published{0};
    std::uint64_t states_received{0};
    std::uint64_t states_refused{0};  // of another schema: hapticd from another release
    std::uint64_t seq{0};
};

// A DeviceState over iceoryx counts only in this release's layout.
void countState(DeviceLink& link, const msgs::DeviceState& state) {
    if (state.header.schema == msgs::kSchema) {
        ++link.states_received;
    } else {
        ++link.states_refused;
    }
}

// Step-time percentiles over the last status window, from stored samples (the sim is not on
// the hard RT path, so a small vector is fine here), by the project's one rank rule.
msgs::Percentiles percentiles(std::vector<double>& samples_us) {
    const common::PercentileSummary summary = common::summarize(samples_us);
    return {summary.p50, summary.p99, summary.max};
}

}  // namespace

std::vector<softhand::DeviceRequest> deviceRequests(const config::SimConfig& cfg) {
    std::vector<softhand::DeviceRequest> requests;
    for (const auto& device : cfg.devices) {
        softhand::DeviceRequest request;
        request.name = device.name;
        const auto binding = cfg.scene.devices.find(device.name);
        if (binding == cfg.scene.devices.end()) {
            throw std::invalid_argument("device '" + device.name +
                                        "' is not bound to a finger in " +
                                        cfg.scene.source.string());
        }
        request.finger = binding->second.finger;
        request.kinesthetic = device.isExoskeleton();
        if (device.isThimble()) {
            request.finger_from_device = device.thimble().finger_calibration.T_finger_device;
            request.max_samples = device.thimble().optimiser.pad_samples;
        }
        requests.push_back(request);
    }
    return requests;
}

int runSim(const SimOptions& options) {
    const auto& cfg = options.config;
    // Over DDS the sim needs no RouDi (and may run on another host).
    const bool dds_sim = cfg.sim_link.transport == config::SimTransport::kDds;
    const std::optional<ipc::RoudiWatch> roudi_watch =
        ipc::joinRoudi(!dds_sim, "handsim", cfg.iceoryx);
    std::vector<DeviceLink> links(cfg.devices.size());
    for (std::size_t i = 0; i < cfg.devices.size(); ++i) {
        const auto& device = cfg.devices[i];
        links[i].device = &device;
        if (dds_sim) {
            continue;
        }
        if (device.isExoskeleton()) {
            links[i].constraint_sets = std::make_unique<iox::popo::Publisher<msgs::ConstraintSet>>(
                ipc::deviceService(device.name, ipc::kConstraintSetEvent));
        } else {
            links[i].contact_surfaces =
                std::make_unique<iox::popo::Publisher<msgs::ContactSurface>>(
                    ipc::deviceService(device.name, ipc::kContactSurfaceEvent));
        }
        iox::popo::SubscriberOptions subscriber_options;
        subscriber_options.queueCapacity = 1;
        links[i].device_states = std::make_unique<iox::popo::Subscriber<msgs::DeviceState>>(
            ipc::deviceService(device.name, ipc::kDeviceStateEvent), subscriber_options);
    }

    const ipc::DdsSettings dds_settings = ipc::ddsSettings(cfg.dds);
    ipc::DdsParticipant participant(dds_settings, "handsim");
    auto status_writer = participant.createWriter<idl::SimStatusPubSubType>(
        ipc::kSimStatusTopic, ipc::TopicKind::kLatestState);
    // The sim link has a participant of its own, apart from status and tracking (#19): its
    // discovery, history and resources are not shared with them.
    std::unique_ptr<ipc::DdsParticipant> link_participant;
    std::unique_ptr<SimLinkDds> dds_link;
    if (dds_sim) {
        link_participant = std::make_unique<ipc::DdsParticipant>(dds_settings, "handsim-sim-link");
        dds_link = std::make_unique<SimLinkDds>(*link_participant, cfg.devices);
        spdlog::info("sim link over DDS on domain {} (no RouDi needed)", cfg.dds.domain_id);
    }
    msgs::ConstraintSet dds_constraints;
    msgs::ContactSurface dds_surface;
    msgs::DeviceState dds_state;

    softhand::SceneSimulation physics(cfg.scene, deviceRequests(cfg),
                                      softhand::realtimeSceneSettings(cfg.scene.solver));
    auto tracking = makeTrackingSource(cfg.scene, physics, participant, cfg.tracking_filter);
    physics.reset(tracking->initialPose());
    const double dt_s = 1.0 / cfg.scene.rate_hz;
    spdlog::info("scene '{}': soft hand {} ({}), tracking from {}", cfg.scene.name,
                 physics.modelName(), softhand::toString(physics.size()), tracking->describe());
    spdlog::info("stepping at {} Hz for {} device(s); solver: {} Newton iteration(s), PCG cap {}",
                 cfg.scene.rate_hz, cfg.devices.size(), cfg.scene.solver.newton_iterations,
                 cfg.scene.solver.pcg_max_iterations);

    // handsim is soft real time: without the request it runs, slower (docs/hapticd.md, "CPU
    // wake-up latency").
    process::CpuLatencyRequest cpu_latency;
    if (cfg.cpu_latency_us >= 0) {
        cpu_latency = process::CpuLatencyRequest(cfg.cpu_latency_us);
        if (cpu_latency.held()) {
            spdlog::info("CPU wake-up latency held at {} us", cfg.cpu_latency_us);
        } else {
            spdlog::warn(
                "CPU wake-up latency not held ({}; needs the udev rule "
                "60-haptic-cpu-latency.rules): steps after each sleep take longer",
                cpu_latency.error());
        }
    }

    const auto period = std::chrono::nanoseconds(1'000'000'000LL / cfg.scene.rate_hz);
    const auto started = std::chrono::steady_clock::now();
    auto next = started;
    auto last_status = started;
    std::uint64_t steps = 0;
    std::uint64_t status_seq = 0;
    std::uint64_t rejected_inputs = 0;  // in this status window, for the log
    std::string last_rejection;
    // Since start, for sim/status: what the solver did instead of a plain step.
    std::uint64_t total_rejected_inputs = 0;
    std::uint64_t zeroed_steps = 0;
    std::uint64_t rescaled_steps = 0;
    std::uint64_t substepped_steps = 0;
    softhand::StepReport last_report;
    std::vector<double> run_step_times_us;  // whole run with --duration, summary at exit
    run_step_times_us.reserve(
        static_cast<std::size_t>(options.duration_s * cfg.scene.rate_hz * 1.1) + 16);
    std::vector<double> step_times_us;
    step_times_us.reserve(static_cast<std::size_t>(cfg.scene.rate_hz) + 1);

    const bool topic_tracking = cfg.scene.tracking.source == config::TrackingSource::kTopic;
    const auto tracking_timeout = std::chrono::milliseconds(cfg.scene.tracking.timeout_ms);
    std::optional<std::chrono::steady_clock::time_point> last_pose_time;
    bool withholding = false;
    bool hand_placed = !topic_tracking;  // scripts and replays start where the hand is built
    while (!process::shutdownRequested()) {
        next += period;
        std::this_thread::sleep_until(next);
        const auto step_start = std::chrono::steady_clock::now();
        // Simulated time advances by dt per step (the script is a function of it), so a
        // slow step shows up as a lower rate, not as a jump in the motion.
        const double t_s = static_cast<double>(steps + 1) * dt_s;
        std::string rejection;
        const auto pose = tracking->poll(t_s, rejection);
        // The hand waits 0.3 m above the scene until the first pose (initialPose). When the
        // tracker already publishes at the first step (the demo's order: hapticemu first),
        // no silence ends, so nothing placed it: the tracking springs dragged it down through
        // the scene at their speed clamp, into whatever the tracked hand touches. Place it.
        // Only a pose that passed validation places the hand (a NaN first pose must not).
        bool pose_accepted = false;
        if (pose) {
            if (const auto reason = physics.setHandPose(*pose)) {
                rejection = *reason;
            } else {
                pose_accepted = true;
                last_pose_time = step_start;
            }
        }
        const bool first_pose = pose_accepted && !hand_placed;
        if (first_pose) {
            physics.reset(*pose);
            (void)physics.setHandPose(*pose);
            hand_placed = true;
            spdlog::info("tracking: first pose on '{}': hand placed at the tracked pose",
                         cfg.scene.tracking.topic);
        }
        // A silent tracker (topic only; scripts and replays never fall silent) freezes the
        // hand; its targets would go on being rendered with fresh stamps. Withhold them
        // instead: hapticd's sim timeout then fades the force out.
        const bool tracking_silent =
            topic_tracking && (!last_pose_time || step_start - *last_pose_time > tracking_timeout);
        if (tracking_silent != withholding) {
            withholding = tracking_silent;
            if (withholding) {
                spdlog::warn("tracking: no valid pose on '{}' for {} ms: device outputs withheld",
                             cfg.scene.tracking.topic, cfg.scene.tracking.timeout_ms);
            } else {
                // The hand stood still while the tracker was silent (or since start, in its
                // initial pose): pulling it to where the tracker is now would drag it through
                // whatever lies between, and the devices would render that transient (the
                // demo's first contact rang at the 10 N clamp in both directions). Nothing was
                // published meanwhile, so there is no continuity to keep: place it there.
                if (pose_accepted && !first_pose) {  // this step's pose ended the silence
                    physics.reset(*pose);
                    (void)physics.setHandPose(*pose);
                }
                spdlog::info(
                    "tracking: poses on '{}' again: hand placed at the tracked pose, "
                    "device outputs resumed",
                    cfg.scene.tracking.topic);
            }
        }
        const softhand::StepReport report = physics.step(dt_s);
        if (report.rejected_input) {
            ++rejected_inputs;
            ++total_rejected_inputs;
            last_rejection = report.rejection_reason;
        } else if (!rejection.empty()) {
            ++rejected_inputs;
            ++total_rejected_inputs;
            last_rejection = rejection;
        }
        zeroed_steps += report.zeroed_steps > 0 ? 1 : 0;
        rescaled_steps += report.rescaled_steps > 0 ? 1 : 0;
        substepped_steps += report.substepped ? 1 : 0;
        const std::int64_t stamp = common::monotonicNowNs();
        const msgs::TrackingOrigin origin = tracking->origin();

        for (std::size_t index = 0; index < links.size(); ++index) {
            auto& link = links[index];
            const std::string& name = link.device->name;
            if (withholding) {
                if (dds_link) {
                    link.states_received +=
                        dds_link->takeDeviceStates(index, dds_state, link.states_refused);
                } else {
                    while (link.device_states->take().and_then(
                        [&](const auto& state) { countState(link, *state); })) {
                    }
                }
                continue;
            }
            // The device's targets of this step, stamped alike whichever transport carries them.
            const auto fillTargets = [&](auto& message) {
                message = std::remove_cvref_t<decltype(message)>{};
                physics.fill(index, message);
                message.tracking = origin;
                message.header = {};
                message.header.seq = ++link.seq;
                message.header.stamp_ns = stamp;
                message.header.source_id.assign(name);
            };
            if (dds_link) {
                if (link.device->isExoskeleton()) {
                    fillTargets(dds_constraints);
                    link.published += dds_link->publish(index, dds_constraints) ? 1 : 0;
                } else {
                    fillTargets(dds_surface);
                    link.published += dds_link->publish(index, dds_surface) ? 1 : 0;
                }
                link.states_received +=
                    dds_link->takeDeviceStates(index, dds_state, link.states_refused);
                continue;
            }
            auto publishLoaned = [&](auto& sample) {  // iceoryx's function_ref takes no const
                fillTargets(*sample);
                sample.publish();
                ++link.published;
            };
            if (link.constraint_sets) {
                link.constraint_sets->loan().and_then(publishLoaned);
            } else {
                link.contact_surfaces->loan().and_then(publishLoaned);
            }
            while (link.device_states->take().and_then(
                [&](const auto& state) { countState(link, *state); })) {
            }
        }
        ++steps;
        last_report = report;
        if (options.duration_s > 0.0) {  // bounded by --duration
            run_step_times_us.push_back(std::chrono::duration<double, std::micro>(
                                            std::chrono::steady_clock::now() - step_start)
                                            .count());
        }
        step_times_us.push_back(
            std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - step_start)
                .count());

        const auto now = std::chrono::steady_clock::now();
        if (now - last_status >= std::chrono::milliseconds(500)) {
            msgs::SimStatus status;
            status.header = {};
            status.header.seq = ++status_seq;
            status.header.stamp_ns = stamp;
            status.header.source_id.assign(cfg.scene.name);
            status.rate_hz = static_cast<double>(step_times_us.size()) /
                             std::chrono::duration<double>(now - last_status).count();
            status.steps = steps;
            status.step_time_us = percentiles(step_times_us);
            status.node_count = static_cast<std::uint32_t>(physics.model().simulation.nodeCount());
            status.element_count =
                static_cast<std::uint32_t>(physics.model().simulation.tetCount());
            status.solver_residual = last_report.pcg_relative_residual;
            status.solver_iterations = static_cast<std::uint32_t>(last_report.pcg_iterations);
            status.energy_j = last_report.energy_j;
            status.model.assign(physics.modelName());
            status.steps_zeroed = zeroed_steps;
            status.steps_substepped = substepped_steps;
            status.steps_rescaled = rescaled_steps;
            status.inputs_rejected = total_rejected_inputs;
            status.last_rejection.assign(last_rejection);
            if (rejected_inputs > 0) {
                spdlog::warn(
                    "{} tracking input(s) rejected in the last {:.1f} s: {}", rejected_inputs,
                    std::chrono::duration<double>(now - last_status).count(), last_rejection);
                rejected_inputs = 0;
            }
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
    if (!run_step_times_us.empty()) {
        const double run_s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
        const msgs::Percentiles run = percentiles(run_step_times_us);
        spdlog::info(
            "{} steps in {:.1f} s ({:.1f} Hz); step time p50 {:.0f} us, p99 {:.0f} us, max {:.0f} "
            "us; energy guard: {} rescaled, {} substepped, {} frozen; {} tracking input(s) "
            "rejected",
            steps, run_s, static_cast<double>(steps) / run_s, run.p50, run.p99, run.max,
            rescaled_steps, substepped_steps, zeroed_steps, total_rejected_inputs);
    }
    for (const auto& link : links) {
        spdlog::info("device '{}': published {} targets, received {} device states",
                     link.device->name, link.published, link.states_received);
        if (link.states_refused > 0) {
            spdlog::warn(
                "device '{}': refused {} device states of another message schema than "
                "{:#010x} (a hapticd from another release)",
                link.device->name, link.states_refused, msgs::kSchema);
        }
    }
    return EXIT_SUCCESS;
}

}  // namespace haptic::handsim
