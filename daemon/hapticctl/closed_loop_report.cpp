#include "closed_loop_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>

namespace haptic::ctl {
namespace {

std::vector<std::string_view> splitFields(std::string_view line) {
    std::vector<std::string_view> fields;
    while (true) {
        const std::size_t comma = line.find(',');
        fields.push_back(line.substr(0, comma));
        if (comma == std::string_view::npos) {
            return fields;
        }
        line.remove_prefix(comma + 1);
    }
}

std::string_view nextLine(std::string_view& text) {
    const std::size_t end = text.find('\n');
    const std::string_view line = text.substr(0, end);
    text.remove_prefix(end == std::string_view::npos ? text.size() : end + 1);
    return line;
}

double norm3(const DeviceColumns& device, std::string_view prefix, std::string_view suffix,
             std::size_t row) {
    double sum = 0.0;
    for (const char* axis : {"x", "y", "z"}) {
        const double v = device.column(fmt::format("{}{}{}", prefix, axis, suffix))[row];
        sum += v * v;
    }
    return std::sqrt(sum);
}

}  // namespace

const std::vector<double>& DeviceColumns::column(std::string_view name) const {
    const auto found = values.find(name);
    if (found == values.end()) {
        throw std::runtime_error("telemetry CSV: no column '" + std::string(name) + "'");
    }
    return found->second;
}

std::map<int, DeviceColumns> readTelemetryCsv(std::string_view csv) {
    std::string_view first = nextLine(csv);
    while (first.starts_with('#') && !csv.empty()) {  // hapticctl record's provenance
        first = nextLine(csv);
    }
    const std::vector<std::string_view> header = splitFields(first);
    constexpr std::size_t kDeviceColumn = 2;
    constexpr std::size_t kKindColumn = 3;
    if (header.size() <= kKindColumn || header[kDeviceColumn] != "device" ||
        header[kKindColumn] != "device_kind") {
        throw std::runtime_error("telemetry CSV: the first line is not hapticctl record's header");
    }
    std::map<int, DeviceColumns> devices;
    while (!csv.empty()) {
        const std::string_view line = nextLine(csv);
        const std::vector<std::string_view> fields = splitFields(line);
        if (fields.size() != header.size()) {
            continue;  // a truncated last line
        }
        int index = 0;
        const auto& device_field = fields[kDeviceColumn];
        if (std::from_chars(device_field.data(), device_field.data() + device_field.size(), index)
                .ec != std::errc()) {
            continue;
        }
        DeviceColumns& device = devices[index];
        device.kind = std::string(fields[kKindColumn]);
        for (std::size_t i = 0; i < header.size(); ++i) {
            if (i == kKindColumn) {
                continue;
            }
            double value = 0.0;
            const auto& field = fields[i];
            if (std::from_chars(field.data(), field.data() + field.size(), value).ec !=
                std::errc()) {
                value = std::nan("");
            }
            device.values[std::string(header[i])].push_back(value);
        }
    }
    return devices;
}

TrackingLatency trackingLatency(const DeviceColumns& device) {
    std::vector<double> from_receipt;
    std::vector<double> from_sample;
    std::size_t tracker_samples = 0;
    const auto found = device.values.find("tracking_sampled_s");
    if (found != device.values.end()) {
        const auto& sampled = found->second;
        const auto& received = device.column("tracking_received_s");
        const auto& time = device.column("time_s");
        const auto& tick = device.column("tick");
        for (std::size_t i = 1; i < sampled.size(); ++i) {
            // A new sample, seen on the tick right after the last one (a lost telemetry
            // sample in between would make the latency look longer than it was).
            if (std::isnan(sampled[i]) || sampled[i] == sampled[i - 1]) {
                continue;
            }
            ++tracker_samples;
            if (tick[i] != tick[i - 1] + 1.0) {
                continue;
            }
            from_receipt.push_back(1e3 * (time[i] - received[i]));
            from_sample.push_back(1e3 * (time[i] - sampled[i]));
        }
    }
    return {common::summarize(from_receipt), common::summarize(from_sample), tracker_samples};
}

ExoskeletonReport exoskeletonReport(const DeviceColumns& device,
                                    const ContactQualitySettings& settings) {
    ExoskeletonReport report;
    const auto& command = device.column("actuator_force_cmd_n");
    const auto& felt = device.column("exo_actuator_force_n");
    const auto& reference = device.column("exo_reference_actuator_force_n");
    const auto& energy = device.column("exo_energy_observer_j");
    const auto& environment = device.column("exo_environment_work_j");
    report.quality = contactQuality(command, settings);
    double sum_reference = 0.0;
    double sum_squared_error = 0.0;
    double sum_squared_ghost = 0.0;
    for (std::size_t i = 0; i < felt.size(); ++i) {
        if (!(std::abs(reference[i]) > settings.contact_threshold_n ||
              std::abs(felt[i]) > settings.contact_threshold_n)) {
            continue;
        }
        ++report.contact_ticks;
        sum_reference += std::abs(reference[i]);
        const double error = felt[i] - reference[i];
        sum_squared_error += error * error;
        report.peak_error_n = std::max(report.peak_error_n, std::abs(error));
        double ghost_squared = 0.0;
        for (int j = 0; j < 3; ++j) {
            const double g = device.column(fmt::format("exo_ghost_torque_{}_nm", j))[i];
            ghost_squared += g * g;
        }
        sum_squared_ghost += ghost_squared;
        if (std::abs(command[i]) >= settings.clamp_fraction * settings.clamp_n &&
            std::abs(reference[i]) < 0.8 * settings.clamp_n) {
            ++report.clamp_below_reference_ticks;
        }
    }
    if (report.contact_ticks > 0) {
        const auto n = static_cast<double>(report.contact_ticks);
        report.mean_reference_n = sum_reference / n;
        report.rms_error_n = std::sqrt(sum_squared_error / n);
        report.rms_ghost_torque_nm = std::sqrt(sum_squared_ghost / n);
    }
    if (!energy.empty()) {
        report.delivered_energy_j = -(energy.back() - energy.front());
        report.environment_work_j = environment.back() - environment.front();
    }
    const auto& tick = device.column("tick");
    for (std::size_t i = 1; i < command.size(); ++i) {
        if (tick[i] != tick[i - 1] + 1.0) {
            continue;  // a telemetry sample was lost in between
        }
        const double step = std::abs(command[i] - command[i - 1]);
        report.largest_step_n = std::max(report.largest_step_n, step);
        report.steps_over_rate_limit += step > settings.max_step_n + 1e-9 ? 1 : 0;
    }
    return report;
}

ThimbleReport thimbleReport(const DeviceColumns& device, const ContactQualitySettings& settings) {
    ThimbleReport report;
    const auto& time = device.column("time_s");
    report.ticks = time.size();
    double sum = 0.0;
    for (std::size_t i = 0; i < time.size(); ++i) {
        const double force = norm3(device, "thimble_reference_force_", "_n", i);
        report.peak_reference_force_n = std::max(report.peak_reference_force_n, force);
        if (force > settings.contact_threshold_n) {
            ++report.contact_ticks;
            sum += force;
        }
    }
    if (report.contact_ticks > 0) {
        report.mean_reference_force_n = sum / static_cast<double>(report.contact_ticks);
    }
    return report;
}

std::string formatReport(const std::map<int, DeviceColumns>& devices,
                         const ContactQualitySettings& settings) {
    std::string out;
    const auto latencyLine = [](const DeviceColumns& device) {
        const TrackingLatency latency = trackingLatency(device);
        if (latency.tracker_samples == 0) {
            return std::string("  tracker to command: no tracker samples (scripted hand)\n");
        }
        if (latency.from_receipt_ms.count == 0) {
            return fmt::format(
                "  tracker to command: not measured: {} tracker samples, none on consecutive "
                "ticks (a decimated recording; loop.telemetry_decimation: 1 records every "
                "tick)\n",
                latency.tracker_samples);
        }
        return fmt::format(
            "  tracker to command, {} samples: from handsim's receipt p50 {:.1f} ms, p99 {:.1f} "
            "ms, max {:.1f} ms; from the sample's stamp p50 {:.1f} ms, p99 {:.1f} ms\n",
            latency.from_receipt_ms.count, latency.from_receipt_ms.p50, latency.from_receipt_ms.p99,
            latency.from_receipt_ms.max, latency.from_sample_ms.p50, latency.from_sample_ms.p99);
    };
    for (const auto& [index, device] : devices) {
        if (device.kind == "exoskeleton") {
            const ExoskeletonReport r = exoskeletonReport(device, settings);
            const ContactQuality& q = r.quality;
            out += fmt::format(
                "exoskeleton (device {}): {} ticks, {} in contact (|F| > {:.2f} N)\n"
                "  felt vs reference: mean |reference| {:.3f} N, error RMS {:.3f} N ({:.1f}% of "
                "it), peak {:.3f} N\n"
                "  ghost torque RMS {:.5f} N m; net energy delivered {:.6f} J, work of the "
                "moving objects {:.6f} J (excess {:.6f} J)\n"
                "  command: at the {:.1f} N clamp {:.1f}% of contact ticks ({:.1f}% while the "
                "reference is below 80% of it); chatter {:.3f} N RMS = {:.1f}% of the mean "
                "|command| {:.3f} N\n"
                "  largest step of the command {:.3f} N; {} steps above the {:.2f} N rate limit\n",
                index, q.ticks, r.contact_ticks, settings.contact_threshold_n, r.mean_reference_n,
                r.rms_error_n, 100.0 * r.errorFraction(), r.peak_error_n, r.rms_ghost_torque_nm,
                r.delivered_energy_j, r.environment_work_j, r.excessEnergy(), settings.clamp_n,
                100.0 * q.clampFraction(), 100.0 * r.clampBelowReferenceFraction(), q.chatter_rms_n,
                100.0 * q.chatterFraction(), q.mean_contact_force_n, r.largest_step_n,
                r.steps_over_rate_limit, settings.max_step_n);
            out += latencyLine(device);
        } else if (device.kind == "thimble") {
            const ThimbleReport r = thimbleReport(device, settings);
            out += fmt::format(
                "thimble (device {}): {} ticks, reference pad force above {:.2f} N on {}, mean "
                "{:.3f} N, peak {:.3f} N (the felt pad force is not measured yet)\n",
                index, r.ticks, settings.contact_threshold_n, r.contact_ticks,
                r.mean_reference_force_n, r.peak_reference_force_n);
            out += latencyLine(device);
        }
    }
    return out;
}

}  // namespace haptic::ctl
