#include "telemetry_csv.hpp"

#include <fmt/format.h>

#include <charconv>

#include "haptic/msgs/names.hpp"

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
    header += ",exo_ghost_force_x_n,exo_ghost_force_y_n,exo_ghost_force_z_n,exo_energy_observer_j";
    for (std::size_t i = 0; i < msgs::kThimbleServos; ++i) {
        header += fmt::format(",servo_angle_{}_rad", i);
    }
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
    for (const double force : exo.ghost_force_n) {
        row += fmt::format(",{:.4f}", force);
    }
    row += fmt::format(",{:.6f}", exo.energy_observer_j);
    for (const double angle : sample.thimble.servo_angle_rad) {
        row += fmt::format(",{:.4f}", angle);
    }
    return row + "\n";
}

std::map<int, std::vector<double>> exoskeletonForcesFromCsv(std::string_view csv) {
    std::map<int, std::vector<double>> out;
    const std::string_view kind = msgs::toString(msgs::DeviceKind::kExoskeleton);
    while (!csv.empty()) {
        const std::size_t end = csv.find('\n');
        std::string_view line = csv.substr(0, end);
        csv.remove_prefix(end == std::string_view::npos ? csv.size() : end + 1);
        // tick, time_s, device, device_kind, actuator_force_cmd_n, ...
        std::string_view fields[5];
        std::size_t count = 0;
        while (count < 5) {
            const std::size_t comma = line.find(',');
            fields[count++] = line.substr(0, comma);
            if (comma == std::string_view::npos) {
                break;
            }
            line.remove_prefix(comma + 1);
        }
        if (count < 5 || fields[3] != kind) {
            continue;
        }
        int device = 0;
        double force = 0.0;
        const auto [device_end, device_error] =
            std::from_chars(fields[2].data(), fields[2].data() + fields[2].size(), device);
        const auto [force_end, force_error] =
            std::from_chars(fields[4].data(), fields[4].data() + fields[4].size(), force);
        if (device_error == std::errc() && force_error == std::errc()) {
            out[device].push_back(force);
        }
    }
    return out;
}

std::string telemetryPlotScript(const std::string& csv_path, const std::string& png_path) {
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
    script += fmt::format(
        "set ylabel 'exoskeleton actuator force command [N]'\n"
        "plot {csv} every ::1 using (strcol(4) eq 'exoskeleton' ? $2 : 1/0):5 with points pt 7 "
        "ps 0.3 title 'actuator force'\n",
        fmt::arg("csv", csv));
    script += "set ylabel 'thimble servo angle command [rad]'\nplot ";
    for (int servo = 0; servo < 3; ++servo) {
        script += fmt::format(
            "{sep}{csv} every ::1 using (strcol(4) eq 'thimble' ? $2 : 1/0):{column} with points "
            "pt 7 ps 0.3 title 'servo {servo}'",
            fmt::arg("sep", servo == 0 ? "" : ", "), fmt::arg("csv", csv),
            fmt::arg("column", 6 + servo), fmt::arg("servo", servo));
    }
    script += "\n";
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
