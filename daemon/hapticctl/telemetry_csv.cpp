#include "telemetry_csv.hpp"

#include <fmt/format.h>

#include <ctime>
#include <stdexcept>
#include <string_view>

#include "haptic/msgs/names.hpp"
#include "status_format.hpp"

namespace haptic::ctl {
namespace {
// Quotes a path for a gnuplot single-quoted string (a quote is written twice).
std::string quoted(const std::string& path) {
    std::string out = "'";
    for (const char c : path) {
        out += c;
        if (c == '\'') {
            out += '\'';
        }
    }
    return out + "'";
}
}  // namespace

std::string telemetryCsvProvenance(std::string_view hapticctl_version, std::int64_t wall_clock_ns,
                                   std::int64_t origin_ns, const msgs::HapticStatus* status) {
    const std::time_t seconds = static_cast<std::time_t>(wall_clock_ns / 1'000'000'000);
    std::tm utc{};
    ::gmtime_r(&seconds, &utc);
    std::string out = fmt::format("# hapticctl record {}\n", hapticctl_version);
    out += fmt::format(
        "# started {:04}-{:02}-{:02}T{:02}:{:02}:{:02}Z (first sample, wall clock)\n",
        utc.tm_year + 1900, utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec);
    out +=
        fmt::format("{}{} (hapticd's stamp of the first sample)\n", kOriginLinePrefix, origin_ns);
    if (status == nullptr) {
        out += "# hapticd: no status received, version and configuration unknown\n";
        return out;
    }
    out += fmt::format("# hapticd {}, configuration {}\n", orUnknown(status->version.view()),
                       orUnknown(status->config_digest.view()));
    std::string devices;
    for (std::size_t i = 0; i < status->devices.size(); ++i) {
        const msgs::DeviceStatus& device = status->devices[i];
        devices += fmt::format("{}{} {} ({})", i == 0 ? "" : ", ", i, device.device_id.view(),
                               msgs::toString(device.kind));
    }
    out += fmt::format("# devices: {}\n", devices.empty() ? std::string("none") : devices);
    return out;
}

std::string telemetryCsvHeader() {
    std::string header = "tick,time_s,device,device_kind,actuator_force_cmd_n";
    for (std::size_t i = 0; i < msgs::kThimbleServos; ++i) {
        header += fmt::format(",servo_angle_cmd_{}_rad", i);
    }
    header += ",tick_work_us,wakeup_latency_us,read_us,write_us";
    // Appended later: the columns above keep their numbers for the plot script.
    for (std::size_t i = 0; i < 3; ++i) {
        header += fmt::format(",exo_joint_{}_rad", i);
    }
    for (std::size_t i = 0; i < 3; ++i) {
        header += fmt::format(",exo_proxy_{}_rad", i);
    }
    header += ",exo_actuator_force_n";
    for (std::size_t i = 0; i < 3; ++i) {
        header += fmt::format(",exo_reference_torque_{}_nm", i);
    }
    header += ",exo_reference_actuator_force_n";
    for (std::size_t i = 0; i < 3; ++i) {
        header += fmt::format(",exo_ghost_torque_{}_nm", i);
    }
    header += ",exo_energy_observer_j,exo_environment_work_j";
    for (std::size_t i = 0; i < msgs::kThimbleServos; ++i) {
        header += fmt::format(",servo_angle_{}_rad", i);
    }
    header +=
        ",thimble_reference_force_x_n,thimble_reference_force_y_n,thimble_reference_force_z_n";
    header +=
        ",thimble_reference_moment_x_nm,thimble_reference_moment_y_nm,"
        "thimble_reference_moment_z_nm";
    header += ",thimble_pad_force_model_n,thimble_pad_limit_flags";
    // The tracker sample behind this tick's sim input, on the time_s axis (empty: scripted).
    header += ",tracking_sampled_s,tracking_received_s";
    return header + "\n";
}

std::string telemetryCsvRow(const msgs::TelemetrySample& sample, std::int64_t origin_ns) {
    std::string row =
        fmt::format("{},{:.6f},{},{},{:.4f}", sample.tick,
                    static_cast<double>(sample.stamp_ns - origin_ns) * 1e-9, sample.device_index,
                    msgs::toString(sample.device_kind), sample.exoskeleton.actuator_force_cmd_n);
    for (const double angle : sample.thimble.servo_angle_cmd_rad) {
        row += fmt::format(",{:.4f}", angle);
    }
    row += fmt::format(",{:.2f},{:.2f},{:.2f},{:.2f}", sample.tick_work_us,
                       sample.wakeup_latency_us, sample.read_us, sample.write_us);
    const msgs::ExoskeletonTelemetry& exo = sample.exoskeleton;
    for (std::size_t i = 0; i < 3; ++i) {
        row += fmt::format(",{:.6f}", exo.joint_position_rad[i]);
    }
    for (std::size_t i = 0; i < 3; ++i) {
        row += fmt::format(",{:.6f}", exo.proxy_position_rad[i]);
    }
    row += fmt::format(",{:.4f}", exo.actuator_force_n);
    for (std::size_t i = 0; i < 3; ++i) {
        row += fmt::format(",{:.6f}", exo.reference_torque_nm[i]);
    }
    row += fmt::format(",{:.4f}", exo.reference_actuator_force_n);
    for (std::size_t i = 0; i < 3; ++i) {
        row += fmt::format(",{:.6f}", exo.ghost_torque_nm[i]);
    }
    // To the nJ: the passivity balance is judged on these, and a recording's budget is
    // tenths of a mJ.
    row += fmt::format(",{:.9f},{:.9f}", exo.energy_observer_j, exo.environment_work_j);
    for (const double angle : sample.thimble.servo_angle_rad) {
        row += fmt::format(",{:.4f}", angle);
    }
    for (const double force : sample.thimble.reference_force_device_n) {
        row += fmt::format(",{:.4f}", force);
    }
    for (const double moment : sample.thimble.reference_moment_device_nm) {
        row += fmt::format(",{:.6f}", moment);
    }
    row += fmt::format(",{:.4f},{}", sample.thimble.pad_force_model_n,
                       static_cast<unsigned>(sample.thimble.pad_limit_flags));
    if (sample.tracking.sampled_ns != 0) {
        row += fmt::format(",{:.6f},{:.6f}",
                           static_cast<double>(sample.tracking.sampled_ns - origin_ns) * 1e-9,
                           static_cast<double>(sample.tracking.received_ns - origin_ns) * 1e-9);
    } else {
        row += ",,";
    }
    return row + "\n";
}

namespace {

// gnuplot's 1-based number of a header column, so that the plot follows the header when a
// column is added (a fixed number once plotted a servo angle as the pad force).
int columnNumber(std::string_view name) {
    const std::string header = telemetryCsvHeader();
    int number = 1;
    std::size_t start = 0;
    while (start <= header.size()) {
        std::size_t end = header.find_first_of(",\n", start);
        if (end == std::string::npos) {
            end = header.size();
        }
        if (std::string_view(header).substr(start, end - start) == name) {
            return number;
        }
        ++number;
        start = end + 1;
    }
    throw std::logic_error("telemetry CSV has no column " + std::string(name));
}

}  // namespace

std::string telemetryPlotScript(const std::string& csv_path, const std::string& png_path,
                                double exo_clamp_n, double thimble_max_force_n,
                                const FeltLogPlot* felt) {
    // Columns: 1 tick, 2 time, 3 device, 4 device kind, 5 exoskeleton force command [N],
    // 6-8 thimble servo commands [rad], 9 tick work (read + compute + write), 10 wake-up
    // latency, 11 read, 12 write. One panel per device kind, each in its own unit.
    const std::string csv = quoted(csv_path);
    std::string script = fmt::format(
        "set terminal pngcairo size 1200,1200 noenhanced\n"
        "set output {png}\n"
        "set datafile separator ','\n"
        "set multiplot layout 3,1 title {title}\n"
        "set grid\n"
        "set xlabel 'time [s]'\n",
        fmt::arg("png", quoted(png_path)),
        fmt::arg("title", quoted("hapticd telemetry: " + csv_path)));
    // The force the actuator reports (felt) and the sim's reference.
    script += fmt::format(
        "set ylabel 'exoskeleton actuator force [N]'\n"
        "set yrange [{low}:{high}]\n"
        "plot {csv} every ::1 using (strcol(4) eq 'exoskeleton' ? $2 : 1/0):{reference} with "
        "points pt 7 ps 0.3 title 'reference (sim, B^+ tau_ref)', "
        "{csv} every ::1 using (strcol(4) eq 'exoskeleton' ? $2 : 1/0):{command} with points "
        "pt 7 ps 0.3 title 'commanded', "
        "{csv} every ::1 using (strcol(4) eq 'exoskeleton' ? $2 : 1/0):{felt} with points pt 7 "
        "ps 0.3 title 'felt (the actuator reports)'\n"
        "set yrange [*:*]\n",
        fmt::arg("csv", csv), fmt::arg("low", -2.0 * exo_clamp_n),
        fmt::arg("high", 2.0 * exo_clamp_n),
        fmt::arg("reference", columnNumber("exo_reference_actuator_force_n")),
        fmt::arg("command", columnNumber("actuator_force_cmd_n")),
        fmt::arg("felt", columnNumber("exo_actuator_force_n")));
    // The sim's reference force on the pad and the pad model's for the commanded plate, on the
    // right axis.
    script += fmt::format(
        "set ylabel 'thimble servo angle command [rad]'\n"
        "set y2label 'thimble pad force [N]'\nset y2tics\nset y2range [0:{}]\nplot ",
        2.0 * thimble_max_force_n);
    for (int servo = 0; servo < 3; ++servo) {
        script += fmt::format(
            "{sep}{csv} every ::1 using (strcol(4) eq 'thimble' ? $2 : 1/0):{column} with points "
            "pt 7 ps 0.3 title 'servo {servo}'",
            fmt::arg("sep", servo == 0 ? "" : ", "), fmt::arg("csv", csv),
            fmt::arg("column", columnNumber(fmt::format("servo_angle_cmd_{}_rad", servo))),
            fmt::arg("servo", servo));
    }
    script += fmt::format(
        ", {csv} every ::1 using (strcol(4) eq 'thimble' ? $2 : 1/0):"
        "(sqrt(${x}**2 + ${y}**2 + ${z}**2)) axes x1y2 with points pt 7 ps 0.3 "
        "title '|reference pad force|', "
        "{csv} every ::1 using (strcol(4) eq 'thimble' ? $2 : 1/0):{model} axes x1y2 with points "
        "pt 7 ps 0.3 title 'pad model force (plate commanded)'",
        fmt::arg("csv", csv), fmt::arg("x", columnNumber("thimble_reference_force_x_n")),
        fmt::arg("y", columnNumber("thimble_reference_force_y_n")),
        fmt::arg("z", columnNumber("thimble_reference_force_z_n")),
        fmt::arg("model", columnNumber("thimble_pad_force_model_n")));
    if (felt != nullptr && felt->complete_rows > 0) {
        // The felt log: stamp_ns, device, finger_penetration_m, pose_known, indentation_m,
        // force x, y, z, ...; each thimble's rows with a known pose, over the recording's span.
        // Points, not lines: the other devices' rows in between are 1/0, which breaks a line
        // at every row.
        for (const std::string& device : felt->devices) {
            script += fmt::format(
                ", {log} every ::1::{last} using (strcol(2) eq {device} && $4 == 1 && "
                "$1 >= {origin} && "
                "($1 - {origin}) * 1e-9 <= {end} ? ($1 - {origin}) * 1e-9 : 1/0):"
                "(sqrt($6**2 + $7**2 + $8**2)) axes x1y2 with points pt 7 ps 0.3 "
                "title {title}",
                fmt::arg("log", quoted(felt->path)), fmt::arg("device", quoted(device)),
                fmt::arg("last", felt->complete_rows), fmt::arg("origin", felt->origin_ns),
                fmt::arg("end", felt->end_s),
                fmt::arg("title",
                         quoted("|felt pad force| " + device + " (virtual user, --felt-log)")));
        }
    }
    script += "\nunset y2label\nunset y2tics\nset y2range [*:*]\n";
    script += fmt::format(
        "set ylabel 'loop timing [us, log scale]'\n"
        "set logscale y\n"
        "plot {csv} every ::1 using ($3==0 ? $2 : 1/0):9 with points pt 7 ps 0.3 title 'tick "
        "work (read+compute+write)', "
        "{csv} every ::1 using ($3==0 ? $2 : 1/0):11 with points pt 7 ps 0.3 title 'read', "
        "{csv} every ::1 using ($3==0 ? $2 : 1/0):12 with points pt 7 ps 0.3 title 'write', "
        "{csv} every ::1 using ($3==0 ? $2 : 1/0):10 with points pt 7 ps 0.3 title 'wake-up "
        "latency'\n"
        "unset multiplot\n",
        fmt::arg("csv", csv));
    return script;
}

}  // namespace haptic::ctl
