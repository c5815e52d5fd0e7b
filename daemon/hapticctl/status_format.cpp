#include "status_format.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "haptic/msgs/names.hpp"

namespace haptic::ctl {

namespace {

std::string percentilesLine(std::string_view label, const msgs::Percentiles& p) {
    return fmt::format("           {:<9} p50 {:7.1f} us   p99 {:7.1f} us   max {:7.1f} us\n", label,
                       p.p50, p.p99, p.max);
}

}  // namespace

std::string formatStatus(const msgs::HapticStatus& status, double sample_age_s) {
    std::string out;
    out += "\u25cf hapticd - haptic runtime daemon\n";
    out += fmt::format("     State: {}   rendering method: {}\n", toString(status.state),
                       status.rendering_method.empty() ? std::string_view("(none)")
                                                       : status.rendering_method.view());
    out += sample_age_s < 0.0 ? fmt::format("    Uptime: {:.1f} s   (status #{})\n",
                                            status.uptime_s, status.header.seq)
                              : fmt::format("    Uptime: {:.1f} s   (status #{}, {:.2f} s old)\n",
                                            status.uptime_s, status.header.seq, sample_age_s);
    // The first 12 hex digits tell configurations apart; the JSON and recordings carry all.
    const std::string_view digest = status.config_digest.view();
    out +=
        fmt::format("   Version: hapticd {}   configuration {}\n", orUnknown(status.version.view()),
                    orUnknown(digest.substr(0, std::min<std::size_t>(digest.size(), 19))));

    const auto& loop = status.loop;
    out += fmt::format(
        "      Loop: {:.0f} Hz, {} ticks, {} overruns (read {} / compute {} / write {})\n",
        loop.rate_hz, loop.ticks, loop.overruns, loop.overruns_read, loop.overruns_compute,
        loop.overruns_write);
    out += percentilesLine("period", loop.period_us);
    out += percentilesLine("wake-up", loop.wakeup_latency_us);
    out += percentilesLine("tick work", loop.tick_work_us);

    const auto& link = status.sim_link;
    const std::string age =
        link.age_ms < 0.0 ? std::string("never") : fmt::format("{:.1f} ms ago", link.age_ms);
    out += fmt::format("  Sim link: {}, {}, last input {}, {:.1f} Hz, {} received, {} rejected\n",
                       toString(link.transport), link.connected ? "connected" : "NOT CONNECTED",
                       age, link.rate_hz, link.received, link.rejected);
    if (link.rejected > 0) {
        // Which check refused them (docs/hapticd.md, "Sim input validation"): a NaN from the
        // sim is not a late message on a loaded machine.
        std::string reasons;
        for (std::size_t i = 0; i < link.rejected_by_reason.size(); ++i) {
            if (link.rejected_by_reason[i] > 0) {
                reasons +=
                    fmt::format("{}{} {}", reasons.empty() ? "" : ", ",
                                msgs::toString(msgs::reasonAt(i)), link.rejected_by_reason[i]);
            }
        }
        out += fmt::format(
            "            rejected: {}\n",
            reasons.empty() ? "by reason unknown (a hapticd that does not count them)" : reasons);
    }
    if (link.late_input_ticks > 0) {
        out += fmt::format(
            "            late input faded the force on {} ticks (sim slower than 3/4 of "
            "sim_timeout_ms, or stalled)\n",
            link.late_input_ticks);
    }

    out += status.devices.empty() ? "   Devices: none configured\n" : "   Devices:\n";
    for (const auto& device : status.devices) {
        const std::string frame_age = device.last_frame_age_ms < 0.0
                                          ? std::string("never")
                                          : fmt::format("{:.1f} ms ago", device.last_frame_age_ms);
        out += fmt::format(
            "            {:<16} {:<11} {:<8} bus {:<13} rx {} tx {} err {}/{} rejected {}  last "
            "frame {}\n",
            device.device_id.view(), toString(device.kind), toString(device.state),
            toString(device.can.bus_state), device.can.rx_frames, device.can.tx_frames,
            device.can.rx_errors, device.can.tx_errors, device.can.rejected_frames, frame_age);
        if (device.awaiting_enable) {
            out +=
                "                             AWAITING ENABLE: its sim input was lost longer "
                "than loop.sim_rearm_after_ms; `hapticctl enable` re-arms it\n";
        }
    }

    if (status.faults.empty()) {
        out += "    Faults: none\n";
    } else {
        out += fmt::format("    Faults: {}\n", status.faults.size());
        for (const auto& fault : status.faults) {
            out += fmt::format("            [{}] {}: {}\n", fault.code, fault.device_id.view(),
                               fault.message.view());
        }
    }
    return out;
}

std::string formatSimStatus(const msgs::SimStatus& status, double sample_age_s) {
    std::string out;
    out += fmt::format("\u25cf handsim - soft hand simulation, scene '{}'\n",
                       status.header.source_id.view());
    out += fmt::format("     Model: {} ({} nodes, {} elements)\n", status.model.view(),
                       status.node_count, status.element_count);
    out += sample_age_s < 0.0
               ? fmt::format("     Steps: {} at {:.1f} Hz   (status #{})\n", status.steps,
                             status.rate_hz, status.header.seq)
               : fmt::format("     Steps: {} at {:.1f} Hz   (status #{}, {:.2f} s old)\n",
                             status.steps, status.rate_hz, status.header.seq, sample_age_s);
    out += percentilesLine("step", status.step_time_us);
    out +=
        fmt::format("    Solver: last step {} PCG iterations, residual {:.2e}, energy {:.3e} J\n",
                    status.solver_iterations, status.solver_residual, status.energy_j);
    const double steps = status.steps > 0 ? static_cast<double>(status.steps) : 1.0;
    const auto share = [&](std::uint64_t count) {
        return 100.0 * static_cast<double>(count) / steps;
    };
    out += fmt::format(
        "    Energy: {} steps rescaled ({:.1f}%), {} substepped ({:.1f}%), {} frozen ({:.1f}%)\n",
        status.steps_rescaled, share(status.steps_rescaled), status.steps_substepped,
        share(status.steps_substepped), status.steps_zeroed, share(status.steps_zeroed));
    out += status.inputs_rejected == 0
               ? std::string("  Tracking: no input rejected\n")
               : fmt::format("  Tracking: {} inputs rejected, last: {}\n", status.inputs_rejected,
                             status.last_rejection.view());
    return out;
}

}  // namespace haptic::ctl
