#include "closed_loop_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <stdexcept>

#include "telemetry_csv.hpp"

namespace haptic::ctl {
namespace {

// Below this |felt| the felt log's five decimals no longer give the push's direction to 1 %:
// the last direction felt above it stands.
constexpr double kPushDirectionFloorN = 1e-3;

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
    const auto& tick = device.column("tick");
    if (!energy.empty()) {
        // The observer's energy is the port's intake (-delivered) since the enable, and a
        // disabled port starts a new interval: both columns read 0 again
        // (ExoskeletonChannel). Such a drop is no energy delivered, nor the objects' work.
        const auto interval_ends = [&](std::size_t i) {
            return energy[i] == 0.0 && environment[i] == 0.0 &&
                   (energy[i - 1] != 0.0 || environment[i - 1] != 0.0);
        };
        report.carried_in_budget_j = energy.front() + environment.front();
        report.worst_balance_j = -report.carried_in_budget_j;
        for (std::size_t i = 1; i < energy.size(); ++i) {
            report.worst_balance_j =
                std::max(report.worst_balance_j, -(energy[i] + environment[i]));
            if (interval_ends(i)) {
                continue;
            }
            const double delivered = -(energy[i] - energy[i - 1]);
            report.delivered_energy_j += delivered;
            report.environment_work_j += environment[i] - environment[i - 1];
            // Consecutive samples only: across a lost sample the balance may have crossed 0.
            if (tick[i] == tick[i - 1] + 1.0 && -(energy[i - 1] + environment[i - 1]) > 0.0 &&
                delivered > 0.0) {
                report.delivered_in_deficit_j += delivered;
            }
        }
    }
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
    report.felt_attached = device.values.contains("felt_force_x_n");
    // The columns once, not per tick: thimble_reference_force_{x,y,z}_n, and felt_force_* when
    // a felt log is attached.
    std::array<const std::vector<double>*, 3> reference_axes{};
    std::array<const std::vector<double>*, 3> felt_axes{};
    const std::vector<double>* indentation = nullptr;
    for (std::size_t k = 0; k < 3; ++k) {
        const char axis = "xyz"[k];
        reference_axes[k] = &device.column(fmt::format("thimble_reference_force_{}_n", axis));
        if (report.felt_attached) {
            felt_axes[k] = &device.column(fmt::format("felt_force_{}_n", axis));
        }
    }
    if (report.felt_attached) {
        indentation = &device.column("felt_indentation_m");
    }
    const auto magnitude = [](const std::array<const std::vector<double>*, 3>& axes,
                              std::size_t i) {
        return std::hypot((*axes[0])[i], (*axes[1])[i], (*axes[2])[i]);
    };
    // |felt| per tick for the chatter and limit figures, from the first to the last tick with
    // a known value, an unknown tick in between holding the last known one (dropping it would
    // join the ticks either side into one moving average).
    std::vector<double> felt_held;
    double reference_sum = 0.0;
    double reference_on_felt_sum = 0.0;
    double felt_sum = 0.0;
    double squared_error_sum = 0.0;
    double squared_along_sum = 0.0;
    double squared_across_sum = 0.0;
    std::array<double, 3> push{0.0, 0.0, -1.0};  // the untilted plate pushes the pad along −z
    double last_felt = 0.0;
    std::size_t held_end = 0;  // past the last known value
    for (std::size_t i = 0; i < time.size(); ++i) {
        const double reference = magnitude(reference_axes, i);
        report.peak_reference_force_n = std::max(report.peak_reference_force_n, reference);
        double felt = std::nan("");
        double error = 0.0;
        double along_error = 0.0;
        double across_error = 0.0;
        if (report.felt_attached) {
            felt = magnitude(felt_axes, i);
            if (std::isfinite(felt)) {
                std::array<double, 3> difference{};
                for (std::size_t k = 0; k < 3; ++k) {
                    difference[k] = (*felt_axes[k])[i] - (*reference_axes[k])[i];
                }
                error = std::hypot(difference[0], difference[1], difference[2]);
                if (felt > kPushDirectionFloorN) {
                    for (std::size_t k = 0; k < 3; ++k) {
                        push[k] = (*felt_axes[k])[i] / felt;
                    }
                }
                // The error vector's parts along the push and across it: exact on every tick,
                // also where a felt force below the floor is not along the held push.
                along_error =
                    difference[0] * push[0] + difference[1] * push[1] + difference[2] * push[2];
                across_error = std::hypot(difference[0] - along_error * push[0],
                                          difference[1] - along_error * push[1],
                                          difference[2] - along_error * push[2]);
                last_felt = felt;
                report.peak_indentation_m = std::max(report.peak_indentation_m, (*indentation)[i]);
            }
            if (std::isfinite(felt) || !felt_held.empty()) {
                felt_held.push_back(last_felt);
            }
            if (std::isfinite(felt)) {
                held_end = felt_held.size();
            }
        }
        const bool felt_known = std::isfinite(felt);
        if (reference > settings.contact_threshold_n ||
            (felt_known && felt > settings.contact_threshold_n)) {
            ++report.contact_ticks;
            reference_sum += reference;
            if (felt_known) {
                ++report.felt_ticks;
                felt_sum += felt;
                reference_on_felt_sum += reference;
                squared_error_sum += error * error;
                squared_along_sum += along_error * along_error;
                squared_across_sum += across_error * across_error;
                report.peak_error_n = std::max(report.peak_error_n, error);
            }
        }
    }
    if (report.contact_ticks > 0) {
        report.mean_reference_force_n = reference_sum / static_cast<double>(report.contact_ticks);
    }
    if (report.felt_ticks > 0) {
        const auto n = static_cast<double>(report.felt_ticks);
        report.mean_felt_force_n = felt_sum / n;
        report.mean_reference_on_felt_ticks_n = reference_on_felt_sum / n;
        report.rms_error_n = std::sqrt(squared_error_sum / n);
        report.rms_error_along_push_n = std::sqrt(squared_along_sum / n);
        report.rms_error_across_push_n = std::sqrt(squared_across_sum / n);
        felt_held.resize(held_end);
        report.felt_quality = contactQuality(felt_held, settings);
    }
    return report;
}

RecordingInfo readRecordingInfo(std::string_view csv) {
    RecordingInfo info;
    constexpr std::string_view kDevices = "# devices: ";
    while (!csv.empty() && csv.starts_with('#')) {
        const std::string_view line = nextLine(csv);
        if (line.starts_with(kOriginLinePrefix)) {
            std::string_view digits = line.substr(kOriginLinePrefix.size());
            std::int64_t origin = 0;
            if (std::from_chars(digits.data(), digits.data() + digits.size(), origin).ec ==
                std::errc()) {
                info.origin_ns = origin;
            }
        } else if (line.starts_with(kDevices)) {
            // "0 exo (exoskeleton), 1 thimble (thimble)"
            for (std::string_view entry : splitFields(line.substr(kDevices.size()))) {
                while (entry.starts_with(' ')) {
                    entry.remove_prefix(1);
                }
                const std::size_t space = entry.find(' ');
                const std::size_t paren = entry.find(" (");
                int index = 0;
                if (space == std::string_view::npos || paren == std::string_view::npos ||
                    std::from_chars(entry.data(), entry.data() + space, index).ec != std::errc()) {
                    continue;
                }
                info.device_names[index] = std::string(entry.substr(space + 1, paren - space - 1));
            }
        }
    }
    return info;
}

std::map<std::string, FeltSeries, std::less<>> readFeltLog(std::string_view csv) {
    std::string_view header = nextLine(csv);
    while (header.starts_with('#') && !csv.empty()) {
        header = nextLine(csv);
    }
    // stamp_ns, device, finger_penetration_m, pose_known, indentation_m, force x, y, z,
    // moment x, y, z
    constexpr std::size_t kFields = 11;
    if (!header.starts_with("stamp_ns,device,finger_penetration_m,pose_known,indentation_m,"
                            "force_x_n") ||
        splitFields(header).size() != kFields) {
        throw std::runtime_error("felt log: the first line is not hapticemu --felt-log's header");
    }
    const auto parse = [](std::string_view field, auto& value) {
        const auto [end, error] = std::from_chars(field.data(), field.data() + field.size(), value);
        return error == std::errc() && end == field.data() + field.size();
    };
    std::map<std::string, FeltSeries, std::less<>> out;
    while (!csv.empty()) {
        const std::vector<std::string_view> fields = splitFields(nextLine(csv));
        // A line cut short (the emulator was still writing it) has fewer fields, or a last
        // number that no longer parses whole.
        if (fields.size() != kFields || fields[1].empty()) {
            continue;
        }
        std::int64_t stamp = 0;
        int pose_known = 0;
        double penetration = 0.0;
        std::array<double, 7> numbers{};  // indentation, force x, y, z, moment x, y, z
        bool ok = parse(fields[0], stamp) && parse(fields[2], penetration) &&
                  parse(fields[3], pose_known);
        for (std::size_t k = 0; k < numbers.size() && ok; ++k) {
            ok = parse(fields[4 + k], numbers[k]);
        }
        if (!ok) {
            continue;
        }
        FeltSeries& series = out[std::string(fields[1])];
        series.stamp_ns.push_back(stamp);
        series.finger_penetration_m.push_back(penetration);
        // No pad contact known: the force is unknown, not zero.
        const double unknown = std::nan("");
        series.indentation_m.push_back(pose_known != 0 ? numbers[0] : unknown);
        series.force_n.push_back(pose_known != 0
                                     ? std::array<double, 3>{numbers[1], numbers[2], numbers[3]}
                                     : std::array<double, 3>{unknown, unknown, unknown});
    }
    return out;
}

std::size_t completeFeltLogRows(std::string_view csv) {
    std::size_t rows = 0;
    bool header_seen = false;
    while (!csv.empty()) {
        const bool complete = csv.find('\n') != std::string_view::npos;
        const std::string_view line = nextLine(csv);
        if (!complete || line.starts_with('#')) {
            continue;
        }
        if (!header_seen) {
            header_seen = true;
            continue;
        }
        ++rows;
    }
    return rows;
}

std::vector<std::string> attachFeltLog(std::map<int, DeviceColumns>& devices,
                                       const RecordingInfo& recording,
                                       const std::map<std::string, FeltSeries, std::less<>>& felt) {
    if (recording.origin_ns < 0) {
        throw std::runtime_error(
            "the recording has no '" + std::string(kOriginLinePrefix) +
            "' line to align a felt log with (recorded by an older hapticctl)");
    }
    if (recording.device_names.empty()) {
        throw std::runtime_error(
            "the recording names no devices (hapticd's status was not received while "
            "recording), so the felt log's devices cannot be matched");
    }
    constexpr std::int64_t kMaxAgeNs = 20'000'000;
    std::vector<std::string> attached;
    for (auto& [index, device] : devices) {
        const auto name = recording.device_names.find(index);
        if (name == recording.device_names.end()) {
            continue;
        }
        const auto series = felt.find(name->second);
        if (series == felt.end()) {
            continue;
        }
        const auto& time = device.column("time_s");
        std::array<std::vector<double>, 3> force;
        std::vector<double> indentation;
        std::vector<double> penetration;
        const FeltSeries& log = series->second;
        std::size_t next = 0;  // first log row after the tick
        for (const double t : time) {
            if (!std::isfinite(t)) {
                for (auto& axis : force) {
                    axis.push_back(std::nan(""));
                }
                indentation.push_back(std::nan(""));
                penetration.push_back(std::nan(""));
                continue;
            }
            const auto stamp =
                recording.origin_ns + static_cast<std::int64_t>(std::llround(t * 1e9));
            while (next < log.stamp_ns.size() && log.stamp_ns[next] <= stamp) {
                ++next;
            }
            const bool known = next > 0 && stamp - log.stamp_ns[next - 1] <= kMaxAgeNs;
            for (std::size_t k = 0; k < 3; ++k) {
                force[k].push_back(known ? log.force_n[next - 1][k] : std::nan(""));
            }
            indentation.push_back(known ? log.indentation_m[next - 1] : std::nan(""));
            penetration.push_back(known ? log.finger_penetration_m[next - 1] : std::nan(""));
        }
        device.values["finger_penetration_m"] = std::move(penetration);
        if (device.kind == "thimble") {
            device.values["felt_force_x_n"] = std::move(force[0]);
            device.values["felt_force_y_n"] = std::move(force[1]);
            device.values["felt_force_z_n"] = std::move(force[2]);
            device.values["felt_indentation_m"] = std::move(indentation);
        }
        attached.push_back(name->second);
    }
    return attached;
}

FingerPenetration fingerPenetration(const DeviceColumns& device) {
    FingerPenetration out;
    const auto found = device.values.find("finger_penetration_m");
    if (found == device.values.end()) {
        return out;
    }
    std::vector<double> inside;
    for (const double depth : found->second) {
        if (std::isfinite(depth)) {
            ++out.known;
            if (depth > 0.0) {
                inside.push_back(depth);
            }
        }
    }
    out.inside = inside.size();
    out.while_inside_m = common::summarize(inside);
    return out;
}

std::string formatReport(const std::map<int, DeviceColumns>& devices,
                         const ContactQualitySettings& settings,
                         const ContactQualitySettings& thimble_settings) {
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
    const auto penetrationLine = [](const DeviceColumns& device) {
        const FingerPenetration p = fingerPenetration(device);
        if (p.known == 0) {
            return std::string();
        }
        if (p.inside == 0) {
            return fmt::format(
                "  the user's finger never inside the scene's static objects ({} ticks)\n",
                p.known);
        }
        return fmt::format(
            "  the user's finger inside the scene's static objects on {:.1f}% of {} ticks; "
            "there p50 {:.2f} mm, p99 {:.2f} mm, max {:.2f} mm\n",
            100.0 * static_cast<double>(p.inside) / static_cast<double>(p.known), p.known,
            1e3 * p.while_inside_m.p50, 1e3 * p.while_inside_m.p99, 1e3 * p.while_inside_m.max);
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
                "moving objects {:.6f} J (excess {:.6f} J, with {:.6f} J of budget carried in); "
                "since the port's enable, delivered minus work at most {:.3g} J; delivered in "
                "deficit {:.3g} "
                "J\n"
                "  command: at the {:.1f} N clamp {:.1f}% of contact ticks ({:.1f}% while the "
                "reference is below 80% of it); chatter {:.3f} N RMS = {:.1f}% of the mean "
                "|command| {:.3f} N\n"
                "  largest step of the command {:.3f} N; {} steps above the {:.2f} N rate limit\n",
                index, q.ticks, r.contact_ticks, settings.contact_threshold_n, r.mean_reference_n,
                r.rms_error_n, 100.0 * r.errorFraction(), r.peak_error_n, r.rms_ghost_torque_nm,
                r.delivered_energy_j, r.environment_work_j, r.excessEnergy(), r.carried_in_budget_j,
                r.worst_balance_j, r.delivered_in_deficit_j, settings.clamp_n,
                100.0 * q.clampFraction(), 100.0 * r.clampBelowReferenceFraction(), q.chatter_rms_n,
                100.0 * q.chatterFraction(), q.mean_contact_force_n, r.largest_step_n,
                r.steps_over_rate_limit, settings.max_step_n);
            out += penetrationLine(device);
            out += latencyLine(device);
        } else if (device.kind == "thimble") {
            const ThimbleReport r = thimbleReport(device, thimble_settings);
            out += fmt::format(
                "thimble (device {}): {} ticks, {} in contact (reference or felt pad force above "
                "{:.2f} N); reference mean {:.3f} N, peak {:.3f} N\n",
                index, r.ticks, r.contact_ticks, thimble_settings.contact_threshold_n,
                r.mean_reference_force_n, r.peak_reference_force_n);
            if (!r.felt_attached) {
                out +=
                    "  felt pad force: no felt log (plot --felt FILE, from hapticemu "
                    "--felt-log)\n";
            } else if (r.felt_ticks == 0) {
                out += "  felt pad force: the felt log has no value on any contact tick\n";
            } else {
                const ContactQuality& q = r.felt_quality;
                out += fmt::format(
                    "  felt vs reference, {} contact ticks with a felt value: mean |felt| {:.3f} "
                    "N against a mean |reference| {:.3f} N there; error RMS {:.3f} N ({:.1f}% of "
                    "that reference), peak {:.3f} N; pad indented up to {:.2f} mm\n",
                    r.felt_ticks, r.mean_felt_force_n, r.mean_reference_on_felt_ticks_n,
                    r.rms_error_n, 100.0 * r.errorFraction(), r.peak_error_n,
                    1e3 * r.peak_indentation_m);
                out += fmt::format(
                    "  of that error, along the plate's push {:.3f} N RMS ({:.1f}%); across it "
                    "{:.3f} N RMS ({:.1f}%): the reference's direction off the plate's push (a "
                    "sliding finger's friction, where the plate follows the contact's "
                    "geometry)\n",
                    r.rms_error_along_push_n, 100.0 * r.alongPushFraction(),
                    r.rms_error_across_push_n, 100.0 * r.acrossPushFraction());
                if (q.contact_ticks == 0) {
                    out +=
                        fmt::format("  felt: never above {:.2f} N, so no chatter or limit figure\n",
                                    thimble_settings.contact_threshold_n);
                } else {
                    out += fmt::format(
                        "  felt above {:.2f} N on {} ticks: at the {:.2f} N pad force limit on "
                        "{:.1f}% of them; chatter {:.3f} N RMS = {:.1f}% of its mean there\n",
                        thimble_settings.contact_threshold_n, q.contact_ticks,
                        thimble_settings.clamp_n, 100.0 * q.clampFraction(), q.chatter_rms_n,
                        100.0 * q.chatterFraction());
                }
            }
            out += penetrationLine(device);
            out += latencyLine(device);
        }
    }
    return out;
}

}  // namespace haptic::ctl
