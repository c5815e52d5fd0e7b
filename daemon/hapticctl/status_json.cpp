#include "status_json.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "haptic/msgs/names.hpp"

namespace haptic::ctl {
namespace {

using Json = nlohmann::ordered_json;

// Unknown or not applicable (negative ages, NaN) is null rather than a sentinel number.
Json orNull(double value) {
    return std::isfinite(value) && value >= 0.0 ? Json(value) : Json(nullptr);
}

Json percentiles(const msgs::Percentiles& p) {
    return Json{{"p50", p.p50}, {"p99", p.p99}, {"max", p.max}};
}

// What every object starts with: which schema, who printed it, which snapshot and how old.
Json opening(const char* schema, const msgs::MessageHeader& header, double sample_age_s) {
    Json out;
    out["schema"] = schema;
    out["hapticctl_version"] = HAPTIC_VERSION;
    out["seq"] = header.seq;
    out["age_s"] = orNull(sample_age_s);
    return out;
}

}  // namespace

std::string statusJson(const msgs::HapticStatus& status, double sample_age_s) {
    Json out = opening(kStatusJsonSchema, status.header, sample_age_s);
    out["state"] = msgs::toString(status.state);
    out["rendering_method"] = status.rendering_method.view();
    out["version"] = status.version.view();
    out["config_digest"] = status.config_digest.view();
    out["uptime_s"] = status.uptime_s;
    const msgs::LoopStatistics& loop = status.loop;
    out["loop"] = Json{{"rate_hz", loop.rate_hz},
                       {"ticks", loop.ticks},
                       {"overruns", loop.overruns},
                       {"overruns_read", loop.overruns_read},
                       {"overruns_compute", loop.overruns_compute},
                       {"overruns_write", loop.overruns_write},
                       {"period_us", percentiles(loop.period_us)},
                       {"wakeup_latency_us", percentiles(loop.wakeup_latency_us)},
                       {"tick_work_us", percentiles(loop.tick_work_us)}};
    const msgs::SimLinkStatus& link = status.sim_link;
    Json rejected_by_reason = Json::object();
    for (std::size_t i = 0; i < link.rejected_by_reason.size(); ++i) {
        rejected_by_reason[msgs::toString(msgs::reasonAt(i))] = link.rejected_by_reason[i];
    }
    out["sim_link"] = Json{{"transport", msgs::toString(link.transport)},
                           {"connected", link.connected},
                           {"age_ms", orNull(link.age_ms)},
                           {"rate_hz", link.rate_hz},
                           {"received", link.received},
                           {"rejected", link.rejected},
                           {"rejected_by_reason", rejected_by_reason},
                           {"late_input_ticks", link.late_input_ticks}};
    Json devices = Json::array();
    for (const msgs::DeviceStatus& device : status.devices) {
        devices.push_back(Json{{"id", device.device_id.view()},
                               {"kind", msgs::toString(device.kind)},
                               {"state", msgs::toString(device.state)},
                               {"awaiting_enable", device.awaiting_enable},
                               {"last_frame_age_ms", orNull(device.last_frame_age_ms)},
                               {"can",
                                {{"bus_state", msgs::toString(device.can.bus_state)},
                                 {"rx_frames", device.can.rx_frames},
                                 {"tx_frames", device.can.tx_frames},
                                 {"rx_errors", device.can.rx_errors},
                                 {"tx_errors", device.can.tx_errors},
                                 {"rejected_frames", device.can.rejected_frames}}}});
    }
    out["devices"] = devices;
    Json faults = Json::array();
    for (const msgs::Fault& fault : status.faults) {
        faults.push_back(Json{{"code", fault.code},
                              {"device", fault.device_id.view()},
                              {"message", fault.message.view()}});
    }
    out["faults"] = faults;
    // Text from the daemon is not checked UTF-8: a bad byte becomes U+FFFD, not an exception.
    return out.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string simStatusJson(const msgs::SimStatus& status, double sample_age_s) {
    Json out = opening(kSimStatusJsonSchema, status.header, sample_age_s);
    out["scene"] = status.header.source_id.view();
    out["model"] = status.model.view();
    out["node_count"] = status.node_count;
    out["element_count"] = status.element_count;
    out["rate_hz"] = status.rate_hz;
    out["steps"] = status.steps;
    out["step_time_us"] = percentiles(status.step_time_us);
    out["solver"] = Json{{"iterations", status.solver_iterations},
                         {"residual", status.solver_residual},
                         {"energy_j", status.energy_j}};
    out["steps_zeroed"] = status.steps_zeroed;
    out["steps_substepped"] = status.steps_substepped;
    out["steps_rescaled"] = status.steps_rescaled;
    out["inputs_rejected"] = status.inputs_rejected;
    out["last_rejection"] = status.last_rejection.view();
    // Text from the daemon is not checked UTF-8: a bad byte becomes U+FFFD, not an exception.
    return out.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace haptic::ctl
